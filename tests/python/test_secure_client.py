"""The Python client's TLS, mutual TLS and token options against a real localizer-server
(certificates from deploy/tls/make_test_certs.sh; the recording and config of test_client)."""
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import unittest
from pathlib import Path

import grpc

from test_client import AUDIO, BLOCK, CLIENT_DIR, SERVER, config, frames_completed, lc

@unittest.skipUnless(SERVER and os.access(SERVER, os.X_OK),
                     f"no localizer-server binary (LOCALIZER_SERVER={SERVER!r})")
@unittest.skipUnless(shutil.which("openssl"), "no openssl CLI (Debian: openssl) for test certificates")
class SecureServerTest(unittest.TestCase):
    """The client's --tls-* and token options against a server with mutual TLS and tokens."""

    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="localizer-pytest-tls-")
        self.pki = Path(self.tmp) / "pki"
        script = Path(__file__).resolve().parents[2] / "deploy" / "tls" / "make_test_certs.sh"
        subprocess.run(["bash", str(script), str(self.pki)], check=True, capture_output=True)
        ready = Path(self.tmp) / "ready.json"
        self.log = open(Path(self.tmp) / "server.log", "wb")
        self.server = subprocess.Popen(
            [SERVER, "--listen", "127.0.0.1:0", "--metrics-listen", "", "--ready-file", str(ready),
             "--workers", "2", "--tls-cert", str(self.pki / "server.crt"), "--tls-key", str(self.pki / "server.key"),
             "--tls-client-ca", str(self.pki / "ca.crt"), "--auth-token-file", str(self.pki / "tokens")],
            stdout=self.log, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + 30.0
        while not ready.exists():
            if self.server.poll() is not None or time.monotonic() > deadline:
                self.fail("TLS server did not start")
            time.sleep(0.05)
        self.target = f"127.0.0.1:{json.loads(ready.read_text())['grpc_port']}"

    def tearDown(self):
        self.server.send_signal(signal.SIGTERM)
        self.server.wait(timeout=20)
        self.log.close()
        shutil.rmtree(self.tmp, ignore_errors=True)

    def connect(self, token=None, cert=True):
        kwargs = dict(tls_ca=str(self.pki / "ca.crt"))
        if cert:
            kwargs.update(tls_cert=str(self.pki / "client.crt"), tls_key=str(self.pki / "client.key"))
        if token:
            kwargs["token_file"] = str(self.pki / token)
        return lc.connect(self.target, **kwargs)

    def test_client_token_streams_but_may_not_list(self):
        with self.connect("client.token") as channel:
            session = lc.TrackSession(channel, config("py-tls"), timeout=60)
            for k in range(4):
                session.send(AUDIO[k * BLOCK:(k + 1) * BLOCK])
            session.close()
            self.assertEqual(len(list(session.estimates())), frames_completed(4 * BLOCK))
            with self.assertRaises(grpc.RpcError) as denied:
                lc.list_sessions(channel, timeout=10)
            self.assertEqual(denied.exception.code(), grpc.StatusCode.PERMISSION_DENIED)

    def test_operator_token_lists_and_missing_token_is_unauthenticated(self):
        with self.connect("operator.token") as channel:
            self.assertEqual(lc.list_sessions(channel, timeout=10), [])
        with self.connect(None) as channel:
            with self.assertRaises(grpc.RpcError) as refused:
                lc.list_sessions(channel, timeout=10)
            self.assertEqual(refused.exception.code(), grpc.StatusCode.UNAUTHENTICATED)

    def test_no_client_certificate_is_refused_by_the_handshake(self):
        with self.connect("operator.token", cert=False) as channel:
            with self.assertRaises(grpc.RpcError) as refused:
                lc.list_sessions(channel, timeout=5)
            self.assertEqual(refused.exception.code(), grpc.StatusCode.UNAVAILABLE)

    def test_loadtest_takes_the_credential_flags(self):
        done = subprocess.run(
            [sys.executable, str(Path(CLIENT_DIR) / "loadtest.py"), "--target", self.target, "--sessions", "2",
             "--duration", "1", "--rate", "max", "--particles", "256", "--tls-ca", str(self.pki / "ca.crt"),
             "--tls-cert", str(self.pki / "client.crt"), "--tls-key", str(self.pki / "client.key"),
             "--auth-token-file", str(self.pki / "client.token")],
            capture_output=True, text=True, timeout=120)
        self.assertEqual(done.returncode, 0, done.stdout[-2000:] + done.stderr[-2000:])


if __name__ == "__main__":
    unittest.main(verbosity=2)

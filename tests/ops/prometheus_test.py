"""The shipped Prometheus files (deploy/prometheus) checked by promtool, their alert rules
unit-tested on synthetic series (alerts_test.yml), and a real Prometheus server started with
the shipped config, scraping two live localizer-server instances: its HTTP API must return
the stage-latency histograms of every instance; and one instance scraped over HTTPS with a
client certificate (--metrics-tls-*).
"""
import json
import shutil
import subprocess
import tempfile
import time
import unittest
import urllib.parse
import urllib.request
from pathlib import Path

import yaml

import ops_util

HERE = Path(__file__).resolve().parent
DEPLOY = HERE.parents[1] / "deploy" / "prometheus"
PROMTOOL = shutil.which("promtool")
PROMETHEUS = shutil.which("prometheus")


@unittest.skipUnless(PROMTOOL, "promtool not installed (Debian package prometheus)")
class PromtoolTest(unittest.TestCase):
    def promtool(self, *args, cwd):
        done = subprocess.run([PROMTOOL, *args], cwd=cwd, capture_output=True, text=True, timeout=60)
        self.assertEqual(done.returncode, 0, done.stdout + done.stderr)

    def test_config_and_rules_are_valid(self):
        self.promtool("check", "config", "prometheus.yml", cwd=DEPLOY)
        self.promtool("check", "rules", "alerts.yml", cwd=DEPLOY)

    def test_alerts_fire_on_the_series_they_are_meant_for(self):
        self.promtool("test", "rules", "alerts_test.yml", cwd=HERE)


@unittest.skipUnless(PROMETHEUS and ops_util.have_binaries(),
                     f"needs prometheus and the localizer binaries (prometheus={PROMETHEUS!r}, "
                     f"server={ops_util.SERVER!r}, cli={ops_util.CLI!r})")
class RealPrometheusTest(unittest.TestCase):
    def setUp(self):
        self.tmp = Path(tempfile.mkdtemp(prefix="localizer-prom-"))
        self.servers = [ops_util.Server(self.tmp, f"instance{i}") for i in range(2)]
        self.prometheus = None
        self.log = None

    def tearDown(self):
        if self.prometheus is not None:
            ops_util.stop_process(self.prometheus)
        if self.log is not None:
            self.log.close()
        for s in self.servers:
            s.stop()
        shutil.rmtree(self.tmp, ignore_errors=True)

    def shipped_config_for(self, targets):
        """The shipped config with its static job pointed at `targets`, the DNS job (for
        Kubernetes) left out, a 1 s scrape interval, and the rules by absolute path."""
        config = yaml.safe_load((DEPLOY / "prometheus.yml").read_text())
        config["global"]["scrape_interval"] = "1s"
        config["global"]["scrape_timeout"] = "1s"
        config["rule_files"] = [str(DEPLOY / f) for f in config["rule_files"]]
        jobs = [j for j in config["scrape_configs"] if "static_configs" in j]
        self.assertEqual(len(jobs), 1, "the shipped config has one static job")
        jobs[0]["static_configs"] = [{"targets": targets}]
        config["scrape_configs"] = jobs
        path = self.tmp / "prometheus.yml"
        path.write_text(yaml.safe_dump(config))
        return path

    def query(self, port, expr):
        url = f"http://127.0.0.1:{port}/api/v1/query?" + urllib.parse.urlencode({"query": expr})
        with urllib.request.urlopen(url, timeout=10) as r:
            body = json.load(r)
        self.assertEqual(body["status"], "success", body)
        return body["data"]["result"]

    def test_prometheus_finds_every_instances_stage_histograms(self):
        for s in self.servers:  # some frames through each, so the histograms have series
            ops_util.stream_simulation(s.grpc_target, seconds=3.0)
        targets = [s.metrics_target for s in self.servers]
        port = ops_util.free_port()
        self.log = open(self.tmp / "prometheus.log", "wb")
        self.prometheus = subprocess.Popen(
            [PROMETHEUS, f"--config.file={self.shipped_config_for(targets)}",
             f"--storage.tsdb.path={self.tmp / 'data'}", f"--web.listen-address=127.0.0.1:{port}"],
            stdout=self.log, stderr=subprocess.STDOUT)
        expr = 'count by (instance, stage) (localizer_stage_seconds_bucket{job="localizer"})'
        deadline = time.monotonic() + 60.0
        seen = set()
        while time.monotonic() < deadline:
            self.assertIsNone(self.prometheus.poll(), (self.tmp / "prometheus.log").read_text()[-3000:])
            try:
                result = self.query(port, expr)
                seen = {(r["metric"]["instance"], r["metric"]["stage"]) for r in result}
            except OSError:
                result = []  # not listening yet
            if {(t, st) for t in targets for st in ("tdoa", "filter", "total")} <= seen:
                break
            time.sleep(0.5)
        for t in targets:
            for stage in ("tdoa", "filter", "queue", "total"):
                self.assertIn((t, stage), seen, f"no {stage} histogram from {t}; saw {sorted(seen)}")
        up = {r["metric"]["instance"]: r["value"][1] for r in self.query(port, 'up{job="localizer"}')}
        self.assertEqual(up, {t: "1" for t in targets})
        # The histograms carry what was streamed: estimates counted on every instance.
        estimates = self.query(port, 'sum by (instance) (localizer_estimates_total)')
        self.assertEqual({r["metric"]["instance"] for r in estimates}, set(targets))
        for r in estimates:
            self.assertGreater(float(r["value"][1]), 10.0, r)

    @unittest.skipUnless(shutil.which("openssl"), "the openssl CLI is not installed (Debian: openssl): no test PKI")
    def test_prometheus_scrapes_an_instance_over_mutual_tls(self):
        """An instance serving its HTTP side over HTTPS with client certificates
        (--metrics-tls-*): Prometheus scrapes it with scheme https and a tls_config, as
        deploy/prometheus/prometheus.yml's header describes."""
        pki = self.tmp / "pki"
        subprocess.run(["bash", str(HERE.parents[1] / "deploy" / "tls" / "make_test_certs.sh"), str(pki)],
                       check=True, capture_output=True, timeout=60)
        https = ops_util.Server(self.tmp, "https", ["--metrics-tls-cert", str(pki / "server.crt"),
                                                    "--metrics-tls-key", str(pki / "server.key"),
                                                    "--metrics-tls-client-ca", str(pki / "ca.crt")])
        self.servers.append(https)
        path = self.shipped_config_for([https.metrics_target])
        config = yaml.safe_load(path.read_text())
        config["scrape_configs"][0]["scheme"] = "https"
        config["scrape_configs"][0]["tls_config"] = {
            "ca_file": str(pki / "ca.crt"), "cert_file": str(pki / "client.crt"), "key_file": str(pki / "client.key")}
        path.write_text(yaml.safe_dump(config))
        port = ops_util.free_port()
        self.log = open(self.tmp / "prometheus.log", "wb")
        self.prometheus = subprocess.Popen(
            [PROMETHEUS, f"--config.file={path}", f"--storage.tsdb.path={self.tmp / 'data'}",
             f"--web.listen-address=127.0.0.1:{port}"], stdout=self.log, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + 60.0
        result = []
        while time.monotonic() < deadline and not result:
            self.assertIsNone(self.prometheus.poll(), (self.tmp / "prometheus.log").read_text()[-3000:])
            try:
                result = self.query(port, 'localizer_build_info{job="localizer"}')
            except OSError:
                result = []  # not listening yet
            time.sleep(0.5)
        self.assertEqual([r["metric"]["instance"] for r in result], [https.metrics_target], result)
        up = self.query(port, 'up{job="localizer"}')
        self.assertEqual([r["value"][1] for r in up], ["1"])
        # Nothing refused: Prometheus presented its certificate on every scrape.
        refused = self.query(port, 'sum(localizer_http_tls_handshake_failures_total{job="localizer"})')
        self.assertEqual([r["value"][1] for r in refused], ["0"])


if __name__ == "__main__":
    unittest.main()

"""The package localizer, synchronous and asyncio, against a real localizer-server: numpy
(channels, samples) blocks in, ``localizer.Estimate`` dataclasses out, on test_client's
synthetic recording (a 1.5 m tetrahedron, a source at whole-sample TDOAs) and with its
bound: the final position within TOLERANCE_M (0.5 m, reasoned in test_client) of the source.
The server fixture is test_client's; the TLS server is test_secure_client's."""
import asyncio
import os
import shutil
import unittest

import grpc
import numpy as np

from test_client import (AUDIO, BLOCK, FRAME, FS_HZ, HOP, SERVER, SOURCE_M, TDOA_SAMPLES, TOLERANCE_M,
                         ServerFixture, config, frames_completed)
import test_secure_client  # its class is not imported by name: unittest would run its tests here too

import localizer
import localizer.aio

# The same recording, channel-major as the package takes it (and in float64, to send both dtypes).
SIGNAL = localizer.synth.broadband_at_sensors(TDOA_SAMPLES, AUDIO.shape[0], FS_HZ, band_hz=(200.0, 8000.0),
                                              snr_db=20.0, seed=7)
BLOCKS = [SIGNAL[:, k * BLOCK:(k + 1) * BLOCK] for k in range(SIGNAL.shape[1] // BLOCK)]
N_FRAMES = frames_completed(SIGNAL.shape[1])
BLOCK_S = BLOCK / FS_HZ


@unittest.skipUnless(SERVER and os.access(SERVER, os.X_OK),
                     f"no localizer-server binary (LOCALIZER_SERVER={SERVER!r})")
class PackageClientTest(ServerFixture):
    def check_estimates(self, estimates):
        """What a run over the whole recording must give, sync or aio."""
        self.assertTrue(all(isinstance(e, localizer.Estimate) for e in estimates))
        self.assertEqual([e.frame_index for e in estimates], list(range(N_FRAMES)))
        self.assertEqual([e.sequence for e in estimates],
                         [-(-(FRAME + k * HOP) // BLOCK) for k in range(N_FRAMES)])
        for e in estimates:
            self.assertIsInstance(e.raw, localizer.pb.Estimate)
            self.assertEqual(e.raw.frame_index, e.frame_index)
            self.assertEqual(e.position_m is None, not e.initialised)
        last = estimates[-1]
        self.assertTrue(last.initialised)
        self.assertEqual(last.position_m.shape, (3,))
        self.assertEqual(last.covariance.shape, (6, 6))
        np.testing.assert_allclose(last.covariance, last.covariance.T)
        self.assertTrue(np.all(np.diag(last.covariance) > 0.0))
        self.assertEqual(len(last.pairs), 3)
        self.assertAlmostEqual(last.t_s, (FRAME / 2 + (N_FRAMES - 1) * HOP) / FS_HZ, delta=FRAME / FS_HZ)
        error_m = np.linalg.norm(last.position_m - SOURCE_M)
        self.assertLess(error_m, TOLERANCE_M,
                        f"final estimate {last.position_m} vs source {SOURCE_M}: {error_m:.3f} m")

    def test_sync_numpy_blocks_in_dataclasses_out(self):
        np.testing.assert_array_equal(SIGNAL, AUDIO.T)  # test_client's recording, transposed
        session = localizer.TrackSession.open(self.channel, config("py-package"), timeout=60)
        self.assertEqual(session.channel_count, 4)
        # A block in the wrong layout is refused before it is sent; the session goes on.
        with self.assertRaisesRegex(ValueError, r"pass samples\.T"):
            session.send(BLOCKS[0].T)
        self.assertEqual(session.next_sequence, 1)
        self.stream(session, [(k + 1, block) for k, block in enumerate(BLOCKS)])
        estimates = list(session.estimates())
        self.assertEqual(session.code(), grpc.StatusCode.OK)
        self.assertEqual((session.rejected, session.gaps), ([], []))
        self.check_estimates(estimates)
        self.assertEqual(localizer.presence_summary(estimates)["initialised"],
                         sum(e.initialised for e in estimates))

    def test_sync_locate_gives_a_fix(self):
        fix = localizer.locate(self.channel, config("py-package-locate"), SIGNAL[:, :2 * BLOCK], timeout=30)
        self.assertIsInstance(fix, localizer.Fix)
        self.assertEqual([p.sensor for p in fix.pairs], [1, 2, 3])
        for pair in fix.pairs:  # whole-sample delays: measured within half a sample
            self.assertAlmostEqual(pair.delay_s * FS_HZ, TDOA_SAMPLES[pair.sensor], delta=0.5)
        self.assertTrue(fix.fix_found)
        self.assertLess(np.linalg.norm(fix.position_m - SOURCE_M), TOLERANCE_M)

    def test_aio_same_surface(self):
        async def run():
            async with localizer.aio.connect(self.target) as channel:
                with self.assertRaises(grpc.RpcError) as refused:  # errors as in the sync client
                    bad = config("py-aio-bad")
                    bad.presence_false_alarm = 0.5
                    await localizer.aio.TrackSession.open(channel, bad, timeout=30)
                self.assertEqual(refused.exception.code(), grpc.StatusCode.INVALID_ARGUMENT)

                session = await localizer.aio.TrackSession.open(channel, config("py-aio"), timeout=60)
                self.assertEqual(session.channel_count, 4)
                listed = [s.session_id for s in await localizer.aio.list_sessions(channel, timeout=10)]
                self.assertIn(session.session_id, listed)

                async def send():  # in real time, float64 blocks
                    loop = asyncio.get_running_loop()
                    t0 = loop.time()
                    for k, block in enumerate(BLOCKS):
                        await asyncio.sleep(max(0.0, k * BLOCK_S - (loop.time() - t0)))
                        self.assertEqual(await session.send(block.astype(np.float64)), k + 1)
                    await session.close()

                sender = asyncio.create_task(send())
                estimates = [e async for e in session.estimates()]
                await sender
                self.assertEqual(await session.code(), grpc.StatusCode.OK)
                self.assertEqual((session.rejected, session.gaps), ([], []))
                fix = await localizer.aio.locate(channel, config("py-aio-locate"), SIGNAL[:, :2 * BLOCK],
                                                 timeout=30)
                return estimates, fix

        estimates, fix = asyncio.run(run())
        self.check_estimates(estimates)
        self.assertTrue(fix.fix_found)
        self.assertLess(np.linalg.norm(fix.position_m - SOURCE_M), TOLERANCE_M)


@unittest.skipUnless(SERVER and os.access(SERVER, os.X_OK),
                     f"no localizer-server binary (LOCALIZER_SERVER={SERVER!r})")
@unittest.skipUnless(shutil.which("openssl"), "no openssl CLI (Debian: openssl) for test certificates")
class AioSecureTest(unittest.TestCase):
    """localizer.aio.connect's TLS and token options (test_secure_client's server)."""
    setUp = test_secure_client.SecureServerTest.setUp
    tearDown = test_secure_client.SecureServerTest.tearDown

    def test_token_reaches_streams_and_unary_calls(self):
        pki = self.pki

        async def run():
            tls = dict(tls_ca=str(pki / "ca.crt"), tls_cert=str(pki / "client.crt"),
                       tls_key=str(pki / "client.key"))
            async with localizer.aio.connect(self.target, token_file=str(pki / "client.token"), **tls) as channel:
                session = await localizer.aio.TrackSession.open(channel, config("py-aio-tls"), timeout=60)
                for block in BLOCKS[:4]:
                    await session.send(block)
                await session.close()
                n = len([e async for e in session.estimates()])
            async with localizer.aio.connect(self.target, **tls) as channel:
                with self.assertRaises(grpc.RpcError) as refused:
                    await localizer.aio.list_sessions(channel, timeout=10)
            return n, refused.exception.code()

        n, code = asyncio.run(run())
        self.assertEqual(n, frames_completed(4 * BLOCK))
        self.assertEqual(code, grpc.StatusCode.UNAUTHENTICATED)


if __name__ == "__main__":
    unittest.main(verbosity=2)

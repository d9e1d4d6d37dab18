"""The Python client against a real farm: lightfarm-server (TLS, tokens) and two
lightfarm-worker processes on a free port of 127.0.0.1, in a temporary folder.

Environment (set by ctest, clients/python/CMakeLists.txt): PYTHONPATH=build/python,
LF_BIN_DIR (the build's bin folder) and LF_TEST_SCENES (tests/scenes). Needs openssl.
"""

import builtins
import datetime
import hashlib
import json
import os
import secrets
import shutil
import socket
import struct
import subprocess
import sys
import tempfile
import time
import unittest
import zlib

import grpc

import lightfarm
from lightfarm.v1 import job_service_pb2 as pb
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', '..',
                                'tests', 'support'))
from processes import stop_all  # noqa: E402  (tests/support)

BIN = os.environ.get("LF_BIN_DIR", "")
SCENES = os.environ.get("LF_TEST_SCENES", "")
DOCS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "docs",
                    "python.md")
EXR_MAGIC = bytes([0x76, 0x2F, 0x31, 0x01])
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
SMALL = dict(spp=4, resolution=(32, 32), tile=8, passes=2)  # 32 tasks, well under a second
WATCHED = dict(spp=512, resolution=(64, 64), tile=16, passes=2)  # 32 tasks, a few seconds


def cornell():
    return os.path.join(SCENES, "cornell_box.json")


def png_pixels(data):
    """Width, height and the RGB bytes of an 8-bit RGB PNG, whatever its row filters."""
    assert data[:8] == PNG_MAGIC, data[:8]
    at, idat = 8, b""
    while at < len(data):
        n, kind = struct.unpack_from(">I4s", data, at)
        body = data[at + 8:at + 8 + n]
        at += 12 + n
        if kind == b"IHDR":
            width, height, depth, color = struct.unpack_from(">IIBB", body)
            assert (depth, color) == (8, 2), (depth, color)
        elif kind == b"IDAT":
            idat += body
    raw = zlib.decompress(idat)
    stride = width * 3
    prev, out, p = bytearray(stride), bytearray(), 0
    for _ in range(height):
        kind, line = raw[p], bytearray(raw[p + 1:p + 1 + stride])
        p += 1 + stride
        for i in range(stride):
            a = line[i - 3] if i >= 3 else 0
            b = prev[i]
            c = prev[i - 3] if i >= 3 else 0
            if kind == 1:
                line[i] = (line[i] + a) & 0xFF
            elif kind == 2:
                line[i] = (line[i] + b) & 0xFF
            elif kind == 3:
                line[i] = (line[i] + (a + b) // 2) & 0xFF
            elif kind == 4:
                pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 0xFF
        out += line
        prev = line
    return width, height, bytes(out)


class Farm:
    """The server, its tokens and certificates, and two workers."""

    def __init__(self):
        self.dir = tempfile.mkdtemp(prefix="lightfarm-python-")
        self.data = self.path("server-data")
        self.procs = []
        self.certificates()
        self.tokens = {}
        for name, role in (("alice", "submitter"), ("bob", "submitter"), ("root", "admin"),
                           ("node", "worker")):
            r = subprocess.run([self.bin("lightfarm-server"), "token", "create", "--data-dir",
                                self.data, "--name", name, "--role", role],
                               capture_output=True, text=True, check=True)
            self.tokens[name] = r.stdout.strip().splitlines()[-1]
            with open(self.path(name + ".token"), "w") as f:
                f.write(self.tokens[name] + "\n")
        server = self.spawn("server", [
            self.bin("lightfarm-server"), "--listen", "127.0.0.1:0", "--data-dir", self.data,
            "--tls-cert", self.path("server.crt"), "--tls-key", self.path("server.key"),
            "--lease-seconds", "5", "--log-level", "warn"], stdout=subprocess.PIPE)
        line = server.stdout.readline().strip()
        if not line.startswith("listening on "):
            raise RuntimeError(f"server did not start: {line!r} {self.log('server')}")
        self.address = line[len("listening on "):]
        # w2 alone has the tag "gpu" (test_tags).
        for name, tags in (("w1", ""), ("w2", "gpu")):
            self.spawn(name, [
                self.bin("lightfarm-worker"), "--server", self.address, "--tls-ca",
                self.path("ca.crt"), "--token-file", self.path("node.token"), "--name", name,
                "--threads", "1", "--cache-dir", self.path("cache-" + name), "--log-level",
                "warn", "--tags", tags])

    def path(self, *names):
        return os.path.join(self.dir, *names)

    @staticmethod
    def bin(name):
        return os.path.join(BIN, name)

    def spawn(self, name, argv, stdout=subprocess.DEVNULL):
        with open(self.path(name + ".log"), "w") as log:
            p = subprocess.Popen(argv, stdout=stdout, stderr=log, text=True)
        self.procs.append(p)
        return p

    def log(self, name):
        try:
            with open(self.path(name + ".log")) as f:
                return f.read()[-3000:]
        except OSError:
            return ""

    def certificates(self):
        def ssl(*args):
            subprocess.run(["openssl"] + list(args), cwd=self.dir, check=True,
                           capture_output=True)

        for ca in ("ca", "other-ca"):
            ssl("ecparam", "-name", "prime256v1", "-genkey", "-noout", "-out", ca + ".key")
            ssl("req", "-x509", "-new", "-key", ca + ".key", "-days", "2", "-subj",
                f"/CN=lightfarm python test {ca}", "-out", ca + ".crt")
        ssl("ecparam", "-name", "prime256v1", "-genkey", "-noout", "-out", "server.key")
        ssl("req", "-new", "-key", "server.key", "-subj", "/CN=127.0.0.1", "-out", "server.csr")
        with open(self.path("server.ext"), "w") as f:
            f.write("subjectAltName=IP:127.0.0.1\nextendedKeyUsage=serverAuth\n")
        ssl("x509", "-req", "-in", "server.csr", "-CA", "ca.crt", "-CAkey", "ca.key",
            "-CAcreateserial", "-days", "2", "-extfile", "server.ext", "-out", "server.crt")

    def client(self, token="alice", ca="ca.crt", **kwargs):
        return lightfarm.Client(self.address, token_file=self.path(token + ".token"),
                                tls_ca=self.path(ca), **kwargs)

    def cli(self, *args, token="alice"):
        """`lightfarm ARGS` against the farm, with TLS and a token."""
        return subprocess.run(
            [self.bin("lightfarm")] + list(args) + [
                "--server", self.address, "--tls-ca", self.path("ca.crt"), "--token-file",
                self.path(token + ".token")], capture_output=True, text=True, timeout=120)

    def stop(self):
        stop_all(self.procs)
        for p in self.procs:
            if p.stdout:
                p.stdout.close()
        shutil.rmtree(self.dir, ignore_errors=True)


class NoiseThresholdMinSppTest(unittest.TestCase):
    def test_is_cycles_automatic_minimum_as_the_cli(self):
        from lightfarm.client import _noise_threshold_min_spp
        # lf::NoiseThresholdMinSpp's values (noise_threshold_test): Cycles' ceil(16 / T^0.3).
        self.assertEqual(_noise_threshold_min_spp(0.1), 32)
        self.assertEqual(_noise_threshold_min_spp(0.01), 64)
        self.assertEqual(_noise_threshold_min_spp(0.001), 128)
        self.assertEqual(_noise_threshold_min_spp(1.0), 16)


class ClientTest(unittest.TestCase):
    farm = None

    @classmethod
    def setUpClass(cls):
        if not BIN or not SCENES:
            raise unittest.SkipTest("LF_BIN_DIR and LF_TEST_SCENES are not set (run by ctest)")
        if shutil.which("openssl") is None:
            raise unittest.SkipTest("no openssl")
        cls.farm = Farm()
        cls.alice = cls.farm.client("alice")
        # The workers are up once the server lists them.
        deadline = time.monotonic() + 20
        while len(cls.alice.workers()) < 2:
            if time.monotonic() > deadline:
                raise RuntimeError("workers did not register: " + cls.farm.log("w1"))
            time.sleep(0.1)

    @classmethod
    def tearDownClass(cls):
        if cls.farm:
            cls.alice.close()
            cls.farm.stop()

    def test_submit_watch_fetch_list(self):
        # Big enough (a few seconds) for the watch to see progress between start and end.
        job_id = self.alice.submit(cornell(), name="python cornell", **WATCHED)
        snapshots = builtins.list(self.alice.watch(job_id))
        seconds = (snapshots[-1].job.finished_unix_ms - snapshots[-1].job.started_unix_ms) / 1000
        print(f"\n  watched job: {len(snapshots)} snapshots in {seconds:.1f} s", file=sys.stderr)
        done = [p.tasks_done for p in snapshots]
        self.assertEqual(done, sorted(done), "progress never goes back")
        self.assertGreaterEqual(len(set(done)), 3, f"rising progress: {snapshots}")
        fractions = [p.fraction for p in snapshots]
        self.assertEqual(fractions, sorted(fractions))
        self.assertEqual(snapshots[-1].state, lightfarm.JobState.SUCCEEDED, snapshots[-1])
        self.assertTrue(all(not p.final for p in snapshots[:-1]))
        self.assertEqual(snapshots[-1].fraction, 1.0)
        self.assertEqual(snapshots[-1].tasks_total, 32)
        self.assertGreater(snapshots[-1].samples, 0)

        job = self.alice.get(job_id)
        self.assertEqual((job.width, job.height), (64, 64))
        self.assertEqual(job.params.spp, 512)
        self.assertEqual(job.name, "python cornell")
        self.assertEqual(job.owner, "alice")
        self.assertEqual(self.alice.wait(job_id).state, lightfarm.JobState.SUCCEEDED)

        out = self.farm.path("python.exr")
        self.assertEqual(self.alice.fetch(job_id, out), out)
        with open(out, "rb") as f:
            exr = f.read()
        self.assertEqual(exr[:4], EXR_MAGIC)
        # Three float channels of 64x64 pixels at least, plus a header, compressed or not.
        self.assertGreater(len(exr), 1000)
        self.assertLess(len(exr), 10 << 20)
        self.assertFalse(os.path.exists(out + ".part"))
        cli_out = self.farm.path("cli.exr")
        r = self.farm.cli("fetch", job_id, "-o", cli_out)
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(cli_out, "rb") as f:
            self.assertEqual(f.read(), exr, "the CLI's fetch writes the same bytes")

        self.assertIn(job_id, [j.id for j in self.alice.list()])
        self.assertIn(job_id, [j.id for j in self.alice.list(page_size=1)], "paging")
        with self.farm.client("root") as admin:
            self.assertIn(job_id, [j.id for j in admin.list()])

    def test_obj_mtl_and_texture_are_uploaded(self):
        folder = self.farm.path("obj-scene")
        os.makedirs(os.path.join(folder, "meshes"))
        os.makedirs(os.path.join(folder, "textures"))
        shutil.copy(os.path.join(SCENES, "gltf_demo", "checker.png"),
                    os.path.join(folder, "textures", "checker.png"))
        with open(os.path.join(folder, "meshes", "panel.obj"), "w") as f:
            f.write("mtllib panel.mtl\nv 0.1 0.1 0.3\nv 0.4 0.1 0.3\nv 0.4 0.4 0.3\n"
                    "v 0.1 0.4 0.3\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl checker\n"
                    "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n")
        with open(os.path.join(folder, "meshes", "panel.mtl"), "w") as f:
            f.write("newmtl checker\nKd 1 1 1\nmap_Kd ../textures/checker.png\n")
        with open(cornell()) as f:
            scene = json.load(f)
        scene["shapes"].append({"type": "mesh", "name": "panel", "file": "meshes/panel.obj"})
        scene_path = os.path.join(folder, "panel.json")
        with open(scene_path, "w") as f:
            json.dump(scene, f)
        _, files = lightfarm.scene_files(scene_path)
        self.assertEqual([n for n, _ in files],
                         ["meshes/panel.mtl", "meshes/panel.obj", "textures/checker.png"])
        job_id = self.alice.submit(scene_path, spp=2, resolution=(16, 16), tile=16)
        job = self.alice.wait(job_id)
        self.assertEqual(job.state, lightfarm.JobState.SUCCEEDED, job.error)

    def test_upload_resumes(self):
        """A broken upload of a 2.5 MiB mesh keeps its first MiB on the server; submit sends the
        rest only."""
        folder = self.farm.path("resume")
        os.makedirs(folder)
        rows = ["v %.6f 0.05 %.6f" % (0.1 + i * 1e-6, 0.1 + i * 1e-6) for i in range(90000)]
        mesh = ("\n".join(rows) + "\nv 0.3 0.05 0.1\nv 0.1 0.05 0.3\nf -3 -2 -1\n").encode()
        self.assertGreater(len(mesh), 2 << 20)
        with open(os.path.join(folder, "big.obj"), "wb") as f:
            f.write(mesh)
        with open(cornell()) as f:
            scene = json.load(f)
        scene["shapes"].append({"type": "mesh", "material": "white", "file": "big.obj"})
        with open(os.path.join(folder, "big.json"), "w") as f:
            json.dump(scene, f)
        digest = hashlib.sha256(mesh).hexdigest()
        stub = self.alice._stub
        md = self.alice._metadata

        def held():
            return stub.BlobUploadOffset(pb.BlobUploadOffsetRequest(hash=digest, size=len(mesh)),
                                         timeout=10, metadata=md).offset

        def wait_until_held(what):
            deadline = time.monotonic() + 30
            while held() != 1 << 20:
                self.assertLess(time.monotonic(), deadline, what)
                time.sleep(0.05)

        def broken():
            yield pb.UploadBlobRequest(hash=digest, size=len(mesh), data=mesh[:1 << 20])
            # The stream breaks once the server has written the chunk, however slowly it runs.
            wait_until_held("the server never wrote the first MiB")
            raise RuntimeError("the link breaks")

        with self.assertRaises(grpc.RpcError):
            stub.UploadBlob(broken(), timeout=60, metadata=md)
        wait_until_held("the server did not keep the first MiB")

        offsets = []
        real = stub.UploadBlob

        def recording(requests, **kwargs):
            def tap():
                for i, r in enumerate(requests):
                    if i == 0:
                        offsets.append((r.hash, r.offset))
                    yield r
            return real(tap(), **kwargs)

        stub.UploadBlob = recording
        try:
            job_id = self.alice.submit(os.path.join(folder, "big.json"), spp=1,
                                       resolution=(16, 16), tile=16)
        finally:
            stub.UploadBlob = real
        self.assertIn((digest, 1 << 20), offsets)
        job = self.alice.wait(job_id)
        self.assertEqual(job.state, lightfarm.JobState.SUCCEEDED, job.error)
        # Stored now: a second submission uploads nothing.
        offsets.clear()
        stub.UploadBlob = recording
        try:
            self.alice.wait(self.alice.submit(os.path.join(folder, "big.json"), spp=1,
                                              resolution=(16, 16), tile=16))
        finally:
            stub.UploadBlob = real
        self.assertEqual(offsets, [])

    def test_gltf_scene(self):
        job_id = self.alice.submit(os.path.join(SCENES, "gltf_demo", "demo.gltf"), spp=2,
                                   resolution=(16, 16), tile=16)
        job = self.alice.wait(job_id)
        self.assertEqual(job.state, lightfarm.JobState.SUCCEEDED, job.error)

    def test_cancel(self):
        job_id = self.alice.submit(cornell(), spp=4096, resolution=(128, 128), tile=32,
                                   name="long")
        for progress in self.alice.watch(job_id):
            if progress.state == lightfarm.JobState.RUNNING:
                break
        job = self.alice.cancel(job_id)
        self.assertEqual(job.state, lightfarm.JobState.CANCELLED)
        self.assertEqual(self.alice.wait(job_id).state, lightfarm.JobState.CANCELLED)
        r = self.farm.cli("status", job_id, "--json")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(json.loads(r.stdout)["state"], "CANCELLED")
        with self.assertRaises(lightfarm.FailedPrecondition):
            self.alice.cancel(job_id)
        with self.assertRaises(lightfarm.FailedPrecondition):
            self.alice.fetch(job_id, self.farm.path("cancelled.exr"))
        self.assertFalse(os.path.exists(self.farm.path("cancelled.exr.part")))
        self.alice.delete(job_id)
        with self.assertRaises(lightfarm.NotFound):
            self.alice.get(job_id)

    def test_wrong_token(self):
        with open(self.farm.path("wrong.token"), "w") as f:
            f.write(secrets.token_hex(32) + "\n")
        with self.farm.client("wrong") as c:
            with self.assertRaises(lightfarm.Unauthenticated) as caught:
                builtins.list(c.list())
        self.assertEqual(caught.exception.code.name, "UNAUTHENTICATED")
        with lightfarm.Client(self.farm.address, token="",
                              tls_ca=self.farm.path("ca.crt")) as c:
            with self.assertRaises(lightfarm.Unauthenticated):
                c.workers()

    def test_worker_token_cannot_submit(self):
        with self.farm.client("node") as c:
            with self.assertRaises(lightfarm.PermissionDenied):
                c.submit(cornell(), **SMALL)

    def test_submitter_sees_only_its_own_jobs(self):
        job_id = self.alice.submit(cornell(), priority=-5, **SMALL)
        with self.farm.client("bob") as bob:
            with self.assertRaises(lightfarm.NotFound):
                bob.get(job_id)
            with self.assertRaises(lightfarm.NotFound):
                bob.cancel(job_id)
            self.assertNotIn(job_id, [j.id for j in bob.list()])
        self.alice.wait(job_id)

    def test_tls(self):
        # Every other test talks TLS with the right CA; another CA's certificate is refused.
        with self.farm.client("alice", ca="other-ca.crt", retry_seconds=0) as c:
            with self.assertRaises(lightfarm.TlsError) as caught:
                c.workers()
        self.assertIn("TLS handshake", caught.exception.message)
        with self.assertRaises(lightfarm.InvalidArgument):
            self.farm.client("alice", ca="alice.token")  # not a PEM file
        with self.assertRaises(lightfarm.InvalidArgument):
            lightfarm.Client(self.farm.address, tls_cert=self.farm.path("server.crt"),
                             tls_key=self.farm.path("server.key"))  # no CA

    def test_fetch_png_is_the_clis_preview(self):
        """fetch(job, "x.png") writes the PNG `lightfarm fetch -o x.png` writes, pixel for pixel,
        with the same exposure and tone curve."""
        job_id = self.alice.submit(cornell(), **SMALL)
        self.assertEqual(self.alice.wait(job_id).state, lightfarm.JobState.SUCCEEDED)
        for flags, kwargs in (([], {}), (["--exposure", "1.5", "--tonemap", "filmic"],
                                         dict(exposure=1.5, tonemap="filmic"))):
            mine, theirs = self.farm.path("python.png"), self.farm.path("cli.png")
            self.assertEqual(self.alice.fetch(job_id, mine, **kwargs), mine)
            r = self.farm.cli("fetch", job_id, "-o", theirs, *flags)
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(mine, "rb") as f:
                ours = png_pixels(f.read())
            with open(theirs, "rb") as f:
                cli = png_pixels(f.read())
            self.assertEqual(ours[:2], (32, 32))
            self.assertEqual(ours, cli, flags)
            self.assertGreater(max(ours[2]), 0, "not black")
            self.assertFalse(os.path.exists(mine + ".part"))
        with self.assertRaises(lightfarm.InvalidArgument):
            self.alice.fetch(job_id, self.farm.path("x.exr"), exposure=1.0)
        with self.assertRaises(lightfarm.InvalidArgument):
            self.alice.fetch(job_id, self.farm.path("x.png"), tonemap="aces")

    def test_tls_on_one_side_only(self):
        """A plain-text client or worker of the TLS server is told that the server speaks TLS
        and to give --tls-ca (tls_ca); one with a CA whose server speaks plain text is told
        that it does not."""
        def wait_for_log(name, text):
            deadline = time.monotonic() + 30
            while text not in self.farm.log(name):
                self.assertLess(time.monotonic(), deadline, self.farm.log(name))
                time.sleep(0.1)

        with lightfarm.Client(self.farm.address, token_file=self.farm.path("alice.token"),
                              tls_ca="", retry_seconds=0) as c:
            with self.assertRaises(lightfarm.Unavailable) as caught:
                c.workers()
        self.assertIn("speaks TLS", caught.exception.message)
        self.assertIn("tls_ca", caught.exception.message)
        r = subprocess.run([self.farm.bin("lightfarm"), "list", "--server", self.farm.address,
                            "--token-file", self.farm.path("alice.token")],
                           capture_output=True, text=True, timeout=60)
        self.assertNotEqual(r.returncode, 0)
        self.assertEqual(r.stdout, "", "no table header from a failed list")
        self.assertIn("speaks TLS", r.stderr)
        self.assertIn("--tls-ca", r.stderr)
        worker = self.farm.spawn("plain-worker", [
            self.farm.bin("lightfarm-worker"), "--server", self.farm.address, "--token-file",
            self.farm.path("node.token"), "--cache-dir", self.farm.path("cache-plain")])
        wait_for_log("plain-worker", "speaks TLS, most likely")
        worker.terminate()
        worker.wait(timeout=10)
        self.assertIn("--tls-ca", self.farm.log("plain-worker"))

        plain = self.farm.spawn("plain-server", [
            self.farm.bin("lightfarm-server"), "--listen", "127.0.0.1:0", "--data-dir",
            self.farm.path("plain-data"), "--log-level", "warn"], stdout=subprocess.PIPE)
        address = plain.stdout.readline().strip()[len("listening on "):]
        with lightfarm.Client(address, token="x", tls_ca=self.farm.path("ca.crt"),
                              retry_seconds=0) as c:
            with self.assertRaises(lightfarm.TlsError) as caught:
                c.workers()
        self.assertIn("does not speak TLS", caught.exception.message)
        r = subprocess.run([self.farm.bin("lightfarm"), "list", "--server", address, "--tls-ca",
                            self.farm.path("ca.crt")], capture_output=True, text=True, timeout=60)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("does not speak TLS", r.stderr)
        worker = self.farm.spawn("tls-worker", [
            self.farm.bin("lightfarm-worker"), "--server", address, "--tls-ca",
            self.farm.path("ca.crt"), "--cache-dir", self.farm.path("cache-tls")])
        wait_for_log("tls-worker", "does not speak TLS")
        worker.terminate()
        worker.wait(timeout=10)
        plain.terminate()
        plain.wait(timeout=10)

    def test_malformed_scene(self):
        bad = self.farm.path("bad.json")
        with open(bad, "w") as f:
            f.write('{"camera": {"position": [0, 0, 0], "look_at": [0, 0, 1]}, "shapes": [')
        with self.assertRaises(lightfarm.InvalidArgument) as caught:
            self.alice.submit(bad, **SMALL)
        self.assertIn("bad.json", caught.exception.message)
        self.assertEqual(caught.exception.code.name, "INVALID_ARGUMENT")

        odd = self.farm.path("odd.json")
        with open(cornell()) as f:
            scene = json.load(f)
        scene["shapes"][0]["type"] = "hexagon"
        with open(odd, "w") as f:
            json.dump(scene, f)
        with self.assertRaises(lightfarm.InvalidArgument) as caught:
            self.alice.submit(odd, **SMALL)
        self.assertIn("shapes[0]", caught.exception.message)

        missing = self.farm.path("missing.json")
        scene["shapes"][0] = {"type": "mesh", "file": "nowhere.obj"}
        with open(missing, "w") as f:
            json.dump(scene, f)
        with self.assertRaises(lightfarm.InvalidArgument) as caught:
            self.alice.submit(missing)
        self.assertIn("nowhere.obj", caught.exception.message)

        with self.assertRaises(lightfarm.InvalidArgument):
            self.alice.submit(cornell(), method="raytrace")
        # A setting out of range, refused by the server.
        with self.assertRaises(lightfarm.InvalidArgument):
            self.alice.submit(cornell(), spp=4, tile=0)

    def test_not_found(self):
        with self.assertRaises(lightfarm.NotFound):
            self.alice.get("no-such-job")
        with self.assertRaises(lightfarm.NotFound):
            builtins.list(self.alice.watch("no-such-job"))

    def test_unreachable(self):
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]  # free, and nothing listens once closed
        with lightfarm.Client(f"127.0.0.1:{port}", token="x", retry_seconds=0) as c:
            with self.assertRaises(lightfarm.Unavailable) as caught:
                c.get("job")
        self.assertIn(f"127.0.0.1:{port}", caught.exception.message)

    def test_docs_example(self):
        """docs/python.md's example, as written, from a folder that has tests/scenes."""
        with open(DOCS) as f:
            text = f.read()
        example = text.split("## Example", 1)[1].split("```python\n", 1)[1].split("```", 1)[0]
        cwd = self.farm.path("docs-example")
        os.makedirs(os.path.join(cwd, "tests"))
        os.symlink(SCENES, os.path.join(cwd, "tests", "scenes"))
        env = dict(os.environ, LIGHTFARM_SERVER=self.farm.address,
                   LIGHTFARM_TOKEN=self.farm.tokens["alice"],
                   LIGHTFARM_TLS_CA=self.farm.path("ca.crt"))
        r = subprocess.run([sys.executable, "-c", example], cwd=cwd, env=env,
                           capture_output=True, text=True, timeout=120)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("SUCCEEDED", r.stdout)
        self.assertIn("cornell.exr written", r.stdout)
        with open(os.path.join(cwd, "cornell.exr"), "rb") as f:
            self.assertEqual(f.read(4), EXR_MAGIC)

    def test_workers(self):
        names = sorted(w.name for w in self.alice.workers())
        self.assertEqual(names, ["w1", "w2"])

    def test_tags(self):
        """A job tagged gpu goes to w2 alone; one tagged with what no worker has says so."""
        self.assertEqual({w.name: w.tags for w in self.alice.workers()},
                         {"w1": (), "w2": ("gpu",)})
        with self.assertRaises(lightfarm.InvalidArgument) as caught:
            self.alice.submit(cornell(), tags="gpu", **SMALL)  # not the tags g, p and u
        self.assertIn("a list of tags", caught.exception.message)
        job_id = self.alice.submit(cornell(), tags=["gpu"], max_workers=1, **SMALL)
        job = self.alice.wait(job_id)
        self.assertEqual(job.state, lightfarm.JobState.SUCCEEDED, job.error)
        self.assertEqual((job.tags, job.max_workers), (("gpu",), 1))
        self.assertEqual({t.worker for t in self.alice.tasks(job_id)},
                         {w.id for w in self.alice.workers() if w.name == "w2"})
        stuck = self.alice.submit(cornell(), tags=["tpu"], **SMALL)
        try:
            self.assertEqual(self.alice.get(stuck).waiting_reason,
                             "waiting for a worker with tags tpu")
        finally:
            self.alice.cancel(stuck)
        with self.assertRaises(lightfarm.InvalidArgument):
            self.alice.submit(cornell(), tags=["No Spaces"], **SMALL)

    def test_after(self):
        """A job submitted after another runs once that one succeeded; a bare str, an unknown id
        and a cycle are refused."""
        with self.assertRaises(lightfarm.InvalidArgument):
            self.alice.submit(cornell(), after="job-1", **SMALL)
        with self.assertRaises(lightfarm.NotFound) as caught:
            self.alice.submit(cornell(), after=["job-nonesuch"], **SMALL)
        self.assertIn("job-nonesuch", caught.exception.message)
        first = self.alice.submit(cornell(), **SMALL)
        second = self.alice.submit(cornell(), after=[first, first], **SMALL)
        self.assertEqual(self.alice.get(second).after, (first,))
        done = self.alice.wait(second)
        self.assertEqual(done.state, lightfarm.JobState.SUCCEEDED, done.error)
        self.assertLessEqual(self.alice.get(first).finished_unix_ms, done.started_unix_ms)
        third = self.alice.submit(cornell(), tags=["tpu"], **SMALL)  # stays queued
        fourth = self.alice.submit(cornell(), after=[third], **SMALL)
        try:
            with self.assertRaises(lightfarm.FailedPrecondition) as caught:
                self.alice.depend(third, [fourth])
            self.assertEqual(caught.exception.message, f"cycle: {third} -> {fourth} -> {third}")
            self.assertEqual(self.alice.get(fourth).waiting_for, (third,))
        finally:
            self.alice.cancel(third)
        failed = self.alice.get(fourth)
        self.assertEqual((failed.state, failed.error),
                         (lightfarm.JobState.FAILED, f"dependency {third} was cancelled"))

    def test_set_worker_state(self):
        """An admin disables w1 (it then takes nothing) and enables it again; a submitter may not."""
        with self.assertRaises(lightfarm.PermissionDenied):
            self.alice.set_worker_state("w1", "disable")
        with self.farm.client("root") as root:
            try:
                (w1,) = root.set_worker_state("w1", "disable")
                self.assertEqual((w1.name, w1.state), ("w1", "disabled"))
                job = self.alice.wait(self.alice.submit(cornell(), **SMALL))
                self.assertEqual(job.state, lightfarm.JobState.SUCCEEDED, job.error)
                self.assertNotIn(w1.id, {t.worker for t in self.alice.tasks(job.id)})
            finally:
                (w1,) = root.set_worker_state("w1", "enable")
            self.assertIn(w1.state, ("idle", "busy"))
            with self.assertRaises(lightfarm.NotFound):
                root.set_worker_state("nobody", "drain")

    def test_tasks_logs_priority(self):
        """SetJobPriority on a running job, then ListTasks and GetTaskLogs of the ended job."""
        job_id = self.alice.submit(cornell(), **SMALL)
        try:
            self.assertEqual(self.alice.set_priority(job_id, 7).priority, 7)
        except lightfarm.FailedPrecondition:
            self.assertTrue(self.alice.get(job_id).state.final, "refused while still running")
        job = self.alice.wait(job_id)
        tasks = self.alice.tasks(job_id)
        self.assertEqual(len(tasks), job.tasks_total)
        self.assertTrue(all(t.state == "DONE" for t in tasks), tasks)
        lines = builtins.list(self.alice.logs(job_id))
        self.assertTrue(lines, "the workers' lines of the job's tasks")
        self.assertEqual({l.task_index for l in lines}, set(range(job.tasks_total)))
        one = builtins.list(self.alice.logs(job_id, task=0))
        self.assertTrue(one and all(l.task_index == 0 for l in one), one)

    def test_max_attempts_and_blocklist_after(self):
        """Job management (issue 30): submit's limits reach the job; out of range is refused."""
        job = self.alice.wait(self.alice.submit(cornell(), max_attempts=7, blocklist_after=2,
                                                **SMALL))
        self.assertEqual((job.max_attempts, job.blocklist_after), (7, 2))
        self.assertEqual(job.blocklist, [])
        with self.assertRaises(lightfarm.InvalidArgument) as caught:
            self.alice.submit(cornell(), max_attempts=101, **SMALL)
        self.assertIn("max_attempts 101: expected 1 to 100", caught.exception.message)

    def test_requeue(self):
        """Job management (issue 30): a cancelled job is queued again; a succeeded one is not."""
        job_id = self.alice.submit(cornell(), spp=4096, resolution=(128, 128), tile=32,
                                   name="long")
        self.assertEqual(self.alice.cancel(job_id).state, lightfarm.JobState.CANCELLED)
        job = self.alice.requeue(job_id)
        self.assertEqual(job.state, lightfarm.JobState.QUEUED)
        self.assertEqual(job.error, "")
        # Paused and resumed while it runs; cancelled, it cannot be paused.
        self.assertTrue(self.alice.pause(job_id).paused)
        self.assertTrue(self.alice.get(job_id).paused)
        self.assertFalse(self.alice.resume(job_id).paused)
        self.assertEqual(self.alice.cancel(job_id).state, lightfarm.JobState.CANCELLED)
        with self.assertRaises(lightfarm.FailedPrecondition):
            self.alice.pause(job_id)
        done = self.alice.wait(self.alice.submit(cornell(), **SMALL))
        with self.assertRaises(lightfarm.FailedPrecondition):
            self.alice.requeue(done.id)

    def test_stats(self):
        """History (issue 30): a submitter's own rows, an admin's everyone's, as plain dicts."""
        job = self.alice.wait(self.alice.submit(cornell(), **SMALL))
        self.assertGreater(job.cpu_seconds, 0)
        self.assertGreater(job.render_seconds, 0)
        mine = self.alice.stats(since=datetime.timedelta(hours=1))
        self.assertIsNotNone(mine["since"])
        self.assertEqual([o["owner"] for o in mine["owners"]], ["alice"])
        alice = mine["owners"][0]
        self.assertGreaterEqual(alice["jobs_succeeded"], 1)
        self.assertGreaterEqual(alice["tasks"], job.tasks_total)
        self.assertGreater(alice["cpu_seconds"], 0)
        self.assertGreater(alice["render_seconds"], 0)
        # The workers' rows are of alice's tasks only: they add up to hers.
        self.assertEqual(sum(w["tasks"] for w in mine["workers"]), alice["tasks"])
        with self.farm.client("root") as root:
            everyone = root.stats()
            self.assertIsNone(everyone["since"])
            self.assertIn(alice["owner"], [o["owner"] for o in everyone["owners"]])
            self.assertGreaterEqual(root.stats(owner="alice")["owners"][0]["tasks"],
                                    alice["tasks"])
        with self.farm.client("bob") as bob:
            with self.assertRaises(lightfarm.PermissionDenied):
                bob.stats(owner="alice")
        with self.assertRaises(lightfarm.InvalidArgument):
            self.alice.stats(since=datetime.datetime(2999, 1, 1))

    def test_requeue_frames(self):
        """requeue(frames=...): a succeeded shot's frame rendered again, and it succeeds again;
        a frame outside the shot is refused, naming it; failed=False alone requeues nothing."""
        ball = os.path.join(SCENES, "shots", "moving_ball.json")
        job_id = self.alice.submit(ball, frames="2-6:2", spp=2, resolution=(32, 18), tile=16)
        self.assertEqual(self.alice.wait(job_id).state, lightfarm.JobState.SUCCEEDED)
        job = self.alice.requeue(job_id, frames="4")
        self.assertEqual(job.state, lightfarm.JobState.QUEUED)
        self.assertEqual(self.alice.wait(job_id).state, lightfarm.JobState.SUCCEEDED)
        with self.assertRaises(lightfarm.InvalidArgument) as caught:
            self.alice.requeue(job_id, frames="5")
        self.assertIn("frame 5 not in job", caught.exception.message)
        with self.assertRaises(ValueError):
            self.alice.requeue(job_id, failed=False)

    def test_shot_submit_and_fetch_frames(self):
        """A shot submitted with frames, fps and shutter; fetch_frames writes each finished
        frame as `lightfarm fetch -o out_####.exr` does, byte for byte."""
        ball = os.path.join(SCENES, "shots", "moving_ball.json")
        job_id = self.alice.submit(ball, frames="2-6:2", fps=12.0, shutter=0.5, spp=2,
                                   resolution=(32, 18), tile=16)
        job = self.alice.wait(job_id)
        self.assertEqual(job.state, lightfarm.JobState.SUCCEEDED, job.error)
        shot = job.params.shot
        self.assertEqual((shot.first, shot.last, shot.step, shot.fps, shot.shutter, shot.chunk),
                         (2, 6, 2, 12.0, 0.5, 1))
        self.assertEqual([f.frame for f in job.proto.frames], [2, 4, 6])
        pattern = self.farm.path("shot", "py_###.exr")
        os.makedirs(os.path.dirname(pattern))
        written = self.alice.fetch_frames(job_id, pattern)
        self.assertEqual(written, [self.farm.path("shot", f"py_00{f}.exr") for f in (2, 4, 6)])
        r = self.farm.cli("fetch", job_id, "-o", self.farm.path("shot", "cli_###.exr"))
        self.assertEqual(r.returncode, 0, r.stderr)
        images = []
        for f in (2, 4, 6):
            with open(self.farm.path("shot", f"py_00{f}.exr"), "rb") as mine, \
                    open(self.farm.path("shot", f"cli_00{f}.exr"), "rb") as cli:
                images.append(mine.read())
                self.assertEqual(images[-1], cli.read(), f"frame {f}: the CLI's bytes")
            self.assertEqual(images[-1][:4], EXR_MAGIC)
        self.assertNotEqual(images[0], images[1], "the ball moves between frames")
        self.assertEqual(self.alice.fetch_frames(job_id, self.farm.path("shot", "one.exr"),
                                                 frames="4"), [self.farm.path("shot", "one.exr")])
        with open(self.farm.path("shot", "one.exr"), "rb") as f:
            self.assertEqual(f.read(), images[1])
        self.assertEqual(self.alice.fetch_frames(job_id, self.farm.path("shot", "s_#.png"),
                                                 frames=[6]), [self.farm.path("shot", "s_6.png")])

        with self.assertRaises(lightfarm.InvalidArgument) as caught:
            self.alice.fetch_frames(job_id, pattern, frames="3")
        self.assertIn("frame 3 is not one of", caught.exception.message)
        with self.assertRaises(lightfarm.InvalidArgument) as caught:
            self.alice.fetch_frames(job_id, self.farm.path("shot", "all.exr"))
        self.assertIn("has no '#'", caught.exception.message)
        still = self.alice.submit(cornell(), **SMALL)
        self.alice.wait(still)
        with self.assertRaises(lightfarm.InvalidArgument) as caught:
            self.alice.fetch_frames(still, pattern)
        self.assertIn("is a still", caught.exception.message)

    def test_shot_arguments_checked(self):
        ball = os.path.join(SCENES, "shots", "moving_ball.json")
        for kwargs, text in ((dict(frames="6-2"), "reversed"),
                             (dict(frames="1-4", frame=2), "not both"),
                             (dict(fps=30.0), "a still has no time"),
                             (dict(shutter=0.5), "motion blur needs frames"),
                             (dict(frames="1-4", shutter=11.0), "shutter 11"),
                             (dict(frames="1-4", fps=0.0), "fps 0"),
                             (dict(frames="1-4", chunk=0), "chunk 0"),
                             (dict(frames="1-4:0"), "step 0")):
            with self.assertRaises(lightfarm.InvalidArgument, msg=kwargs) as caught:
                self.alice.submit(ball, **kwargs)
            self.assertIn(text, caught.exception.message)
        # One frame: the scene at that frame's time, fetched as that frame.
        job_id = self.alice.submit(ball, frame=12, spp=1, resolution=(16, 9), tile=16, chunk=1)
        self.assertEqual(self.alice.wait(job_id).state, lightfarm.JobState.SUCCEEDED)
        self.assertEqual(self.alice.fetch_frames(job_id, self.farm.path("frame12.exr")),
                         [self.farm.path("frame12.exr")])


if __name__ == "__main__":
    unittest.main()

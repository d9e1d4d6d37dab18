#!/usr/bin/env python3
"""The farm across hosts (issue 16): Linux network namespaces joined by a bridge.

One namespace per host: the server, two workers and a client, each with one veth into a hub
namespace that holds the bridge (nothing is added to the host's own namespace). Everything
speaks TLS (a CA of the test, a server certificate for the server's address, a client
certificate for the workers) with bearer tokens. Checked:

  (a) a path-traced and a radiosity job give the pixels of `lightfarm render` with the same flags;
  (b) over 20 Mbit/s links (tc tbf) with 50 ms more each way (a delaying TCP proxy: this kernel
      may lack netem) a job completes with the pixels of `lightfarm render`; its throughput
      against the same links unlimited is printed, not checked (a benchmark's figure);
  (c) a worker whose link is cut mid-job loses its lease, the other worker finishes, the image is
      the uncut one, and the worker leases again once its link is back;
  (d) the server's link cut for 60 s: workers and `lightfarm watch --retry-seconds 180` ride it
      out and the job succeeds;
  (e) a worker certificate of another CA, a wrong token and a worker token used to submit are
      refused.

Needs root (CAP_NET_ADMIN), iproute2, tc and openssl; without them it says why and exits 77,
which ctest reports as skipped. Every namespace, link and process is removed at the end.

  python3 tests/netns/farm_netns_test.py --bin-dir build/bin --scenes tests/scenes

`--proxy LISTEN TARGET DELAY` runs the delaying proxy alone (the test starts it that way inside
the server's namespace).
"""

import argparse
import asyncio
import datetime
import itertools
import os
import re
import secrets
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time
import zlib

SKIP = 77

SUBNET = "10.200.0"
HOSTS = {"server": SUBNET + ".1", "w1": SUBNET + ".11", "w2": SUBNET + ".12",
         "client": SUBNET + ".21"}
PORT, PROXY_PORT, PLAIN_PORT = 7070, 7071, 7072
LEASE_SECONDS = 2
RATE = "20mbit"
DELAY = 0.050
OUTAGE_SECONDS = 60

# (b): the throughput job, 16 tasks. A worker renders its task, sends the result (104 bytes a
# pixel: 425 KB) and only then asks for the next, so each task pays two round trips and its
# upload on top of its render; the summary prints that overhead per task.
BIG_FLAGS = "--resolution 256x256 --spp 256 --tile 64 --seed 7"
PATH_FLAGS = "--resolution 64x64 --spp 16 --tile 16 --seed 3"
RADIOSITY_FLAGS = "--method radiosity --patches 300 --resolution 64x64 --spp 4 --tile 16"
OUTAGE_FLAGS = "--resolution 128x128 --spp 64 --tile 16 --seed 11"
REJOIN_FLAGS = "--resolution 64x64 --spp 32 --tile 8 --seed 13"


def log(msg):
    print(f"[{time.strftime('%H:%M:%S')}] {msg}", flush=True)


class Failed(Exception):
    pass


def check(cond, msg):
    if not cond:
        raise Failed(msg)


# ---- the delaying proxy -------------------------------------------------------------------------

async def _pump(reader, writer, delay):
    """Forwards reader to writer, each chunk `delay` seconds after it arrived; never throttles."""
    loop = asyncio.get_running_loop()
    queue = asyncio.Queue()

    async def read():
        try:
            while True:
                data = await reader.read(1 << 16)
                queue.put_nowait((loop.time() + delay, data))
                if not data:
                    return
        except (ConnectionError, OSError):
            queue.put_nowait((loop.time(), b""))

    async def write():
        try:
            while True:
                due, data = await queue.get()
                wait = due - loop.time()
                if wait > 0:
                    await asyncio.sleep(wait)
                if not data:
                    if writer.can_write_eof():
                        writer.write_eof()
                    return
                writer.write(data)
                await writer.drain()
        except (ConnectionError, OSError):
            pass

    await asyncio.gather(read(), write())


async def _proxy_main(listen, target, delay):
    thost, tport = target.rsplit(":", 1)

    async def handle(creader, cwriter):
        try:
            sreader, swriter = await asyncio.open_connection(thost, int(tport))
        except OSError:
            cwriter.close()
            return
        try:
            await asyncio.gather(_pump(creader, swriter, delay), _pump(sreader, cwriter, delay))
        finally:
            for w in (cwriter, swriter):
                w.close()

    host, port = listen.rsplit(":", 1)
    server = await asyncio.start_server(handle, host, int(port))
    print(f"proxy on {listen} to {target}, +{delay * 1000:.0f} ms each way", flush=True)
    async with server:
        await server.serve_forever()


# ---- OpenEXR pixels, read with the standard library (scan-line files, lightfarm's ZIP) ----------

LINES_PER_CHUNK = {0: 1, 1: 1, 2: 1, 3: 16, 4: 32, 5: 16, 6: 32, 7: 32, 8: 32, 9: 256}


def read_exr(path):
    """Header attributes {name: (type, bytes)}, channels and the chunks [(y, bytes)] of a
    single-part scan-line EXR."""
    data = open(path, "rb").read()
    magic, version = struct.unpack_from("<ii", data, 0)
    check(magic == 20000630, f"{path}: not an OpenEXR file")
    check(not version & 0x1200, f"{path}: tiled or multi-part EXR, which this reader skips")
    pos, attrs = 8, {}

    def cstr(p):
        end = data.index(b"\0", p)
        return data[p:end].decode(), end + 1

    while data[pos] != 0:
        name, pos = cstr(pos)
        kind, pos = cstr(pos)
        (size,) = struct.unpack_from("<i", data, pos)
        attrs[name] = (kind, data[pos + 4:pos + 4 + size])
        pos += 4 + size
    pos += 1
    channels, raw, p = [], attrs["channels"][1], 0
    while raw[p] != 0:
        end = raw.index(b"\0", p)
        (ptype,) = struct.unpack_from("<i", raw, end + 1)
        channels.append((raw[p:end].decode(), ptype))
        p = end + 1 + 16
    xmin, ymin, xmax, ymax = struct.unpack("<iiii", attrs["dataWindow"][1])
    compression = attrs["compression"][1][0]
    n = -(-(ymax - ymin + 1) // LINES_PER_CHUNK[compression])
    offsets = struct.unpack_from(f"<{n}Q", data, pos)
    chunks = []
    for off in offsets:
        y, size = struct.unpack_from("<ii", data, off)
        chunks.append((y, data[off + 8:off + 8 + size]))
    return {"attrs": attrs, "channels": channels, "width": xmax - xmin + 1,
            "height": ymax - ymin + 1, "compression": compression, "chunks": chunks}


def chunk_pixels(exr, chunk):
    """The raw pixel bytes of a chunk (ZIP/ZIPS undone; others as stored)."""
    if exr["compression"] not in (2, 3):
        return chunk
    t = zlib.decompress(chunk)
    t = bytes(itertools.accumulate(t, lambda a, b: (a + b - 128) & 255))
    half = (len(t) + 1) // 2
    out = bytearray(len(t))
    out[0::2], out[1::2] = t[:half], t[half:]
    return bytes(out)


def mean_of(exr, name):
    """Mean of a float32 channel, to show an image is not black."""
    sizes = {0: 4, 1: 2, 2: 4}
    total, count = 0.0, 0
    lines = LINES_PER_CHUNK[exr["compression"]]
    for y, chunk in exr["chunks"]:
        raw, p = chunk_pixels(exr, chunk), 0
        for _ in range(min(lines, exr["height"] - y)):
            for ch, ptype in exr["channels"]:
                n = exr["width"] * sizes[ptype]
                if ch == name:
                    vals = struct.unpack_from(f"<{exr['width']}f", raw, p)
                    total, count = total + sum(vals), count + len(vals)
                p += n
    return total / max(count, 1)


TIMINGS = {"lightfarm.seconds", "lightfarm.radiosity.formFactorSeconds",
           "lightfarm.radiosity.solveSeconds"}


def same_image(a_path, b_path):
    """Same channels and pixels bit for bit, and the same lightfarm.* header values but for the
    timings. Returns whether the stored (compressed) chunks are byte-identical too."""
    a, b = read_exr(a_path), read_exr(b_path)
    check(a["channels"] == b["channels"], f"channels differ: {a['channels']} {b['channels']}")
    check((a["width"], a["height"]) == (b["width"], b["height"]), "image sizes differ")
    check(len(a["chunks"]) == len(b["chunks"]), "chunk counts differ")
    stored_same = True
    for (ya, ca), (yb, cb) in zip(a["chunks"], b["chunks"]):
        check(ya == yb, f"chunk order differs at y={ya}")
        if ca != cb:
            stored_same = False
            check(chunk_pixels(a, ca) == chunk_pixels(b, cb),
                  f"pixels of {a_path} and {b_path} differ in the lines from y={ya}")
    names = {n for n in a["attrs"] if n.startswith("lightfarm.")}
    check(names == {n for n in b["attrs"] if n.startswith("lightfarm.")},
          "the lightfarm.* header attributes differ in their names")
    for n in sorted(names - TIMINGS):
        check(a["attrs"][n] == b["attrs"][n], f"header attribute {n} differs")
    return stored_same


# ---- the test -----------------------------------------------------------------------------------

class Farm:
    def __init__(self, args):
        self.bin = os.path.abspath(args.bin_dir)
        self.scenes = os.path.abspath(args.scenes)
        self.scene = os.path.join(self.scenes, "cornell_box.json")
        self.prefix = f"lf{os.getpid()}"
        self.hub = self.prefix + "hub"
        self.ns = {h: f"{self.prefix}{h}" for h in HOSTS}
        self.made_ns = []
        self.procs = []
        self.dir = tempfile.mkdtemp(prefix=f"lightfarm-netns-{os.getpid()}-")
        self.keep = args.keep
        self.results = {}
        self.workers = {}
        self.pid_host = {}
        self.server = None
        self.addr = f"{HOSTS['server']}:{PORT}"

    # -- processes
    def path(self, *names):
        return os.path.join(self.dir, *names)

    def sh(self, argv, ns=None, timeout=120, ok=True):
        full = (["ip", "netns", "exec", self.ns[ns]] if ns else []) + argv
        r = subprocess.run(full, capture_output=True, text=True, timeout=timeout)
        if ok and r.returncode != 0:
            raise Failed(f"`{' '.join(full)}` exited {r.returncode}: {r.stdout}{r.stderr}")
        return r

    def ip(self, *args, ns=None):
        full = ["ip"] + (["-n", ns] if ns else []) + list(args)
        r = subprocess.run(full, capture_output=True, text=True, timeout=30)
        if r.returncode != 0:
            raise Failed(f"`{' '.join(full)}`: {r.stderr.strip()}")

    def spawn(self, ns, argv, name):
        if os.path.exists(self.path(name + ".log")):
            name += f"-{len(os.listdir(self.dir))}"
        logf = open(self.path(name + ".log"), "w")
        p = subprocess.Popen(["ip", "netns", "exec", self.ns[ns]] + argv,
                             stdout=subprocess.PIPE, stderr=logf, text=True,
                             start_new_session=True)
        p.log_path = self.path(name + ".log")
        self.procs.append(p)
        return p

    def stop(self, p, sig=signal.SIGTERM, wait=10):
        if p.poll() is None:
            p.send_signal(sig)
            try:
                p.wait(wait)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait(5)
        if p in self.procs:
            self.procs.remove(p)

    def lf(self, ns, cmd, token="alice", server=None, tls=True, timeout=300, ok=True):
        """`lightfarm CMD` from a namespace, with TLS and a token."""
        argv = [os.path.join(self.bin, "lightfarm")] + cmd
        argv += ["--server", server or self.addr]
        if tls:
            argv += ["--tls-ca", self.path("ca.crt")]
        if token:
            argv += ["--token-file", self.path(token + ".token")]
        return self.sh(argv, ns=ns, timeout=timeout, ok=ok)

    # -- set up
    def probe(self):
        for tool in ("ip", "tc", "openssl"):
            if not shutil.which(tool):
                return f"{tool} is not installed"
        if os.geteuid() != 0:
            return "not root: creating network namespaces needs CAP_NET_ADMIN"
        # What the test needs, tried in a namespace of its own: a bridge, a veth pair, tbf.
        name = self.prefix + "probe"
        r = subprocess.run(["ip", "netns", "add", name], capture_output=True, text=True)
        if r.returncode != 0:
            return f"cannot create a network namespace: {r.stderr.strip()}"
        try:
            for what, argv in (
                    ("a bridge", ["ip", "-n", name, "link", "add", "br0", "type", "bridge"]),
                    ("a veth pair", ["ip", "-n", name, "link", "add", "v0", "type", "veth",
                                     "peer", "name", "v1"]),
                    ("a tbf qdisc", ["tc", "-n", name, "qdisc", "add", "dev", "v0", "root",
                                     "tbf", "rate", RATE, "burst", "64kb", "limit", "1mb"])):
                r = subprocess.run(argv, capture_output=True, text=True)
                if r.returncode != 0:
                    return f"cannot create {what}: {r.stderr.strip()}"
        finally:
            subprocess.run(["ip", "netns", "del", name], capture_output=True)
        for b in ("lightfarm", "lightfarm-server", "lightfarm-worker"):
            if not os.access(os.path.join(self.bin, b), os.X_OK):
                raise Failed(f"{self.bin}/{b} is missing: build the project first")
        return None

    def network(self):
        for ns in [self.hub] + list(self.ns.values()):
            self.ip("netns", "add", ns)
            self.made_ns.append(ns)
            self.ip("link", "set", "lo", "up", ns=ns)
        self.ip("link", "add", "br0", "type", "bridge", ns=self.hub)
        self.ip("link", "set", "br0", "up", ns=self.hub)
        for host, addr in HOSTS.items():
            # The hub's end is named after the host; the host's end is eth0.
            self.ip("link", "add", host, "type", "veth", "peer", "name", "eth0", "netns",
                    self.ns[host], ns=self.hub)
            self.ip("link", "set", host, "master", "br0", "up", ns=self.hub)
            self.ip("addr", "add", addr + "/24", "dev", "eth0", ns=self.ns[host])
            self.ip("link", "set", "eth0", "up", ns=self.ns[host])

    def link(self, host, up):
        self.ip("link", "set", host, "up" if up else "down", ns=self.hub)

    def shape(self, on):
        """20 Mbit/s each way on every link: tbf on both ends of each veth. Its queue holds 1 MB
        (0.4 s at 20 Mbit/s): with a 100 ms queue the two workers' results, meeting on the
        server's link, overflow it, and each tail drop costs a TCP retransmission timeout."""
        for host in HOSTS:
            for dev, ns in ((host, self.hub), ("eth0", self.ns[host])):
                if on:
                    subprocess.run(["tc", "-n", ns, "qdisc", "replace", "dev", dev, "root", "tbf",
                                    "rate", RATE, "burst", "64kb", "limit", "1mb"],
                                   check=True, capture_output=True)
                else:
                    subprocess.run(["tc", "-n", ns, "qdisc", "del", "dev", dev, "root"],
                                   capture_output=True)

    def certificates(self):
        def ssl_(*args):
            r = subprocess.run(["openssl"] + list(args), capture_output=True, text=True,
                               cwd=self.dir)
            if r.returncode != 0:
                raise Failed(f"openssl {' '.join(args)}: {r.stderr}")

        def key(name):
            ssl_("ecparam", "-name", "prime256v1", "-genkey", "-noout", "-out", name + ".key")

        def ca(name):
            key(name)
            ssl_("req", "-x509", "-new", "-key", name + ".key", "-days", "2", "-subj",
                 f"/CN=lightfarm netns test {name}", "-out", name + ".crt")

        def leaf(name, ca_name, cn, ext):
            key(name)
            ssl_("req", "-new", "-key", name + ".key", "-subj", f"/CN={cn}", "-out",
                 name + ".csr")
            with open(self.path(name + ".ext"), "w") as f:
                f.write(ext)
            ssl_("x509", "-req", "-in", name + ".csr", "-CA", ca_name + ".crt", "-CAkey",
                 ca_name + ".key", "-CAcreateserial", "-days", "2", "-extfile", name + ".ext",
                 "-out", name + ".crt")

        ca("ca")
        ca("other-ca")
        leaf("server", "ca", HOSTS["server"],
             f"subjectAltName=IP:{HOSTS['server']}\nextendedKeyUsage=serverAuth\n")
        leaf("worker", "ca", "lightfarm worker", "extendedKeyUsage=clientAuth\n")
        leaf("rogue", "other-ca", "rogue worker", "extendedKeyUsage=clientAuth\n")

    def tokens(self):
        data = self.path("server-data")
        for name, role in (("alice", "submitter"), ("node", "worker")):
            r = self.sh([os.path.join(self.bin, "lightfarm-server"), "token", "create",
                         "--data-dir", data, "--name", name, "--role", role])
            with open(self.path(name + ".token"), "w") as f:
                f.write(r.stdout.strip().splitlines()[-1] + "\n")
        with open(self.path("wrong.token"), "w") as f:
            f.write(secrets.token_hex(32) + "\n")

    def start_server(self):
        self.server = self.spawn("server", [
            os.path.join(self.bin, "lightfarm-server"), "--listen", self.addr, "--data-dir",
            self.path("server-data"), "--tls-cert", self.path("server.crt"), "--tls-key",
            self.path("server.key"), "--tls-client-ca", self.path("ca.crt"), "--lease-seconds",
            str(LEASE_SECONDS), "--log-level", "debug"], "server")
        line = self.server.stdout.readline().strip()
        check(line.startswith("listening on"), f"server did not start: {line!r}, "
              f"{open(self.server.log_path).read()[-2000:]}")

    def start_worker(self, host, port=PORT, cert="worker"):
        if host in self.workers:
            self.stop(self.workers.pop(host))
        certs = ["--tls-cert", self.path(cert + ".crt"), "--tls-key",
                 self.path(cert + ".key")] if cert else []
        p = self.spawn(host, [
            os.path.join(self.bin, "lightfarm-worker"), "--server", f"{HOSTS['server']}:{port}",
            "--tls-ca", self.path("ca.crt")] + certs + [
            "--token-file", self.path("node.token"), "--name", host, "--threads", "1",
            "--cache-dir", self.path("cache-" + host), "--log-level", "debug"],
            host)
        self.workers[host] = p
        self.pid_host[p.pid] = host
        return p

    def start_proxy(self):
        p = self.spawn("server", [sys.executable, os.path.abspath(__file__), "--proxy",
                                  f"{HOSTS['server']}:{PROXY_PORT}", self.addr, str(DELAY)],
                       "proxy")
        check(p.stdout.readline().startswith("proxy on"), "the delaying proxy did not start")
        return p

    # -- jobs
    def submit(self, flags, server=None):
        r = self.lf("client", ["submit", self.scene] + flags.split(), server=server)
        return r.stdout.strip().splitlines()[-1]

    def watch(self, job, server=None, timeout=300):
        argv = ["ip", "netns", "exec", self.ns["client"], os.path.join(self.bin, "lightfarm"),
                "watch", job, "--server", server or self.addr, "--tls-ca", self.path("ca.crt"),
                "--token-file", self.path("alice.token")]
        p = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        end = time.monotonic() + timeout
        try:
            while p.poll() is None:
                for host, w in self.workers.items():
                    if "run workers of the server's build" in open(w.log_path).read():
                        raise Failed(f"{host} is refused as another build than the server's: "
                                     "were the binaries rebuilt during the test?")
                if time.monotonic() > end:
                    tails = "".join(f"\n{h}: " + "".join(open(w.log_path).readlines()[-3:])
                                    for h, w in self.workers.items())
                    raise Failed(f"job {job} did not end within {timeout} s; workers:{tails}")
                time.sleep(0.02)
        finally:
            if p.poll() is None:
                p.kill()
            err = p.communicate()[1]
        check(p.returncode == 0, f"watch {job} exited {p.returncode}: {err[-2000:]}")

    def fetch(self, job, out, server=None):
        self.lf("client", ["fetch", job, "-o", out], server=server)

    def render_local(self, flags, out):
        if not os.path.exists(out):
            self.sh([os.path.join(self.bin, "lightfarm"), "render", self.scene, "-o", out,
                     "--no-progress"] + flags.split(), timeout=600)
        return out

    def timed_job(self, flags, server=None):
        t0 = time.monotonic()
        job = self.submit(flags, server=server)
        self.watch(job, server=server)
        return job, time.monotonic() - t0

    # -- server log
    def server_log(self):
        return open(self.server.log_path).read()

    @staticmethod
    def stamp(line):
        m = re.match(r"\[(\d{4}-\d\d-\d\d \d\d:\d\d:\d\d\.\d+)\]", line)
        if not m:
            return None
        return datetime.datetime.strptime(m.group(1)[:26], "%Y-%m-%d %H:%M:%S.%f").timestamp()

    def leases(self, job):
        """[(time, task, host, attempt)] of a job, from the server's debug log (a worker's id
        is HOSTNAME-PID, and `ip netns exec` execs, so the pid is that of our Popen)."""
        out = []
        for line in self.server_log().splitlines():
            m = re.search(rf"job={re.escape(job)} task=(\d+) leased to (\S+) \(attempt (\d+)\)",
                          line)
            if m:
                pid = int(m.group(2).rsplit("-", 1)[-1]) if "-" in m.group(2) else -1
                out.append((self.stamp(line), int(m.group(1)), self.pid_host.get(pid, m.group(2)),
                            int(m.group(3))))
        return out

    def wait_for(self, pred, timeout, what, step=0.02):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            v = pred()
            if v:
                return v
            time.sleep(step)
        raise Failed(f"timed out after {timeout} s waiting for {what}")

    # -- the parts
    def part_e_refusals(self):
        log("(e) refusals")
        # A client certificate from another CA: the TLS handshake fails.
        r = self.lf("client", ["list", "--tls-cert", self.path("rogue.crt"), "--tls-key",
                               self.path("rogue.key")], ok=False)
        check(r.returncode != 0, "a client certificate of another CA was accepted")
        self.results["e: other CA's client cert (lightfarm list)"] = \
            f"exit {r.returncode}: {last_line(r.stderr)}"
        handshakes = self.server_log().count("Handshake failed")
        check(handshakes > 0, "the server logged no failed handshake for the client")
        # A worker with such a certificate leases nothing: the server fails its handshakes. A
        # worker with no certificate (from the client's host) is refused at LeaseTask.
        rogue = self.start_worker("w2", cert="rogue")
        bare = self.start_worker("client", cert=None)
        time.sleep(3)
        for p in (rogue, bare):
            self.stop(p)
        self.workers.pop("w2", None)
        self.workers.pop("client", None)
        wlog, slog = open(rogue.log_path).read(), self.server_log()
        said = [ln.split("] ")[-1] for ln in wlog.splitlines()
                if "unreachable" in ln or "refused" in ln]
        check(said, f"the rogue worker's log says nothing:\n{wlog[-1500:]}")
        check(slog.count("Handshake failed") > handshakes,
              "the server logged no failed handshake for the rogue worker")
        for p in (rogue, bare):
            check(not re.search(rf"leased to \S+-{p.pid} ", slog), "a refused worker leased")
        self.results["e: other CA's worker cert"] = (
            "no lease; worker: " + last_line(said[0]) +
            "; server: " + last_line([ln.split("]")[-1] for ln in slog.splitlines()
                                      if "Handshake failed" in ln][-1]))
        refused = [ln for ln in slog.splitlines() if "LeaseTask from" in ln and
                   HOSTS["client"] in ln and "refused" in ln]
        check(refused and "client certificate" in refused[0],
              f"a worker without a certificate was not refused:\n{slog[-1500:]}")
        self.results["e: worker without a client cert"] = "no lease; server: " + \
            refused[0].split("] ")[-1]
        # A wrong token: UNAUTHENTICATED.
        r = self.lf("client", ["list"], token="wrong", ok=False)
        check(r.returncode != 0 and unauthenticated(r.stderr),
              f"a wrong token: exit {r.returncode}, {r.stdout}{r.stderr}")
        self.results["e: wrong token"] = f"exit {r.returncode}: {last_line(r.stderr)}"
        # A worker's token used to submit: PERMISSION_DENIED.
        r = self.lf("client", ["submit", self.scene, "--retry-seconds", "0"] +
                    PATH_FLAGS.split(), token="node", ok=False)
        check(r.returncode != 0 and ("PERMISSION_DENIED" in r.stderr or
                                     'has role worker, which may not' in r.stderr),
              f"a worker token submitting: exit {r.returncode}, {r.stdout}{r.stderr}")
        self.results["e: worker token submits"] = f"exit {r.returncode}: {last_line(r.stderr)}"
        # No token at all.
        r = self.lf("client", ["list"], token=None, ok=False)
        check(r.returncode != 0 and unauthenticated(r.stderr),
              f"no token: exit {r.returncode}, {r.stdout}{r.stderr}")
        self.results["e: no token"] = f"exit {r.returncode}: {last_line(r.stderr)}"

    def handshake_ms(self, port, n=10):
        """Medians of n TCP connects and of the TLS handshakes that follow (h2, the worker's
        client certificate, as gRPC makes them), from the client's host."""
        code = (
            "import socket, ssl, time, statistics as s\n"
            f"c = ssl.create_default_context(cafile={self.path('ca.crt')!r})\n"
            f"c.load_cert_chain({self.path('worker.crt')!r}, {self.path('worker.key')!r})\n"
            "c.set_alpn_protocols(['h2'])\n"
            "hs, tcp = [], []\n"
            f"for i in range({n}):\n"
            "    t0 = time.perf_counter()\n"
            f"    raw = socket.create_connection(({HOSTS['server']!r}, {port}))\n"
            "    t1 = time.perf_counter()\n"
            f"    t = c.wrap_socket(raw, server_hostname={HOSTS['server']!r})\n"
            "    t2 = time.perf_counter()\n"
            "    tcp.append(t1 - t0); hs.append(t2 - t1); t.close()\n"
            "print(s.median(tcp) * 1e3, s.median(hs) * 1e3)\n")
        r = self.sh([sys.executable, "-c", code], ns="client")
        return tuple(map(float, r.stdout.split()))

    def part_tls_cost(self):
        log("TLS cost")
        tcp_ms, hs_ms = self.handshake_ms(PORT)
        self.results["TCP connect (median of 10)"] = f"{tcp_ms:.2f} ms"
        self.results["TLS handshake after it (median of 10)"] = f"{hs_ms:.2f} ms"
        # The same calls to this server and to a plain one (--insecure; with a token still, as
        # every server beyond loopback asks for one): the difference is TLS.
        r = self.sh([os.path.join(self.bin, "lightfarm-server"), "token", "create", "--data-dir",
                     self.path("plain-data"), "--name", "alice", "--role", "submitter"])
        with open(self.path("plain.token"), "w") as f:
            f.write(r.stdout.strip().splitlines()[-1] + "\n")
        plain = self.spawn("server", [
            os.path.join(self.bin, "lightfarm-server"), "--listen",
            f"{HOSTS['server']}:{PLAIN_PORT}", "--data-dir", self.path("plain-data"),
            "--insecure"], "plain-server")
        check(plain.stdout.readline().startswith("listening on"), "plain server did not start")
        kinds = {"TLS": {}, "plain": {"server": f"{HOSTS['server']}:{PLAIN_PORT}", "tls": False,
                                      "token": "plain"}}
        try:
            # tools/rpc_bench: a new connection's first call, and calls on an open connection.
            bench = os.path.join(self.bin, "rpc_bench")
            if os.access(bench, os.X_OK):
                for kind, kw in kinds.items():
                    argv = [bench, "--server", kw.get("server", self.addr), "--token-file",
                            self.path(kw.get("token", "alice") + ".token"), "--connections",
                            "20", "--calls", "200"]
                    if kw.get("tls", True):
                        argv += ["--tls-ca", self.path("ca.crt")]
                    out = self.sh(argv, ns="client").stdout
                    for what, median in re.findall(r"^(.*?)\s+n=\d+.*?median ([\d.]+) ms", out,
                                                   re.M):
                        self.results[f"rpc_bench {kind}: {what} (median)"] = f"{median} ms"
            # Whole `lightfarm list` runs (process start included), alternating the two.
            n, times = 10, {k: [] for k in kinds}
            for _ in range(n):
                for kind, kw in kinds.items():
                    t0 = time.monotonic()
                    self.lf("client", ["list"], **kw)
                    times[kind].append((time.monotonic() - t0) * 1e3)
        finally:
            self.stop(plain)
        med = {k: sorted(v)[n // 2] for k, v in times.items()}
        self.results["`lightfarm list` TLS / plain (median of 10)"] = (
            f"{med['TLS']:.1f} / {med['plain']:.1f} ms ({med['TLS'] - med['plain']:+.1f} ms)")

    def part_a_identity(self):
        log("(a) path and radiosity jobs against `lightfarm render`")
        jobs = {name: self.submit(flags) for name, flags in
                (("path", PATH_FLAGS), ("radiosity", RADIOSITY_FLAGS))}
        for name, flags in (("path", PATH_FLAGS), ("radiosity", RADIOSITY_FLAGS)):
            local = self.render_local(flags, self.path(f"local-{name}.exr"))
            self.watch(jobs[name])
            farm = self.path(f"farm-{name}.exr")
            self.fetch(jobs[name], farm)
            stored = same_image(farm, local)
            mean = mean_of(read_exr(farm), "R")
            check(mean > 0, f"the {name} image is black")
            self.results[f"a: {name} job = local render"] = (
                f"bit-identical pixels (mean R {mean:.4f}); stored chunks "
                f"{'byte-identical' if stored else 'differ'}")

    def task_overhead(self, job):
        """Per task, the mean seconds a worker spent on it but not rendering (from its lease to
        its result accepted, minus the render time the worker logs) and the mean wait from a
        result to the worker's next lease."""
        render = {}
        for name in os.listdir(self.dir):
            if name.startswith("w") and name.endswith(".log"):
                for m in re.finditer(rf"job={re.escape(job)} task=(\d+) done in ([\d.]+) s",
                                     open(self.path(name)).read()):
                    render[int(m.group(1))] = float(m.group(2))
        events = [(t, task, host, "lease") for t, task, host, _ in self.leases(job)]
        for line in self.server_log().splitlines():
            m = re.search(rf"job={re.escape(job)} task=(\d+) done by (\S+) ", line)
            if m:
                pid = int(m.group(2).rsplit("-", 1)[-1])
                events.append((self.stamp(line), int(m.group(1)), self.pid_host.get(pid), "done"))
        events.sort()
        lease_at, last_done, busy, gaps = {}, {}, [], []
        for t, task, host, kind in events:
            if kind == "lease":
                lease_at[(task, host)] = t
                if host in last_done:
                    gaps.append(t - last_done.pop(host))
            elif (task, host) in lease_at and task in render:
                busy.append(t - lease_at[(task, host)] - render[task])
                last_done[host] = t
        mean = lambda v: sum(v) / len(v) if v else float("nan")
        return mean(busy), mean(gaps)

    def part_b_throughput(self, job_u, t_u, local):
        """The job completes over shaped links with the pixels of `lightfarm render`. Its
        throughput against the unconstrained run is printed only: on this shared machine one run
        can be 15% off, so a bound on the ratio fails with the farm working as it should."""
        log(f"(b) throughput over {RATE} links, +{DELAY * 1e3:.0f} ms each way")
        proxied = f"{HOSTS['server']}:{PROXY_PORT}"
        proxy = self.start_proxy()
        over = {"unconstrained": self.task_overhead(job_u)}
        self.shape(True)
        for host in ("w1", "w2"):
            self.start_worker(host, port=PROXY_PORT)
        job_c, t_c = self.timed_job(BIG_FLAGS, server=proxied)
        out = self.path("farm-constrained.exr")
        self.fetch(job_c, out, server=proxied)
        same_image(out, local)
        _, hs_slow = self.handshake_ms(PROXY_PORT, n=3)
        over["constrained"] = self.task_overhead(job_c)
        self.stop(proxy)
        self.shape(False)
        samples = 256 * 256 * 256
        self.results["b: TLS handshake, shaped and delayed"] = (
            f"{hs_slow:.1f} ms (each round trip 100 ms more)")
        self.results["b: unconstrained, submit -> succeeded"] = (
            f"{t_u:.2f} s: {samples / t_u / 1e6:.2f} M samples/s")
        self.results[f"b: {RATE} + {DELAY * 1e3:.0f} ms each way"] = (
            f"{t_c:.2f} s: {samples / t_c / 1e6:.2f} M samples/s; pixels of lightfarm render")
        self.results["b: ratio constrained / unconstrained"] = f"{t_u / t_c:.2f} (not checked)"
        for name, (busy, gap) in over.items():
            self.results[f"b: per task, not rendering ({name})"] = (
                f"{busy * 1e3:.0f} + {gap * 1e3:.0f} ms "
                "(lease to result minus render + result to next lease)")

    def part_c_cut_worker(self, reference):
        log("(c) a worker's link cut mid-job")
        job = self.submit(BIG_FLAGS)
        # Cut w1 once it holds a lease and has rendered a little of it.
        _, task, _, _ = self.wait_for(
            lambda: next((l for l in self.leases(job) if l[2] == "w1"), None), 60,
            "w1 to lease a task")
        time.sleep(0.3)
        t_cut = time.time()
        self.link("w1", False)
        log(f"    w1's link down while it renders task {task}")
        releases = self.wait_for(
            lambda: [l for l in self.leases(job) if l[1] == task and l[3] > 1], 60,
            f"task {task} to be leased again")
        t_re, _, again_to, _ = releases[0]
        check(again_to == "w2", f"task {task} went again to {again_to}")
        self.watch(job)
        out = self.path("farm-cut.exr")
        self.fetch(job, out)
        same_image(out, reference)
        self.results["c: cut -> task re-leased to w2"] = (
            f"{t_re - t_cut:.2f} s (--lease-seconds {LEASE_SECONDS})")
        self.results["c: image with w1 cut = uncut image"] = "bit-identical pixels"
        # The link back: w1 leases again.
        t_up = time.time()
        self.link("w1", True)
        # Small jobs, one after another, until w1 takes a task of one: w2 may render a whole job
        # before w1 has noticed that its old connection is dead (keepalive: up to 15 s).
        deadline = time.monotonic() + 90
        seed = 13
        while True:
            job2 = self.submit(REJOIN_FLAGS.replace("--seed 13", f"--seed {seed}"))
            self.watch(job2)
            w1_again = [l for l in self.leases(job2) if l[2] == "w1"]
            if w1_again:
                break
            if time.monotonic() > deadline:
                tail = ""
                if os.path.exists(self.path("w1.log")):
                    with open(self.path("w1.log")) as f:
                        tail = "".join(f.readlines()[-15:])
                raise Failed("w1 did not lease again within 90 s after its link came back; "
                             f"its log ends:\n{tail}")
            seed += 1
        self.results["c: link up -> w1 leases again"] = (
            f"{w1_again[0][0] - t_up:.2f} s ({len(w1_again)} tasks of {job2})")

    def part_d_server_outage(self):
        log(f"(d) the server's link cut for {OUTAGE_SECONDS} s")
        job = self.submit(OUTAGE_FLAGS)
        argv = [os.path.join(self.bin, "lightfarm"), "watch", job, "--server", self.addr,
                "--tls-ca", self.path("ca.crt"), "--token-file", self.path("alice.token"),
                "--retry-seconds", "180"]
        watch = self.spawn("client", argv, "outage-watch")
        self.wait_for(lambda: re.search(rf"job={re.escape(job)} task=\d+ done by",
                                        self.server_log()), 60, "a first task done")
        t_cut = time.monotonic()
        self.link("server", False)
        time.sleep(OUTAGE_SECONDS)
        self.link("server", True)
        t_up, t_up_wall = time.monotonic(), time.time()
        log("    link back up")
        try:
            rc = watch.wait(240)
        except subprocess.TimeoutExpired:
            raise Failed("watch did not end within 240 s of the link coming back")
        t_end = time.monotonic()
        self.procs.remove(watch)
        check(rc == 0, f"watch exited {rc}: {open(watch.log_path).read()[-1500:]}")
        wlog = open(watch.log_path).read()
        out = self.path("farm-outage.exr")
        self.fetch(job, out)
        same_image(out, self.render_local(OUTAGE_FLAGS, self.path("local-outage.exr")))
        done_after = [l for l in self.leases(job) if l[0] > time.time() - (t_end - t_up)]
        self.results["d: outage"] = f"{t_up - t_cut:.0f} s, watch exit 0, image = local"
        self.results["d: link up -> job succeeded"] = (
            f"{t_end - t_up:.1f} s ({len({l[2] for l in done_after})} workers leased after)")
        said = [ln for ln in wlog.splitlines() if "retry" in ln.lower()]
        check(said, "watch said nothing about the outage")
        self.results["d: watch said during the outage"] = last_line(said[-1])
        # gRPC's reconnect back-off, not the link, sets how soon each worker is back.
        for host in ("w1", "w2"):
            back = [self.stamp(ln) for ln in open(self.workers[host].log_path)
                    if "server reachable again" in ln]
            back = [t for t in back if t and t > t_up_wall]
            self.results[f"d: link up -> {host} reaches the server"] = (
                f"{back[0] - t_up_wall:.1f} s" if back else
                f"not within {t_end - t_up:.0f} s, when the job ended (gRPC reconnect back-off)")

    def run(self):
        why = self.probe()
        if why:
            print(f"SKIP: {why}", flush=True)
            return SKIP
        log(f"namespaces {self.prefix}*, files in {self.dir}")
        self.network()
        self.certificates()
        self.tokens()
        self.start_server()
        self.start_worker("w1")
        self.start_worker("w2")
        self.part_e_refusals()
        self.start_worker("w2")
        self.part_tls_cost()
        self.part_a_identity()

        log("(b) throughput, unconstrained")
        job_u, t_u = self.timed_job(BIG_FLAGS)
        reference = self.path("farm-unconstrained.exr")
        self.fetch(job_u, reference)
        self.render_local(BIG_FLAGS, self.path("local-big.exr"))
        same_image(reference, self.path("local-big.exr"))

        self.part_c_cut_worker(reference)
        self.part_d_server_outage()

        self.part_b_throughput(job_u, t_u, self.path("local-big.exr"))
        return 0

    def cleanup(self):
        for p in list(self.procs):
            try:
                self.stop(p, wait=5)
            except Exception:
                pass
        for ns in reversed(self.made_ns):
            subprocess.run(["ip", "netns", "del", ns], capture_output=True)
        if not self.keep:
            shutil.rmtree(self.dir, ignore_errors=True)

    def summary(self):
        if not self.results:
            return
        width = max(len(k) for k in self.results)
        print("\n" + "measured".ljust(width) + " | value")
        print("-" * width + "-|-" + "-" * 40)
        for k, v in self.results.items():
            print(k.ljust(width) + " | " + v)
        print(flush=True)


def unauthenticated(text):
    """The CLI prints the server's message, not the status code's name: these are the
    UNAUTHENTICATED messages of server/src/auth.cc."""
    return any(m in text for m in ("UNAUTHENTICATED", "not one of this server's",
                                   "requires a token", "was revoked"))


def last_line(text):
    lines = [ln for ln in text.strip().splitlines() if ln.strip()]
    return lines[-1].strip()[:200] if lines else "(no output)"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bin-dir", default="build/bin")
    parser.add_argument("--scenes", default="tests/scenes")
    parser.add_argument("--keep", action="store_true", help="keep the temporary folder")
    parser.add_argument("--proxy", nargs=3, metavar=("LISTEN", "TARGET", "DELAY"))
    args = parser.parse_args()
    if args.proxy:
        try:
            asyncio.run(_proxy_main(args.proxy[0], args.proxy[1], float(args.proxy[2])))
        except KeyboardInterrupt:
            pass
        return 0
    farm = Farm(args)
    # A SIGTERM (ctest's timeout) still cleans up.
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    t0 = time.monotonic()
    try:
        rc = farm.run()
    except Failed as e:
        print(f"FAILED: {e}", flush=True)
        rc = 1
    finally:
        farm.summary()
        if farm.server is not None:
            print(f"(logs in {farm.dir}{'' if farm.keep else ', removed'})")
        farm.cleanup()
    log(f"done in {time.monotonic() - t0:.0f} s")
    return rc


if __name__ == "__main__":
    sys.exit(main())

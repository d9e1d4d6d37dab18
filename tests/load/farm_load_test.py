#!/usr/bin/env python3
"""The coordinator's resource limits under attack (issue 27): a hostile load test.

A real lightfarm-server (tokens: admin, submitters alice and mallory, worker tokens w1, w2, w3
and rogue), two honest lightfarm-workers and an honest client (alice) submitting a handful of
small jobs, waiting for them and fetching their results. The honest phase runs once quietly,
then again while these attacks run:

  1. three unauthenticated ListJobs calls, each with a 300 MB page_token;
  2. two chunked POST /api/session bodies of 300 MB each;
  3. mallory submits a glTF scene whose camera (and, in a second scene, a light) sits at 1e308;
  4. the rogue worker token leases under a fresh worker_id each time and never answers, and
     heartbeats, fails and leases under the id of another token's worker (w3, run by the test);
  5. slowloris on the HTTP port (20 connections, a header line every 3 s) while /healthz is probed;
  6. mallory holds 24 stalled uploads and 300 WatchJob streams while alice uploads and watches;
  7. mallory opens 400 FetchResult streams of a 512x512 result, reads one chunk of each and stops;
  8. mallory submits with alice's request_id.

Attacks 1, 2 and 7 run one after another, each in its own window, so the server's peak resident
memory in the window (VmHWM, reset through /proc/PID/clear_refs) minus its resident memory before
it is that attack's cost; the others run throughout. The server's VmRSS/VmHWM, threads and open
file descriptors are sampled every 50 ms. A worker that dies is restarted, as its supervisor
would, and counted. Printed: each attack's outcome, peak resident memory, peak threads and fds,
honest jobs failed, the honest makespan without and with the attacks. Checked: peak resident
memory below 1 GB, every honest job succeeds (submitted, SUCCEEDED, fetched) with no counted task
failure, /healthz answers at the end, and each attack is refused or contained (one line each).

  PYTHONPATH=build/python python3 tests/load/farm_load_test.py --bin-dir build/bin \\
      --scenes tests/scenes

Exits 0 when every check holds, 1 otherwise (a list of the failed checks ends the output).
"""

import argparse
import hashlib
import json
import os
import re
import secrets
import select
import shutil
import socket
import subprocess
import sys
import tempfile
import threading
import time

import grpc

import lightfarm
from lightfarm.v1 import job_service_pb2 as jpb
from lightfarm.v1 import job_service_pb2_grpc as jgrpc
from lightfarm.v1 import worker_service_pb2 as wpb
from lightfarm.v1 import worker_service_pb2_grpc as wgrpc
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'support'))
from processes import stop_all  # noqa: E402  (tests/support)

MIB = 1 << 20  # payload sizes
MB = 1_000_000  # what is reported and checked
PEAK_LIMIT = 1000 * MB  # "the server stays below 1 GB"
# What one attack may add to the server's resident memory: the issue asks that no call without
# a valid token make it hold more than a few MB; a cap with bounded buffering keeps stalled
# readers to a few MB each for a few streams.
UNAUTHENTICATED_RISE_LIMIT = 64 * MB
STALLED_READERS_RISE_LIMIT = 128 * MB
# The rogue worker token's leases held at once (leased in the last lease time and never
# answered): the attack took 600 in 3 s. lightfarm-server's --max-leases-per-token
# default caps them.
ROGUE_LEASES_LIMIT = 256
ROGUE_THREADS = 2
LEASE_SECONDS = 3
HONEST_JOBS = 4
HONEST_DEADLINE = 60  # seconds for the honest phase under attack; its jobs fail after that
ATTACK_SECONDS = 20  # the longest a memory attack (1, 2) sends
SLOTS_SECONDS = 30  # how long mallory holds her uploads and watches (6)
# glibc gives freed memory back at once (a fixed mmap threshold, trimming down to 128 KiB), so
# that what one attack's window leaves allocated-but-free does not hide the next one's cost.
MALLOC_ENV = dict(os.environ, MALLOC_MMAP_THRESHOLD_="131072", MALLOC_TRIM_THRESHOLD_="131072")
HONEST_PARAMS = dict(resolution=(64, 64), spp=64, tile=16)


def log(msg):
    print(f"[{time.strftime('%H:%M:%S')}] {msg}", flush=True)


class Checks:
    """Named assertions: each prints ok/FAIL with its message; the test fails if any failed."""

    def __init__(self):
        self.failed = []

    def check(self, cond, msg):
        print(f"{'ok  ' if cond else 'FAIL'}: {msg}", flush=True)
        if not cond:
            self.failed.append(msg)


# ---- processes ----------------------------------------------------------------------------------

class Farm:
    def __init__(self, bin_dir, scenes, dir):
        self.bin_dir, self.scenes, self.dir = bin_dir, scenes, dir
        self.data = os.path.join(dir, "data")
        os.makedirs(self.data)
        self.server = None
        self.workers = {}  # name -> Popen
        self.worker_deaths = []  # (name, returncode)
        self.stopping = False
        self.lock = threading.Lock()

    def bin(self, name):
        return os.path.join(self.bin_dir, name)

    def token(self, name, role):
        out = subprocess.run([self.bin("lightfarm-server"), "token", "create", "--data-dir",
                              self.data, "--name", name, "--role", role],
                             check=True, capture_output=True, text=True).stdout
        token = out.strip().splitlines()[-1].strip()
        path = os.path.join(self.dir, f"{name}.token")
        with open(path, "w") as f:
            f.write(token + "\n")
        os.chmod(path, 0o600)
        return token, path

    def start_server(self):
        self.server_log = open(os.path.join(self.dir, "server.log"), "w")
        self.server = subprocess.Popen(
            [self.bin("lightfarm-server"), "--listen", "127.0.0.1:0", "--http", "127.0.0.1:0",
             "--data-dir", self.data, "--lease-seconds", str(LEASE_SECONDS)],
            stdout=subprocess.PIPE, stderr=self.server_log, text=True, env=MALLOC_ENV)
        grpc_addr = http_addr = None
        deadline = time.time() + 30
        while (grpc_addr is None or http_addr is None) and time.time() < deadline:
            line = self.server.stdout.readline()
            if not line:
                break
            if m := re.match(r"listening on ([\d.]+:\d+)", line):
                grpc_addr = m.group(1)
            if m := re.match(r"http on ([\d.]+:\d+)", line):
                http_addr = m.group(1)
        if grpc_addr is None or http_addr is None:
            raise RuntimeError("lightfarm-server did not say its ports:\n" + self.server_tail())
        threading.Thread(target=self.server.stdout.read, daemon=True).start()
        self.grpc_addr = grpc_addr
        host, port = http_addr.rsplit(":", 1)
        self.http = (host, int(port))

    def server_tail(self, n=30):
        self.server_log.flush()
        with open(os.path.join(self.dir, "server.log")) as f:
            return "".join(f.readlines()[-n:])

    def start_worker(self, name, token_file):
        log_file = open(os.path.join(self.dir, f"{name}.log"), "a")
        self.workers[name] = (subprocess.Popen(
            [self.bin("lightfarm-worker"), "--server", self.grpc_addr, "--token-file", token_file,
             "--name", name, "--threads", "1", "--cache-dir",
             os.path.join(self.dir, f"cache-{name}")],
            stdout=log_file, stderr=log_file), token_file)

    def supervise(self):
        """Restarts a worker that died (as systemd's Restart= would) and counts it."""
        while not self.stopping:
            with self.lock:
                for name, (proc, token_file) in list(self.workers.items()):
                    if proc.poll() is not None and not self.stopping:
                        self.worker_deaths.append((name, proc.returncode))
                        log(f"worker {name} died (rc {proc.returncode}); restarting it")
                        self.start_worker(name, token_file)
            time.sleep(0.2)

    def stop(self):
        self.stopping = True
        with self.lock:
            procs = [p for p, _ in self.workers.values()] + ([self.server] if self.server else [])
        stop_all(procs)


class Sampler:
    """The server's VmRSS/VmHWM, threads and open fds every 50 ms. `window()` resets VmHWM
    (clear_refs 5) so that the peak of one attack's window is read exactly."""

    def __init__(self, pid):
        self.pid = pid
        self.peak_rss = self.peak_threads = self.peak_fds = 0
        self.rss = 0
        self.lock = threading.Lock()
        self.stopped = threading.Event()
        self.thread = threading.Thread(target=self.run, daemon=True)
        self.thread.start()

    def status(self):
        out = {}
        with open(f"/proc/{self.pid}/status") as f:
            for line in f:
                key, _, value = line.partition(":")
                if key in ("VmRSS", "VmHWM"):
                    out[key] = int(value.split()[0]) * 1024
                elif key == "Threads":
                    out[key] = int(value)
        return out

    def sample(self):
        try:
            s = self.status()
            fds = len(os.listdir(f"/proc/{self.pid}/fd"))
        except (FileNotFoundError, ProcessLookupError):
            return None
        with self.lock:
            self.rss = s["VmRSS"]
            self.peak_rss = max(self.peak_rss, s["VmHWM"], s["VmRSS"])
            self.peak_threads = max(self.peak_threads, s["Threads"])
            self.peak_fds = max(self.peak_fds, fds)
        return s

    def run(self):
        while not self.stopped.wait(0.05):
            self.sample()

    def settle(self, seconds=10):
        """Waits, at most `seconds`, until the resident memory stops falling: what an earlier
        window left is given back before the next one starts."""
        end = time.time() + seconds
        last = self.status()["VmRSS"]
        while time.time() < end:
            time.sleep(0.5)
            now = self.status()["VmRSS"]
            if now > last - 2 * MB:
                return
            last = now

    def reset_hwm(self):
        """Takes the peak so far into peak_rss, resets VmHWM and returns VmRSS now."""
        with self.lock:
            s = self.status()
            self.peak_rss = max(self.peak_rss, s["VmHWM"])
            with open(f"/proc/{self.pid}/clear_refs", "w") as f:
                f.write("5")
            return self.status()["VmRSS"]

    def hwm(self):
        s = self.sample()
        return s["VmHWM"] if s else 0

    def stop(self):
        self.stopped.set()
        self.thread.join()
        self.sample()


# ---- helpers ------------------------------------------------------------------------------------

def channel(addr):
    # Its own connection: Python's channels otherwise share one per target.
    return grpc.insecure_channel(addr, options=[("grpc.use_local_subchannel_pool", 1),
                                                ("grpc.max_send_message_length", -1),
                                                ("grpc.max_receive_message_length", -1)])


def bearer(token):
    return (("authorization", f"Bearer {token}"),)


def http_get(addr, path, timeout):
    """Status code of GET path, or the reason there was none."""
    try:
        with socket.create_connection(addr, timeout=timeout) as s:
            s.settimeout(timeout)
            s.sendall(f"GET {path} HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n".encode())
            data = s.recv(256)
        m = re.match(rb"HTTP/1\.[01] (\d+)", data)
        return int(m.group(1)) if m else f"no answer ({data[:40]!r})"
    except OSError as e:
        return f"{type(e).__name__}: {e}"


def scene_variant(farm, base_text, tag):
    """cornell_box.json with `tag` spaces added: the same scene, a new blob to upload."""
    path = os.path.join(farm.dir, f"cornell_{tag}.json")
    with open(path, "w") as f:
        f.write(base_text + " " * tag)
    return path


# ---- the honest client --------------------------------------------------------------------------

class HonestRun:
    """Alice submits HONEST_JOBS jobs (each scene a new upload), waits for each with WatchJob
    (polling GetJob when a watch is refused) and fetches each result."""

    def __init__(self, farm, token, base_text, first_tag, request_id=None, held=None):
        self.farm, self.token, self.base_text, self.first_tag = farm, token, base_text, first_tag
        self.request_id = request_id
        # Set when mallory lets go of her uploads (6): was alice's first upload in before?
        self.held = held
        self.first_in_while_held = None
        self.first_seconds = None
        self.submitted = threading.Event()
        self.job_ids, self.outcomes = [], {}
        self.upload_refusals, self.watch_refusals, self.fetch_errors = [], [], []
        self.makespan = None

    def run(self, deadline):
        start = time.time()
        client = lightfarm.Client(self.farm.grpc_addr, token=self.token, retry_seconds=10)
        try:
            for i in range(HONEST_JOBS):
                path = scene_variant(self.farm, self.base_text, self.first_tag + i)
                rid = self.request_id if i == 0 and self.request_id else None
                while True:
                    try:
                        self.job_ids.append(client.submit(path, name=f"honest-{self.first_tag + i}",
                                                          request_id=rid, **HONEST_PARAMS))
                        if self.first_seconds is None:
                            self.first_seconds = time.time() - start
                            if self.held is not None:
                                self.first_in_while_held = not self.held.is_set()
                        break
                    except lightfarm.ResourceExhausted as e:
                        self.upload_refusals.append(str(e))
                        if time.time() > deadline:
                            self.outcomes[f"(submission {i})"] = f"not submitted: {e}"
                            break
                        time.sleep(1)
                    except lightfarm.LightfarmError as e:
                        self.outcomes[f"(submission {i})"] = f"not submitted: {e}"
                        break
                self.submitted.set()
            threads = [threading.Thread(target=self.follow, args=(client, j, deadline))
                       for j in self.job_ids]
            for t in threads:
                t.start()
            for t in threads:
                t.join()
        finally:
            self.submitted.set()
            client.close()
        self.makespan = time.time() - start

    def follow(self, client, job_id, deadline):
        state = None
        try:
            for progress in client.watch(job_id):
                state = progress.job
        except lightfarm.LightfarmError as e:
            self.watch_refusals.append(f"{job_id}: {e}")
        while (state is None or not state.state.final) and time.time() < deadline:
            try:
                state = client.get(job_id)
            except lightfarm.LightfarmError:
                pass
            time.sleep(0.3)
        if state is None or not state.state.final:
            self.outcomes[job_id] = "did not end in time"
            return
        if state.state != lightfarm.JobState.SUCCEEDED:
            self.outcomes[job_id] = f"{state.state.name}: {state.error}"
            return
        try:
            client.fetch(job_id, os.path.join(self.farm.dir, f"{job_id}.exr"))
            self.outcomes[job_id] = "SUCCEEDED"
        except lightfarm.LightfarmError as e:
            self.fetch_errors.append(f"{job_id}: {e}")
            self.outcomes[job_id] = f"succeeded but not fetched: {e}"

    def failed(self):
        return {j: o for j, o in self.outcomes.items() if o != "SUCCEEDED"}


def task_failures(admin, job_ids, exclude=()):
    """Counted failures of the jobs' tasks, but for the (job, task) pairs in exclude."""
    total = 0
    for job_id in job_ids:
        try:
            tasks = admin.ListTasks(jpb.ListTasksRequest(job_id=job_id), timeout=10).tasks
        except grpc.RpcError:
            continue
        total += sum(t.failures for t in tasks if (job_id, t.index) not in exclude)
    return total


# ---- the attacks --------------------------------------------------------------------------------

def attack_huge_unauthenticated(farm, sampler, out):
    """(1) Three ListJobs calls with no token and a 300 MB page_token each, at once, for at
    most ATTACK_SECONDS (a loaded machine sends them slowly)."""
    sampler.settle()
    before = sampler.reset_hwm()
    start = time.time()
    codes = []

    def one():
        ch = channel(farm.grpc_addr)
        try:
            jgrpc.JobServiceStub(ch).ListJobs(jpb.ListJobsRequest(page_token="x" * (300 * MIB)),
                                              timeout=ATTACK_SECONDS)
            codes.append("OK")
        except grpc.RpcError as e:
            codes.append(e.code().name)
        finally:
            ch.close()

    threads = [threading.Thread(target=one) for _ in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    out.update(codes=sorted(codes), rise=sampler.hwm() - before, before=before,
               seconds=time.time() - start)


def attack_chunked_session(farm, sampler, out):
    """(2) Two chunked POST /api/session bodies of 300 MB each, at once, each sent for at most
    ATTACK_SECONDS."""
    sampler.settle()
    before = sampler.reset_hwm()
    answers = []
    chunk = b"a" * MIB
    frame = b"%x\r\n" % len(chunk) + chunk + b"\r\n"

    def one():
        sent = 0
        try:
            with socket.create_connection(farm.http, timeout=30) as s:
                s.sendall(b"POST /api/session HTTP/1.1\r\nHost: x\r\nContent-Type: application/json"
                          b"\r\nTransfer-Encoding: chunked\r\n\r\n")
                end = time.time() + ATTACK_SECONDS
                try:
                    while sent < 300 and time.time() < end:
                        s.sendall(frame)
                        sent += 1
                    s.sendall(b"0\r\n\r\n")
                except OSError:
                    pass  # the server stopped reading: what a limit does
                try:
                    data = s.recv(256)
                    m = re.match(rb"HTTP/1\.[01] (\d+)", data)
                    status = int(m.group(1)) if m else "closed without an answer"
                except OSError as e:
                    status = f"{type(e).__name__}"
        except OSError as e:
            status = f"{type(e).__name__}: {e}"
        answers.append((status, sent))

    threads = [threading.Thread(target=one) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    out.update(answers=answers, rise=sampler.hwm() - before, before=before)


def attack_gltf(farm, mallory_token, out):
    """(3) glTF scenes with the camera, then a light, at 1e308, submitted by mallory."""
    src = os.path.join(farm.scenes, "gltf_demo")
    results = {}
    for what, node in (("camera", "Camera"), ("light", "Spot")):
        d = os.path.join(farm.dir, f"gltf_{what}")
        os.makedirs(d)
        shutil.copy(os.path.join(src, "checker.png"), d)
        with open(os.path.join(src, "demo.gltf")) as f:
            gltf = json.load(f)
        for n in gltf["nodes"]:
            if n.get("name") == node:
                n["translation"] = [0, 2.5, 1e308]
        path = os.path.join(d, "demo.gltf")
        with open(path, "w") as f:
            json.dump(gltf, f)
        with lightfarm.Client(farm.grpc_addr, token=mallory_token, retry_seconds=0) as c:
            try:
                results[what] = ("accepted", c.submit(path, resolution=(32, 32), spp=1, tile=16,
                                                      name=f"overflow-{what}"))
            except lightfarm.LightfarmError as e:
                results[what] = (e.code.name, e.message[:160])
    out.update(results=results)


def server_version(farm, token):
    """The build a worker must claim, as the server's refusal of a worker without one says."""
    ch = channel(farm.grpc_addr)
    try:
        wgrpc.WorkerServiceStub(ch).LeaseTask(wpb.LeaseTaskRequest(worker_id="probe", wait_ms=0),
                                              timeout=5, metadata=bearer(token))
        return ""
    except grpc.RpcError as e:
        m = re.search(r"server version (.+?): run workers", e.details() or "")
        return m.group(1) if m else ""
    finally:
        ch.close()


def attack_leases(farm, rogue_token, w3_token, stop, out):
    """(4) The rogue worker token leases under a fresh worker_id each time and never answers
    (two threads until `stop`), and claims the id of w3's worker, which the test runs."""
    version = server_version(farm, rogue_token)
    granted = []  # (time, lease_id, job_id, task_index)
    refused = {}
    lock = threading.Lock()

    def steal():
        ch = channel(farm.grpc_addr)
        stub = wgrpc.WorkerServiceStub(ch)
        while not stop.is_set():
            try:
                r = stub.LeaseTask(wpb.LeaseTaskRequest(worker_id=f"rogue-{secrets.token_hex(8)}",
                                                        wait_ms=500, name="rogue",
                                                        version=version),
                                   timeout=5, metadata=bearer(rogue_token))
                if r.HasField("task"):
                    with lock:
                        granted.append((time.time(), r.task.lease_id, r.task.job_id,
                                        r.task.task_index))
            except grpc.RpcError as e:
                with lock:
                    refused[e.code().name] = refused.get(e.code().name, 0) + 1
                time.sleep(0.05)
        ch.close()

    threads = [threading.Thread(target=steal) for _ in range(ROGUE_THREADS)]
    for t in threads:
        t.start()

    # The victim: w3's worker (its own token) leases a task and heartbeats it; the rogue, which
    # knows its lease id, heartbeats and fails that lease and leases under w3's worker id.
    forged = {}
    ch = channel(farm.grpc_addr)
    stub = wgrpc.WorkerServiceStub(ch)
    victim_id = f"w3-{os.getpid()}"
    task = None
    end = time.time() + 20
    while task is None and time.time() < end and not stop.is_set():
        try:
            r = stub.LeaseTask(wpb.LeaseTaskRequest(worker_id=victim_id, wait_ms=2000, name="w3",
                                                    version=version),
                               timeout=5, metadata=bearer(w3_token))
            task = r.task if r.HasField("task") else None
        except grpc.RpcError as e:
            forged["victim lease"] = e.code().name
            time.sleep(0.2)
    if task is not None:
        stub.Heartbeat(wpb.HeartbeatRequest(lease_id=task.lease_id, worker_id=victim_id),
                       timeout=5, metadata=bearer(w3_token))
        # A worker is its token and the id it claims: the rogue's calls under w3's id act for
        # a worker of the rogue's own, so they may succeed, but must not touch w3's lease.
        for name, call, req in (
                ("Heartbeat", stub.Heartbeat,
                 wpb.HeartbeatRequest(lease_id=task.lease_id, worker_id=victim_id)),
                ("FailTask", stub.FailTask,
                 wpb.FailTaskRequest(lease_id=task.lease_id, worker_id=victim_id,
                                     reason="forged by the rogue token")),
                ("LeaseTask", stub.LeaseTask,
                 wpb.LeaseTaskRequest(worker_id=victim_id, wait_ms=0, name="w3",
                                      version=version))):
            try:
                r = call(req, timeout=5, metadata=bearer(rogue_token))
                forged[name] = "cancelled" if name == "Heartbeat" and r.cancelled else "OK"
            except grpc.RpcError as e:
                forged[name] = e.code().name
        try:
            r = stub.Heartbeat(wpb.HeartbeatRequest(lease_id=task.lease_id, worker_id=victim_id),
                               timeout=5, metadata=bearer(w3_token))
            forged["w3's lease after"] = "cancelled" if r.cancelled else "kept"
        except grpc.RpcError as e:
            forged["w3's lease after"] = e.code().name
        # The victim lets go of its lease (a counted failure of that task, excluded below).
        try:
            stub.FailTask(wpb.FailTaskRequest(lease_id=task.lease_id, worker_id=victim_id,
                                              reason="load test: w3 lets go of its lease"),
                          timeout=5, metadata=bearer(w3_token))
        except grpc.RpcError:
            pass
    ch.close()
    for t in threads:
        t.join()
    # Leases held at once: those granted within one lease time of each other (never answered).
    held, first = 0, 0
    for last, (t, *_) in enumerate(granted):
        while granted[first][0] <= t - LEASE_SECONDS:
            first += 1
        held = max(held, last - first + 1)
    out.update(granted=len(granted), held=held, refused=refused, forged=forged,
               victim_task=(task.job_id, task.task_index) if task is not None else None,
               lease_ids=[g[1] for g in granted[:3]],
               short_ids=sum(1 for g in granted if len(g[1]) < 16))


def attack_slowloris(farm, stop, out):
    """(5) 20 connections sending one header line every 3 s (each one the server closes is
    opened again), while /healthz is probed each second with a 2 s timeout (a kubelet's is 1 s)
    from the 2nd second on."""
    def connect():
        try:
            s = socket.create_connection(farm.http, timeout=5)
            s.sendall(b"GET /healthz HTTP/1.1\r\nHost: x\r\n")
            return s
        except OSError:
            return None

    socks = [connect() for _ in range(20)]
    reopened = 0

    def drip():
        nonlocal reopened
        while not stop.wait(3):
            for i, s in enumerate(socks):
                try:
                    if s is None or select.select([s], [], [], 0)[0]:
                        raise OSError("closed by the server")
                    s.sendall(b"X-Slow: %d\r\n" % int(time.time()))
                except OSError:
                    if s is not None:
                        s.close()
                    socks[i] = connect()
                    reopened += 1

    dripper = threading.Thread(target=drip)
    dripper.start()
    probes = []
    stop.wait(2)
    while not stop.is_set():
        probes.append(http_get(farm.http, "/healthz", 2))
        stop.wait(1)
    dripper.join()
    for s in socks:
        if s is not None:
            s.close()
    out.update(connections=len(socks), reopened=reopened, probes=len(probes),
               answered=sum(1 for p in probes if p == 200),
               unanswered=[p for p in probes if p != 200][:3])


def attack_slots(farm, mallory_token, out, ready):
    """(6) Mallory's 24 stalled uploads and 300 WatchJob streams on her long job, held for
    SLOTS_SECONDS or until `out['release']` is set."""
    release = out["release"]
    channels = [channel(farm.grpc_addr) for _ in range(8)]
    stubs = [jgrpc.JobServiceStub(c) for c in channels]
    upload_codes, watch_codes = {}, {}
    futures = []

    def stalled_upload():
        data = secrets.token_bytes(10 * MIB)
        digest = hashlib.sha256(data).hexdigest()
        yield jpb.UploadBlobRequest(hash=digest, size=len(data), offset=0, data=data[:64 << 10])
        release.wait()

    for i in range(24):
        futures.append(stubs[i % 8].UploadBlob.future(stalled_upload(), timeout=120,
                                                      metadata=bearer(mallory_token)))
    streams = []
    for i in range(300):
        streams.append(stubs[i % 8].WatchJob(jpb.WatchJobRequest(job_id=out["job"]), timeout=120,
                                             metadata=bearer(mallory_token)))
    watching = 0
    for s in streams:
        try:
            next(s)
            watching += 1
        except grpc.RpcError as e:
            watch_codes[e.code().name] = watch_codes.get(e.code().name, 0) + 1
        except StopIteration:
            pass
    time.sleep(1)
    for f in futures:
        if f.done():
            try:
                f.result()
                code = "OK"
            except grpc.RpcError as e:
                code = e.code().name
            upload_codes[code] = upload_codes.get(code, 0) + 1
    out.update(uploads_refused=upload_codes, uploads_held=24 - sum(upload_codes.values()),
               watching=watching, watches_refused=watch_codes)
    ready.set()
    release.wait(SLOTS_SECONDS)
    release.set()
    for s in streams:
        s.cancel()
    for f in futures:
        f.cancel()
    for c in channels:
        c.close()


def attack_stalled_readers(farm, sampler, mallory_token, job_id, out):
    """(7) 400 FetchResult streams of mallory's 512x512 result that read one chunk and stop
    (each waits at most ATTACK_SECONDS for its first chunk), held for 4 s more."""
    sampler.settle()
    before = sampler.reset_hwm()
    channels = [channel(farm.grpc_addr) for _ in range(8)]
    stubs = [jgrpc.JobServiceStub(c) for c in channels]
    codes, reading = {}, []
    lock = threading.Lock()
    streams = [stubs[i % 8].FetchResult(jpb.FetchResultRequest(job_id=job_id),
                                        timeout=ATTACK_SECONDS + 10,
                                        metadata=bearer(mallory_token)) for i in range(400)]
    end = time.time() + ATTACK_SECONDS

    def first_chunks(part):
        for s in part:
            if time.time() > end:
                s.cancel()
            try:
                next(s)
                with lock:
                    reading.append(s)
            except grpc.RpcError as e:
                with lock:
                    codes[e.code().name] = codes.get(e.code().name, 0) + 1
            except StopIteration:
                pass

    threads = [threading.Thread(target=first_chunks, args=(streams[i::8],)) for i in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    time.sleep(4)  # the stalled readers hold what they hold
    rise = sampler.hwm() - before
    for s in streams:
        s.cancel()
    for c in channels:
        c.close()
    out.update(reading=len(reading), refused=codes, rise=rise, before=before)


def attack_request_id(farm, mallory_token, alice_token, honest, out):
    """(8) Mallory submits with the request_id of alice's first job of the attacked phase."""
    honest.submitted.wait(60)
    if not honest.job_ids:
        out.update(result="alice submitted nothing")
        return
    alice_job = honest.job_ids[0]
    # The scene of her watched job: stored already, so no upload of hers is in the way.
    path = scene_variant(farm, honest.base_text, 501)
    with lightfarm.Client(farm.grpc_addr, token=mallory_token, retry_seconds=0) as c:
        try:
            got = c.submit(path, resolution=(16, 16), spp=1, tile=16, name="reused-request-id",
                           request_id=honest.request_id)
        except lightfarm.LightfarmError as e:
            out.update(result=f"refused: {e}", got=None, alice_job=alice_job)
            return
        try:
            c.get(got)
            visible = "OK"
        except lightfarm.LightfarmError as e:
            visible = e.code.name
    with lightfarm.Client(farm.grpc_addr, token=alice_token, retry_seconds=0) as c:
        owner = c.get(alice_job).proto.owner
    out.update(result="accepted", got=got, alice_job=alice_job, visible=visible, owner=owner)


# ---- the test -----------------------------------------------------------------------------------

def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin-dir", required=True, help="the folder of lightfarm-server and -worker")
    ap.add_argument("--scenes", required=True, help="tests/scenes")
    ap.add_argument("--keep", action="store_true", help="keep the temporary folder (logs)")
    args = ap.parse_args()

    checks = Checks()
    dir = tempfile.mkdtemp(prefix="lf_load_")
    farm = Farm(os.path.abspath(args.bin_dir), os.path.abspath(args.scenes), dir)
    try:
        run(farm, checks)
    finally:
        farm.stop()
        if args.keep or checks.failed:
            log(f"logs kept in {dir}")
        else:
            shutil.rmtree(dir, ignore_errors=True)
    if checks.failed:
        print(f"\n{len(checks.failed)} check(s) failed:")
        for msg in checks.failed:
            print(f"  - {msg}")
        return 1
    print("\nall checks passed")
    return 0


def run(farm, checks):
    admin_token, _ = farm.token("admin", "admin")
    alice_token, _ = farm.token("alice", "submitter")
    mallory_token, _ = farm.token("mallory", "submitter")
    _, w1_file = farm.token("w1", "worker")
    _, w2_file = farm.token("w2", "worker")
    w3_token, _ = farm.token("w3", "worker")
    rogue_token, _ = farm.token("rogue", "worker")
    farm.start_server()
    log(f"server pid {farm.server.pid}: gRPC {farm.grpc_addr}, http {farm.http[0]}:{farm.http[1]}")
    sampler = Sampler(farm.server.pid)
    with farm.lock:
        farm.start_worker("w1", w1_file)
        farm.start_worker("w2", w2_file)
    threading.Thread(target=farm.supervise, daemon=True).start()
    admin_ch = channel(farm.grpc_addr)
    admin_stub = jgrpc.JobServiceStub(admin_ch)

    class Admin:  # the admin stub with its token
        def ListTasks(self, req, timeout):
            return admin_stub.ListTasks(req, timeout=timeout, metadata=bearer(admin_token))

    with open(os.path.join(farm.scenes, "cornell_box.json")) as f:
        base_text = f.read()

    # Mallory's earlier job, whose result the stalled readers fetch.
    with lightfarm.Client(farm.grpc_addr, token=mallory_token) as m:
        fetch_job = m.submit(scene_variant(farm, base_text, 500), resolution=(512, 512), spp=1,
                             tile=64, name="mallory-result")
        state = m.wait(fetch_job).state
    log(f"mallory's 512x512 job {fetch_job}: {state.name}")

    # The honest phase alone.
    quiet = HonestRun(farm, alice_token, base_text, 0)
    quiet.run(time.time() + HONEST_DEADLINE)
    log(f"quiet honest phase: {quiet.makespan:.1f} s, outcomes {quiet.outcomes}")
    sampler.sample()
    quiet_peak = sampler.peak_rss

    # The attacked phase.
    stop = threading.Event()
    outcomes = {i: {} for i in range(1, 9)}
    with lightfarm.Client(farm.grpc_addr, token=mallory_token) as m:
        # Low priority, many passes: it lasts the whole phase, and honest jobs go first.
        outcomes[6]["job"] = m.submit(scene_variant(farm, base_text, 501), resolution=(64, 64),
                                      spp=1 << 16, passes=256, tile=16, priority=-1,
                                      name="mallory-watched")
    outcomes[6]["release"] = threading.Event()
    # Before mallory's stalled uploads, which may hold her own uploads back too.
    attack_gltf(farm, mallory_token, outcomes[3])
    log(f"attack 3 done: {outcomes[3]['results']}")
    slots_ready = threading.Event()
    background = [
        threading.Thread(target=attack_slots, args=(farm, mallory_token, outcomes[6], slots_ready)),
        threading.Thread(target=attack_leases,
                         args=(farm, rogue_token, w3_token, stop, outcomes[4])),
    ]
    for t in background:
        t.start()
    slots_ready.wait(30)
    log(f"attack 6 holds {outcomes[6].get('uploads_held')} uploads, "
        f"{outcomes[6].get('watching')} watches")
    # Alice watches a job of hers while mallory holds her watches (an ended job: one message).
    with lightfarm.Client(farm.grpc_addr, token=alice_token, retry_seconds=0) as a:
        try:
            a.wait(quiet.job_ids[0])
            outcomes[6]["alice_watch"] = "OK"
        except lightfarm.LightfarmError as e:
            outcomes[6]["alice_watch"] = str(e)
    attacked = HonestRun(farm, alice_token, base_text, 100, request_id=secrets.token_hex(16),
                         held=outcomes[6]["release"])
    honest_thread = threading.Thread(target=attacked.run,
                                     args=(time.time() + HONEST_DEADLINE,))
    honest_thread.start()
    reuse = threading.Thread(target=attack_request_id,
                             args=(farm, mallory_token, alice_token, attacked, outcomes[8]))
    reuse.start()
    # The memory attacks, one window each; slowloris from the second on (it would keep the
    # chunked sign-ins from being read at all).
    attack_huge_unauthenticated(farm, sampler, outcomes[1])
    log(f"attack 1 done: {outcomes[1]['codes']} in {outcomes[1]['seconds']:.0f} s")
    attack_chunked_session(farm, sampler, outcomes[2])
    log(f"attack 2 done: {outcomes[2]['answers']}")
    slowloris = threading.Thread(target=attack_slowloris, args=(farm, stop, outcomes[5]))
    slowloris.start()
    background.append(slowloris)
    slowloris_start = time.time()
    attack_stalled_readers(farm, sampler, mallory_token, fetch_job, outcomes[7])
    log(f"attack 7 done: {outcomes[7]['reading']} reading")
    # Leases and slowloris for at least 20 s, the slots until the honest client is done.
    stop.wait(max(0.0, 20 - (time.time() - slowloris_start)))
    stop.set()
    reuse.join()
    honest_thread.join()
    outcomes[6]["release"].set()
    for t in background:
        t.join()
    log(f"attacked honest phase: {attacked.makespan:.1f} s")
    healthz_end = http_get(farm.http, "/healthz", 5)
    server_alive = farm.server.poll() is None
    sampler.stop()
    with lightfarm.Client(farm.grpc_addr, token=mallory_token, retry_seconds=0) as m:
        try:
            m.cancel(outcomes[6]["job"])
        except lightfarm.LightfarmError:
            pass
    victim = outcomes[4].get("victim_task")
    honest_failures = task_failures(Admin(), quiet.job_ids + attacked.job_ids,
                                    exclude={victim} if victim else set())
    admin_ch.close()

    # ---- the report ----
    o = outcomes
    print("\n==== hostile load: outcomes ====")
    print(f"(1) unauthenticated ListJobs x3 with 300 MB page_token: {o[1]['codes']}, server RSS "
          f"{o[1]['before'] / MB:.0f} MB before, +{o[1]['rise'] / MB:.0f} MB peak in the window")
    print(f"(2) chunked POST /api/session x2 of 300 MB: (answer, MB sent) {o[2]['answers']}, "
          f"RSS {o[2]['before'] / MB:.0f} MB before, +{o[2]['rise'] / MB:.0f} MB peak")
    print(f"(3) glTF at 1e308 by mallory: {o[3].get('results')}; worker deaths "
          f"{farm.worker_deaths}")
    print(f"(4) rogue token: {o[4].get('granted')} leases under fresh ids, at most "
          f"{o[4].get('held')} held at once, refused {o[4].get('refused')}; claiming w3's id: "
          f"{o[4].get('forged')}; lease ids like {o[4].get('lease_ids')}")
    print(f"(5) slowloris x{o[5].get('connections')} ({o[5].get('reopened')} reopened): /healthz answered {o[5].get('answered')} "
          f"of {o[5].get('probes')} probes (others: {o[5].get('unanswered')})")
    print(f"(6) mallory: {o[6].get('uploads_held')} stalled uploads held (refused "
          f"{o[6].get('uploads_refused')}), {o[6].get('watching')} watches open (refused "
          f"{o[6].get('watches_refused')}); alice's watch during the hold: "
          f"{o[6].get('alice_watch')}; alice's uploads refused {len(attacked.upload_refusals)}"
          f" times, watches refused {len(attacked.watch_refusals)}, her first submission took "
          f"{attacked.first_seconds or -1:.1f} s (quiet: {quiet.first_seconds or -1:.1f} s) "
          f"{attacked.upload_refusals[:1] + attacked.watch_refusals[:1]}")
    print(f"(7) 400 stalled FetchResult readers: {o[7]['reading']} reading, refused "
          f"{o[7]['refused']}, RSS {o[7]['before'] / MB:.0f} MB before, +{o[7]['rise'] / MB:.0f} "
          f"MB peak; alice's fetch errors {attacked.fetch_errors[:2]}")
    print(f"(8) mallory reusing alice's request_id: {o[8]}")
    print("\n==== hostile load: numbers ====")
    print(f"peak resident memory: {sampler.peak_rss / MB:.0f} MB "
          f"(quiet phase: {quiet_peak / MB:.0f} MB)")
    print(f"peak threads: {sampler.peak_threads}, peak open fds: {sampler.peak_fds}")
    print(f"honest jobs failed: {len(quiet.failed())} of {HONEST_JOBS} quiet, "
          f"{len(attacked.failed())} of {HONEST_JOBS} attacked {attacked.failed()}")
    print(f"honest task failures counted: {honest_failures}")
    print(f"honest makespan: {quiet.makespan:.1f} s quiet, {attacked.makespan:.1f} s under attack")
    print(f"worker deaths: {len(farm.worker_deaths)}")
    print(f"/healthz at the end: {healthz_end}\n")

    checks.check(sampler.peak_rss < PEAK_LIMIT,
                 f"peak resident memory {sampler.peak_rss / MB:.0f} MB is below 1 GB (10^9 bytes)")
    checks.check(not quiet.failed() and len(quiet.outcomes) == HONEST_JOBS,
                 f"every honest job of the quiet phase succeeded: {quiet.outcomes}")
    checks.check(not attacked.failed() and len(attacked.outcomes) == HONEST_JOBS,
                 f"every honest job under attack succeeded: {attacked.outcomes}")
    checks.check(honest_failures == 0,
                 f"no honest task counted a failure (counted: {honest_failures})")
    checks.check(server_alive and healthz_end == 200,
                 f"the server still answers /healthz at the end ({healthz_end})")
    checks.check("OK" not in o[1]["codes"] and o[1]["rise"] < UNAUTHENTICATED_RISE_LIMIT,
                 f"(1) unauthenticated 300 MB ListJobs calls are refused ({o[1]['codes']}) "
                 f"holding under {UNAUTHENTICATED_RISE_LIMIT // MB} MB (held "
                 f"+{o[1]['rise'] / MB:.0f} MB)")
    checks.check(all(isinstance(a[0], int) and 400 <= a[0] < 500 for a in o[2]["answers"])
                 and o[2]["rise"] < UNAUTHENTICATED_RISE_LIMIT,
                 f"(2) chunked 300 MB sign-in bodies are answered 4xx ({o[2]['answers']}) holding "
                 f"under {UNAUTHENTICATED_RISE_LIMIT // MB} MB (held +{o[2]['rise'] / MB:.0f} MB)")
    gltf = o[3].get("results", {})
    checks.check(all(r[0] == "INVALID_ARGUMENT" for r in gltf.values()) and len(gltf) == 2,
                 f"(3) glTF scenes with a camera or a light at 1e308 are refused at submission "
                 f"({gltf})")
    checks.check(not farm.worker_deaths,
                 f"(3) no worker died ({farm.worker_deaths})")
    # "Held" is counted on the client's clock, which sees a lease up to one round trip late: a
    # lease freed and granted again meanwhile counts twice, at most once per stealing thread.
    checks.check(o[4].get("held", 0) <= ROGUE_LEASES_LIMIT + ROGUE_THREADS,
                 f"(4) the rogue worker token held at most {ROGUE_LEASES_LIMIT} leases at once "
                 f"(held {o[4].get('held')}, {o[4].get('granted')} in all)")
    forged = o[4].get("forged", {})
    checks.check(o[4].get("victim_task") is not None and forged.get("Heartbeat") != "OK"
                 and forged.get("w3's lease after") == "kept",
                 f"(4) the rogue token's calls under w3's worker id keep no lease of w3's, and "
                 f"w3's lease survives its FailTask ({forged})")
    checks.check(o[4].get("short_ids", 1) == 0,
                 f"(4) lease ids are at least 16 characters ({o[4].get('lease_ids')})")
    checks.check(o[5].get("probes", 0) > 0 and o[5].get("answered") == o[5].get("probes"),
                 f"(5) /healthz answered every probe within 2 s during slowloris "
                 f"({o[5].get('answered')} of {o[5].get('probes')})")
    checks.check(not attacked.upload_refusals and attacked.first_in_while_held,
                 f"(6) alice's uploads are neither refused nor held back while mallory stalls "
                 f"{o[6].get('uploads_held')} (refusals {attacked.upload_refusals[:1]}; her first "
                 f"submission went through before mallory let go {SLOTS_SECONDS} s later: "
                 f"{attacked.first_in_while_held})")
    checks.check(not attacked.watch_refusals and o[6].get("alice_watch") == "OK",
                 f"(6) alice's watches are not refused while mallory holds {o[6].get('watching')} "
                 f"(during the hold: {o[6].get('alice_watch')}; of her jobs: "
                 f"{attacked.watch_refusals[:1]})")
    checks.check(o[7]["rise"] < STALLED_READERS_RISE_LIMIT,
                 f"(7) 400 stalled FetchResult readers hold under "
                 f"{STALLED_READERS_RISE_LIMIT // MB} MB (held +{o[7]['rise'] / MB:.0f} MB, "
                 f"{o[7]['reading']} streams reading)")
    checks.check(not attacked.fetch_errors,
                 f"(7) alice's fetches succeed while mallory stalls readers "
                 f"({attacked.fetch_errors[:1]})")
    r8 = o[8]
    checks.check(r8.get("got") is None or (r8.get("got") != r8.get("alice_job")
                                           and r8.get("visible") == "OK"),
                 f"(8) mallory's submission with alice's request_id is her own job, not alice's "
                 f"(got {r8.get('got')}, alice's {r8.get('alice_job')}, GetJob by mallory: "
                 f"{r8.get('visible')})")
    checks.check(r8.get("owner") == "alice",
                 f"(8) alice's job is still alice's (owner {r8.get('owner')!r})")


if __name__ == "__main__":
    sys.exit(main())

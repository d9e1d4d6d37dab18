#!/usr/bin/python3
"""Does an open dashboard slow the farm? 200 small jobs on a server and two workers, rendered
once with no dashboard and once with 20 dashboard tabs polling it, alternately, several rounds.

A tab is simulated by the requests the page makes (server/web/*.js, every 2 s while shown):
  jobs page:    GET /api/jobs?limit=100
  job page:     GET /api/jobs/ID, /api/jobs/ID/tasks, /api/jobs/ID/logs?task=0&after=N (a
                task's log open), /api/jobs/ID/preview.png whenever tasks_done changed, and
                /api/jobs/ID/metadata once and when the job ends; then the tab opens the
                newest running job (one jobs request), as a user following the farm would
  workers page: GET /api/workers;  farm page: GET /api/farm (every 5 s)
Of the 20 tabs, 10 show the jobs page, 8 a job, 1 the workers and 1 the farm. They sign in with
an admin token (authentication is on, as on a real farm) and run in a process of their own at
nice 19, so that on this small machine they take CPU from the farm only when it idles: what is
measured is what serving them costs the server, not the browsers' own work.

Prints, per round and as medians: the makespan (first submission to the last job's end, from the
server's timestamps), the server's CPU seconds, and the tabs' request count and latencies.

  /usr/bin/python3 tools/dashboard_load_bench.py [--bin-dir build/bin] [--jobs 200] [--tabs 20]
      [--rounds 2]
Needs a build (deploy/build.sh): the binaries and build/python (the Python client).
"""

import argparse
import http.client
import json
import os
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def free_port():
    import socket
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def cpu_seconds(pid):
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


class Farm:
    def __init__(self, bin_dir, work):
        self.work = work
        data = os.path.join(work, "data")
        os.makedirs(data)
        make = lambda name, role: subprocess.run(
            [f"{bin_dir}/lightfarm-server", "token", "create", "--data-dir", data, "--name", name,
             "--role", role], check=True, capture_output=True, text=True).stdout.strip().split()[-1]
        self.tokens = {r: make(r, r) for r in ("admin", "submitter", "worker")}
        for role, token in self.tokens.items():
            with open(os.path.join(work, role), "w") as f:
                f.write(token + "\n")
        self.grpc = f"127.0.0.1:{free_port()}"
        self.http = free_port()
        self.server = subprocess.Popen(
            [f"{bin_dir}/lightfarm-server", "--listen", self.grpc, "--data-dir", data,
             "--http", f"127.0.0.1:{self.http}", "--log-level", "warn"],
            stdout=subprocess.DEVNULL, stderr=open(os.path.join(work, "server.log"), "w"))
        deadline = time.time() + 20
        while True:
            try:
                http.client.HTTPConnection("127.0.0.1", self.http, timeout=1).request("GET", "/healthz")
                break
            except OSError:
                if time.time() > deadline:
                    sys.exit("the server did not start: see " + work + "/server.log")
                time.sleep(0.1)
        self.workers = [subprocess.Popen(
            [f"{bin_dir}/lightfarm-worker", "--server", self.grpc, "--threads", "1",
             "--token-file", os.path.join(work, "worker"), "--cache-dir", os.path.join(work, f"c{i}"),
             "--log-level", "warn"],
            stdout=subprocess.DEVNULL, stderr=open(os.path.join(work, f"worker{i}.log"), "w"))
            for i in range(2)]

    def stop(self):
        for p in self.workers + [self.server]:
            p.send_signal(signal.SIGTERM)
        for p in self.workers + [self.server]:
            try:
                p.wait(20)
            except subprocess.TimeoutExpired:
                p.kill()


TABS_CODE = r'''
import http.client, json, os, sys, threading, time
port, token, tabs, stop_file = int(sys.argv[1]), sys.argv[2], int(sys.argv[3]), sys.argv[4]
headers = {"Authorization": "Bearer " + token}
latencies, lock = [], threading.Lock()

failures = []

def tab(kind):
    conn = None
    def get(path):
        nonlocal conn
        t = time.perf_counter()
        # A browser keeps a connection alive while the server does (it closes idle ones after
        # a second), and opens a new one when it is gone: so does a tab here.
        for attempt in (1, 2):
            if conn is None:
                conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
            try:
                conn.request("GET", path, headers=headers)
                r = conn.getresponse()
                body = r.read()
                break
            except (http.client.RemoteDisconnected, ConnectionError, BrokenPipeError):
                conn.close()
                conn = None
                if attempt == 2:
                    raise
        with lock:
            latencies.append(time.perf_counter() - t)
        if r.status != 200:
            raise SystemExit(f"GET {path}: {r.status} {body[:200]!r}")
        return body
    shown, log_after, job, metadata = None, 0, None, False
    while not os.path.exists(stop_file):
        start = time.perf_counter()
        if kind == "jobs":
            get("/api/jobs?limit=100")
        elif kind == "workers":
            get("/api/workers")
        elif kind == "farm":
            get("/api/farm")
        else:
            if job is None:  # the user opens the newest running job from the jobs page
                running = [j for j in json.loads(get("/api/jobs?limit=100"))["jobs"]
                           if j["state"] == "running"]
                if running:
                    job, shown, log_after, metadata = running[0]["id"], None, 0, False
            if job:
                j = json.loads(get(f"/api/jobs/{job}"))
                get(f"/api/jobs/{job}/tasks")
                page = json.loads(get(f"/api/jobs/{job}/logs?task=0&after={log_after}&max=500"))
                log_after = page["next_seq"]
                version = (j["tasks_done"], j["state"])
                if version != shown and j["tasks_done"] > 0:
                    shown = version
                    get(f"/api/jobs/{job}/preview.png")
                    if not metadata:
                        metadata = True
                        get(f"/api/jobs/{job}/metadata")
                if j["state"] in ("succeeded", "failed", "cancelled"):
                    get(f"/api/jobs/{job}/metadata")  # the page reads the final header
                    job = None  # and the user moves on to the next running job
        period = 5.0 if kind == "farm" else 2.0
        time.sleep(max(0.0, period - (time.perf_counter() - start)))

def guarded(kind):
    try:
        tab(kind)
    except BaseException as e:
        with lock:
            failures.append(f"{kind} tab: {e!r}")

kinds = ["jobs"] * (tabs // 2) + ["job"] * (tabs - tabs // 2 - 2) + ["workers", "farm"]
threads = [threading.Thread(target=guarded, args=(k,), daemon=True) for k in kinds[:tabs]]
for t in threads:
    t.start()
    time.sleep(2.0 / len(threads))  # tabs opened over one polling period, not in lockstep
for t in threads:
    t.join()
if failures:
    sys.exit("\n".join(failures))
latencies.sort()
print(json.dumps({"requests": len(latencies),
                  "p50_ms": 1000 * latencies[len(latencies) // 2] if latencies else 0,
                  "p99_ms": 1000 * latencies[int(len(latencies) * 0.99)] if latencies else 0}))
'''


def run(args, tabs, scene):
    sys.path.insert(0, os.path.join(args.build_dir, "python"))
    import lightfarm
    work = tempfile.mkdtemp(prefix="lf_dash_bench.")
    farm = Farm(args.bin_dir, work)
    stop_file = os.path.join(work, "stop")
    tab_process = None
    try:
        if tabs:
            tab_process = subprocess.Popen(
                ["nice", "-n", "19", sys.executable, "-c", TABS_CODE, str(farm.http),
                 farm.tokens["admin"], str(tabs), stop_file], stdout=subprocess.PIPE, text=True)
            time.sleep(2.5)  # every tab open before the first job
        cpu0 = cpu_seconds(farm.server.pid)
        with lightfarm.Client(farm.grpc, token=farm.tokens["submitter"]) as client:
            ids = [client.submit(scene, spp=args.spp, tile=16, name=f"bench-{i}") for i in range(args.jobs)]
            for job_id in ids:
                job = client.wait(job_id)
                if job.state.name != "SUCCEEDED":
                    sys.exit(f"{job_id}: {job.state.name} {job.error}")
            jobs = [client.get(i) for i in ids]
        makespan = (max(j.finished_unix_ms for j in jobs) - min(j.submitted_unix_ms for j in jobs)) / 1000
        cpu = cpu_seconds(farm.server.pid) - cpu0
        stats = {}
        if tab_process:
            open(stop_file, "w").close()
            out, _ = tab_process.communicate(timeout=60)
            if tab_process.returncode != 0:
                sys.exit("the tabs failed")
            stats = json.loads(out)
        return {"tabs": tabs, "makespan_s": makespan, "server_cpu_s": cpu, **stats}
    finally:
        if tab_process and tab_process.poll() is None:
            tab_process.kill()
        farm.stop()
        shutil.rmtree(work, ignore_errors=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--bin-dir", default=os.path.join(ROOT, "build/bin"))
    parser.add_argument("--build-dir", default=os.path.join(ROOT, "build"))
    parser.add_argument("--jobs", type=int, default=200)
    parser.add_argument("--tabs", type=int, default=20)
    parser.add_argument("--spp", type=int, default=16)
    parser.add_argument("--rounds", type=int, default=2)
    args = parser.parse_args()
    work = tempfile.mkdtemp(prefix="lf_dash_scene.")
    scene = json.load(open(os.path.join(ROOT, "tests/scenes/cornell_box.json")))
    scene["camera"]["resolution"] = [64, 64]  # 16 tiles of 16x16: 3200 tasks in all
    scene_path = os.path.join(work, "cornell32.json")
    json.dump(scene, open(scene_path, "w"))
    results = {0: [], args.tabs: []}
    for r in range(args.rounds):
        # Alternate which goes first, so that a drift of the machine's speed falls on both.
        for tabs in ((0, args.tabs) if r % 2 == 0 else (args.tabs, 0)):
            result = run(args, tabs, scene_path)
            results[tabs].append(result)
            print(json.dumps(result), flush=True)
    med = {t: statistics.median(x["makespan_s"] for x in rs) for t, rs in results.items()}
    cpu = {t: statistics.median(x["server_cpu_s"] for x in rs) for t, rs in results.items()}
    print(f"jobs {args.jobs}: makespan median {med[0]:.2f} s without the dashboard, "
          f"{med[args.tabs]:.2f} s with {args.tabs} tabs: slowdown "
          f"{100 * (med[args.tabs] / med[0] - 1):+.1f}%; server CPU {cpu[0]:.2f} s vs "
          f"{cpu[args.tabs]:.2f} s")
    shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()

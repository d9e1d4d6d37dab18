#!/usr/bin/env bash
# Farm load: a server and 2 workers on this machine; CLIENTS clients submit JOBS tiny jobs
# (Cornell box, 8x8, 1 spp) at once, each job with its own `lightfarm watch`. Prints how many
# succeeded, the time, and the server's peak memory (VmHWM) before and after.
#
#   tools/farm_load.sh [--clients N] [--jobs N]
#
# Needs a build (deploy/build.sh); binaries come from build/bin unless LF_BIN_DIR says otherwise.
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${LF_BIN_DIR:-build/bin}"
clients=20 jobs=200
while [ $# -gt 0 ]; do
  case "$1" in
    --clients) clients="$2"; shift 2 ;;
    --jobs) jobs="$2"; shift 2 ;;
    *) echo "usage: $0 [--clients N] [--jobs N]" >&2; exit 2 ;;
  esac
done

source tools/farm_common.sh

python3 -c '
import json, sys
scene = json.load(open("tests/scenes/cornell_box.json"))
scene["camera"]["resolution"] = [8, 8]
json.dump(scene, open(sys.argv[1], "w"))' "$work/tiny.json"

start_farm farm_load --log-level warn
hwm() { sed -n 's/^VmHWM:\s*//p' "/proc/$server/status"; }
echo "server VmHWM idle: $(hwm)"

# Each client submits its share one after another and starts a watcher per job.
t0="$(date +%s.%N)"
per_client=$((jobs / clients))
for c in $(seq "$clients"); do
  (
    for j in $(seq "$per_client"); do
      job="$("$bin/lightfarm" submit "$work/tiny.json" --server "$address" --spp 1 | tail -n 1)"
      echo "$job" >>"$work/jobs.$c"
      ( "$bin/lightfarm" watch "$job" --server "$address" >/dev/null 2>&1 \
          && echo "$job" >>"$work/ok.$c" ) &
    done
    wait
  ) &
done
wait_clients() { while [ "$(jobs -rp | wc -l)" -gt "${#pids[@]}" ]; do sleep 0.2; done; }
wait_clients
t1="$(date +%s.%N)"

submitted="$(cat "$work"/jobs.* | sort -u | wc -l)"
succeeded="$(cat "$work"/ok.* 2>/dev/null | sort -u | wc -l)"
listed="$("$bin/lightfarm" list --server "$address" | grep -c 'job-' || true)"
echo "clients $clients, jobs $jobs: $submitted distinct ids, $succeeded succeeded, $listed listed"
echo "time $(python3 -c "print(round($t1 - $t0, 1))") s"
echo "server VmHWM after: $(hwm)"
[ "$submitted" -eq "$jobs" ] && [ "$succeeded" -eq "$jobs" ]

#!/usr/bin/env bash
# Farm overhead: the same job (Cornell box, 256x256, 256 spp) rendered by `lightfarm render`
# with 2 threads and by lightfarm-server with 2 workers of 1 thread each, all on this machine.
# Prints both throughputs and their ratio (farm / local); the target is >= 0.90.
#
#   tools/farm_bench.sh [--spp N] [--tile N] [--passes N] [--rounds N]
#
# Needs a build (deploy/build.sh); binaries come from build/bin unless LF_BIN_DIR says otherwise.
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${LF_BIN_DIR:-build/bin}"
spp=256 tile=32 passes=1 rounds=1
while [ $# -gt 0 ]; do
  case "$1" in
    --spp) spp="$2"; shift 2 ;;
    --tile) tile="$2"; shift 2 ;;
    --passes) passes="$2"; shift 2 ;;
    --rounds) rounds="$2"; shift 2 ;;
    *) echo "usage: $0 [--spp N] [--tile N] [--passes N] [--rounds N]" >&2; exit 2 ;;
  esac
done

source tools/farm_common.sh

scene=tests/scenes/cornell_box.json  # 256x256
now() { date +%s.%N; }
samples=$((256 * 256 * spp))

start_farm farm_bench

best_local=0 best_farm=0 ratios=()
for round in $(seq "$rounds"); do
  t0="$(now)"
  "$bin/lightfarm" render "$scene" -o "$work/local.exr" --method path --spp "$spp" --threads 2 \
    --tile "$tile" \
    --no-progress >/dev/null
  t1="$(now)"
  job="$("$bin/lightfarm" submit "$scene" --server "$address" --spp "$spp" --tile "$tile" \
    --passes "$passes" | tail -n 1)"
  "$bin/lightfarm" watch "$job" --server "$address" >/dev/null
  t2="$(now)"
  local_rate="$(echo "$samples $t0 $t1" | awk '{printf "%.4f", $1 / ($3 - $2) / 1e6}')"
  farm_rate="$(echo "$samples $t1 $t2" | awk '{printf "%.4f", $1 / ($3 - $2) / 1e6}')"
  ratios+=("$(echo "$farm_rate $local_rate" | awk '{printf "%.3f", $1 / $2}')")
  echo "round $round: local $local_rate M samples/s, farm $farm_rate M samples/s," \
    "ratio ${ratios[-1]}"
  best_local="$(echo "$best_local $local_rate" | awk '{print ($2 > $1) ? $2 : $1}')"
  best_farm="$(echo "$best_farm $farm_rate" | awk '{print ($2 > $1) ? $2 : $1}')"
done
echo "local (2 threads):            $best_local M samples/s"
echo "farm (2 workers x 1 thread):  $best_farm M samples/s (submit to last tile merged)"
echo "ratio farm/local, best of each: $(echo "$best_farm $best_local" | awk '{printf "%.3f", $1 / $2}')"
# Each round runs local and farm back to back, so the median of the rounds' ratios is the least
# disturbed by other load on the machine.
echo "ratio farm/local, median round: $(printf '%s\n' "${ratios[@]}" | sort -n |
  awk '{r[NR] = $1} END {print (NR % 2) ? r[(NR + 1) / 2] : (r[NR / 2] + r[NR / 2 + 1]) / 2}')"

#!/usr/bin/env bash
# Shot throughput on the farm against local mode, and the cost of motion blur: the 240-frame demo
# shot (tests/scenes/shots/demo_shot.gltf) at 320x180,
#   - `lightfarm render --frames` with 2 threads,
#   - one `submit --frames` to a server with 2 workers of 1 thread each, with --chunk 1 and 8,
#   - `render --frames` with --shutter 0.5 against the same frames as stills (equal spp).
# Prints frames per minute of each, and the machine's load before and after (other work on the
# machine slows every figure).
#
#   tools/shot_farm_bench.sh [--spp N] [--frames A-B[:STEP]] [--resolution WxH] [--chunks "1 8"]
#
# Needs a build; binaries come from build/bin unless LF_BIN_DIR says otherwise.
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${LF_BIN_DIR:-build/bin}"
spp=4 frames=1-240 resolution=320x180 chunks="1 8"
while [ $# -gt 0 ]; do
  case "$1" in
    --spp) spp="$2"; shift 2 ;;
    --frames) frames="$2"; shift 2 ;;
    --resolution) resolution="$2"; shift 2 ;;
    --chunks) chunks="$2"; shift 2 ;;
    *) echo "usage: $0 [--spp N] [--frames A-B[:STEP]] [--resolution WxH] [--chunks \"1 8\"]" >&2
       exit 2 ;;
  esac
done

source tools/farm_common.sh

scene=tests/scenes/shots/demo_shot.gltf
now() { date +%s.%N; }
count="$(echo "$frames" | awk -F'[-:]' '{step = ($3 == "") ? 1 : $3; print int(($2 - $1) / step) + 1}')"
per_minute() { echo "$count $1 $2" | awk '{printf "%.1f", $1 / ($3 - $2) * 60}'; }
flags=(--frames "$frames" --resolution "$resolution" --spp "$spp" --method path)

echo "machine: $(nproc) cores; before: $(uptime)"
t0="$(now)"
"$bin/lightfarm" render "$scene" "${flags[@]}" --threads 2 -o "$work/still_####.exr" \
  --no-progress >/dev/null 2>&1
t1="$(now)"
echo "local, 2 threads:                   $(per_minute "$t0" "$t1") frames/min"
"$bin/lightfarm" render "$scene" "${flags[@]}" --threads 2 --shutter 0.5 \
  -o "$work/blur_####.exr" --no-progress >/dev/null 2>&1
t2="$(now)"
echo "local, 2 threads, --shutter 0.5:    $(per_minute "$t1" "$t2") frames/min" \
  "(blur costs $(echo "$t0 $t1 $t2" | awk '{printf "%.2f", ($3 - $2) / ($2 - $1)}')x the stills)"

start_farm shot_farm_bench
for chunk in $chunks; do
  t0="$(now)"
  job="$("$bin/lightfarm" submit "$scene" "${flags[@]}" --chunk "$chunk" --server "$address" |
    tail -n 1)"
  "$bin/lightfarm" watch "$job" --server "$address" >/dev/null
  t1="$(now)"
  printf 'farm, 2 workers x 1 thread, --chunk %-3s %s frames/min (submit to last frame written)\n' \
    "$chunk" "$(per_minute "$t0" "$t1")"
done
# Per-frame pose and BVH times on the workers: "frame F posed in P ms, BVH built in B ms".
cat "$work"/worker*.log | awk '
  / posed in / { n++; for (i = 1; i <= NF; i++) { if ($i == "posed") p += $(i + 2); if ($i == "built") b += $(i + 2) } }
  END { if (n) printf "workers: %d poses, mean pose %.3f ms, mean BVH %.2f ms\n", n, p / n, b / n }'
echo "after:  $(uptime)"

#!/usr/bin/env bash
# Quality per second (issue 14): the old configuration (independent sampler, lights by power)
# against the new ones (Sobol, light BVH, and the two mixed) on the Cornell box and on the
# many-lights scene (tests/scenes/many_lights.json), each against one reference `lightfarm
# converge` renders itself (the most efficient configuration, another seed). Prints per scene
# and configuration: RMSE and relMSE at equal time and their ratio to the old configuration,
# the slopes of RMSE and relative RMSE against time over 16 to 1024 spp, and samples per
# second; then the issue's targets on the Cornell box: RMSE slope <= -0.6, equal-time RMSE
# ratio new / old <= 1/3, samples/s within 10 % of the old.
#
#   tools/quality_bench.sh [--resolution 256] [--max-spp 1024] [--reference-spp 8192]
#                          [--threads 2] [--scenes cornell_box,many_lights] [--out DIR]
#
# The defaults are the issue's measurement (256 x 256, 2 threads, 8192-spp reference); a run
# takes tens of minutes on 2 cores. Timings (and so every equal-time figure) are noisy on a
# shared machine: converge renders the configurations rung by rung in turn so that a change in
# load falls on all of them, but repeat a run before trusting a few percent. Needs a build
# (deploy/build.sh); binaries come from build/bin unless LF_BIN_DIR says otherwise.
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${LF_BIN_DIR:-build/bin}"
resolution=256 max_spp=1024 reference_spp=8192 threads=2 scenes=cornell_box,many_lights out=""
usage="usage: $0 [--resolution N] [--max-spp N] [--reference-spp N] [--threads N] [--scenes LIST] [--out DIR]"
while [ $# -gt 0 ]; do
  case "$1" in
    --resolution) resolution="$2"; shift 2 ;;
    --max-spp) max_spp="$2"; shift 2 ;;
    --reference-spp) reference_spp="$2"; shift 2 ;;
    --threads) threads="$2"; shift 2 ;;
    --scenes) scenes="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    *) echo "$usage" >&2; exit 2 ;;
  esac
done
if [ -z "$out" ]; then
  out="$(mktemp -d /tmp/quality_bench.XXXXXX)"
fi
mkdir -p "$out"

configs=independent/power,independent/bvh,sobol/power,sobol/bvh
echo "quality_bench: ${resolution} px wide, ladders 1 to ${max_spp} spp, reference ${reference_spp} spp," \
  "${threads} threads, fit and equal time over 16 to 1024 spp; output in ${out}"

for name in ${scenes//,/ }; do
  scene="tests/scenes/${name}.json"
  [ -f "$scene" ] || { echo "$scene: no such scene" >&2; exit 2; }
  start=$(date +%s)
  "$bin/lightfarm" converge "$scene" --out "$out/$name" --method path \
    --resolution "$resolution" --max-spp "$max_spp" --reference-spp "$reference_spp" \
    --threads "$threads" --fit-spp 16:1024 --compare "$configs" >"$out/$name.log" 2>&1 ||
    { cat "$out/$name.log" >&2; exit 1; }
  echo
  echo "== $name ($(($(date +%s) - start)) s in all)"
  grep -o 'own path-traced reference.*' "$out/$name.log" || grep -o '^reference .*' "$out/$name.log"
  # summary.csv (docs/convergence.md): sampler,light_sampling,fit_from_spp,fit_to_spp,
  # relative_rmse_slope,rmse_slope,samples_per_second,equal_time_from,equal_time_to,
  # rmse_at_equal_time,relmse_at_equal_time,rmse_ratio_at_end,rmse_ratio_mean,
  # relmse_ratio_at_end,relmse_ratio_mean,rmse_spp_slope
  awk -F, -v scene="$name" '
    NR == 1 { next }
    NR == 2 {
      printf "equal time %.3g s (RMSE there; ratios to independent/power there and as the mean over %.3g to %.3g s)\n", $9, $8, $9
      printf "%-18s %11s %13s %11s %13s %9s %9s %9s %10s %8s\n", "configuration", "RMSE", "ratio end/mean",
        "relMSE", "ratio end/mean", "slope", "slope rel", "slope spp", "Msamples/s", "speed"
      old_speed = $7
    }
    {
      printf "%-18s %11.4e %6.3f/%-6.3f %11.4e %6.3f/%-6.3f %9.3f %9.3f %9.3f %10.3f %8.3f\n", $1 "/" $2, $10,
        $12, $13, $11, $14, $15, $6, $5, $16, $7 / 1e6, $7 / old_speed
      if (scene == "cornell_box" && NR > 2) {
        targets = targets sprintf("  %-16s RMSE slope %6.3f (<= -0.6: %s; per spp %.3f), equal-time RMSE ratio %.3f (<= 0.333: %s), speed %.3f of old (>= 0.9: %s)\n",
          $1 "/" $2, $6, ($6 <= -0.6 ? "met" : "MISSED"), $16, $12, ($12 <= 1 / 3 ? "met" : "MISSED"),
          $7 / old_speed, ($7 / old_speed >= 0.9 ? "met" : "MISSED"))
      }
    }
    END { if (targets != "") printf "targets (issue 14, Cornell box):\n%s", targets }
  ' "$out/$name/summary.csv"
done

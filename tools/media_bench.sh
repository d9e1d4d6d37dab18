#!/usr/bin/env bash
# The participating-media benchmark of issue 32 ("Speed and memory"): a 256^3 smoke grid lit by
# a sun and a sky, 512^2. Builds tools/media_grid.cc (g++ against libopenvdb-dev, outside the
# product's build), generates the grid procedurally (fractal noise in a sphere, 2 m across: a
# Blender bake at resolution 256 takes far longer than this whole run on 2 cores), writes the
# scenes with tools/media_scenes.py (sun + sky + ground; the same with the smoke, its sigma_t
# scaled 1x, 10x and 100x) and renders each with `lightfarm render`. Prints the grid's file size
# and bytes per active voxel, its dense in-memory size (4 bytes a lattice point of the active
# bounding box, plus a 16^3 float majorant grid), the load phase with and without the grid,
# and samples/s of each scene with its ratio to the scene without smoke.
#
#   tools/media_bench.sh [--grid-size 256] [--resolution 512] [--spp 8] [--threads 2] [--out DIR]
#
# Needs libopenvdb-dev and libboost-dev (Debian's OpenVDB headers include Boost's but the
# package does not depend on it). Timings are noisy on a shared machine; repeat before trusting
# a few percent.
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${LF_BIN_DIR:-build/bin}"
grid_size=256 resolution=512 spp=8 threads=2 out=""
usage="usage: $0 [--grid-size N] [--resolution N] [--spp N] [--threads N] [--out DIR]"
source tools/bench_options.sh
parse_options "grid-size resolution spp threads out" "$@"
[ -n "$out" ] || out="$(mktemp -d /tmp/media_bench.XXXXXX)"
mkdir -p "$out"
[ -x "$bin/lightfarm" ] || { echo "media_bench: no $bin/lightfarm; build it first" >&2; exit 1; }
echo "media_bench: ${grid_size}^3 grid, ${resolution}x${resolution}, ${spp} spp, ${threads}" \
  "threads; output in ${out}"

tool="$out/media_grid"
if [ ! -x "$tool" ] || [ tools/media_grid.cc -nt "$tool" ]; then
  g++ -std=c++20 -O2 tools/media_grid.cc -o "$tool" -lopenvdb -ltbb -lImath
fi
grid="$out/smoke${grid_size}.vdb"
"$tool" smoke "$grid" "$grid_size" | tee "$out/grid.log"
"$tool" info "$grid" >"$out/grid_info.log"
column=$(sed -n 's/.*central column density integral \([0-9.e+-]*\) m.*/\1/p' "$out/grid.log")
python3 tools/media_scenes.py bench "$out" "$grid" >/dev/null

# Memory: the file per active voxel, and the dense copy a renderer keeps (lf::VolumeGrid: the
# active bounding box as floats) with a 16^3 float majorant grid.
awk '
  /^file / { bytes = $3 }
  /^grid / {
    for (i = 1; i <= NF; i++) if ($i == "active" && $(i + 1) == "voxels,") active = $(i - 1)
    match($0, /\[[-0-9 ]+\]\.\.\[[-0-9 ]+\]/)
    box = substr($0, RSTART + 1, RLENGTH - 2); gsub(/\]\.\.\[/, " ", box); split(box, c, " ")
    points = (c[4] - c[1] + 1) * (c[5] - c[2] + 1) * (c[6] - c[3] + 1)
  }
  END {
    dense = 4 * points + 4 * 16 ^ 3
    printf "grid: %d active voxels; file %.1f MiB = %.2f bytes per active voxel\n",
      active, bytes / 2 ^ 20, bytes / active
    printf "dense in memory: %d lattice points (active box) x 4 bytes + 16^3 majorant = %.1f MiB" \
      " = %.2f bytes per active voxel\n", points, dense / 2 ^ 20, dense / active
  }' "$out/grid_info.log"

# One render; prints "load_s samples_per_s rays_per_s" or nothing if it failed.
render() {
  local name="$1"
  if "$bin/lightfarm" render "$out/$name.json" -o "$out/$name.exr" --png "$out/$name.png" \
    --resolution "$resolution" --spp "$spp" --threads "$threads" --seed 1 --no-progress \
    >"$out/$name.log" 2>&1; then
    awk '
      /M samples\/s/ {
        for (i = 2; i <= NF; i++) {
          if ($i == "samples/s,") s = $(i - 2)
          if ($i == "rays/s,") r = $(i - 2)
        }
      }
      /^time: load/ { load = $3 }
      END { print load, s, r }' "$out/$name.log"
  fi
}

printf '%-12s %12s %10s %14s %12s %12s\n' scene "tau(centre)" "load s" "M samples/s" "M rays/s" \
  "vs clear"
clear_rate=""
for name in clear smoke_1x smoke_10x smoke_100x; do
  scale=0 tau="-"
  case "$name" in smoke_*) scale="${name#smoke_}"; scale="${scale%x}" ;; esac
  # sigma_t at density 1 is 4 m^-1 in media_scenes.py's bench scenes.
  [ "$scale" = 0 ] || tau=$(awk -v c="$column" -v s="$scale" 'BEGIN { printf "%.3g", c * 4 * s }')
  result=$(render "$name")
  if [ -z "$result" ]; then
    why=$(grep -m1 -i error "$out/$name.log" || tail -1 "$out/$name.log")
    printf '%-12s %12s  failed: %s\n' "$name" "$tau" "$why"
    continue
  fi
  read -r load rate rays <<<"$result"
  [ -n "$clear_rate" ] || clear_rate="$rate"
  printf '%-12s %12s %10s %14s %12s %11.3fx\n' "$name" "$tau" "$load" "$rate" "$rays" \
    "$(awk -v a="$rate" -v b="$clear_rate" 'BEGIN { print a / b }')"
  # The loader's own lines about the grid, if it logs them.
  grep -i 'vdb\|grid' "$out/$name.log" | grep -v '^job ' | sed 's/^/    /' | head -3 || true
done
echo "tau(centre): optical depth through the middle of the smoke (sigma_t x density along its" \
  "central column); load s: the render's load phase (scene and grid)"

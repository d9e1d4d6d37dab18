#!/usr/bin/env bash
# Local shot throughput: `lightfarm render --frames` of tests/scenes/shots/demo_shot.gltf (the glTF
# demo with its spheres animated, made by make_demo_shot.py), 240 frames at 320x180 by default.
# Prints frames per minute, the mean and worst per-frame pose and BVH times, and the machine's
# load (uptime) before and after, since other work on the machine slows the render.
#
#   tools/shot_bench.sh [--spp N] [--frames A-B[:STEP]] [--resolution WxH] [--method M]
#                       [--build DIR] [--keep DIR]
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
spp=4 frames=1-240 resolution=320x180 method=path build="$root/build" keep=""
while [[ $# -gt 0 ]]; do
    case "$1" in
        --spp) spp=$2; shift 2 ;;
        --frames) frames=$2; shift 2 ;;
        --resolution) resolution=$2; shift 2 ;;
        --method) method=$2; shift 2 ;;
        --build) build=$2; shift 2 ;;
        --keep) keep=$2; shift 2 ;;
        *) echo "shot_bench.sh: unknown argument $1" >&2; exit 2 ;;
    esac
done
lightfarm="$build/bin/lightfarm"
[[ -x "$lightfarm" ]] || { echo "shot_bench.sh: $lightfarm missing: build the lightfarm target" >&2; exit 1; }

out=${keep:-$(mktemp -d)}
mkdir -p "$out"
[[ -n "$keep" ]] || trap 'rm -rf "$out"' EXIT
scene="$root/tests/scenes/shots/demo_shot.gltf"

echo "machine: $(nproc) cores; before: $(uptime)"
"$lightfarm" render "$scene" --frames "$frames" --resolution "$resolution" --spp "$spp" \
    --method "$method" -o "$out/frame_####.exr" --no-progress >"$out/shot.log" 2>"$out/render.log"
echo "after:  $(uptime)"
tail -n 1 "$out/shot.log"
# Per-frame lines: "frame F (T s): pose P ms, BVH B ms|reused[, radiosity S s], render R s, ..."
awk 'function after(label,    rest) {
        if (!match($0, label " [0-9.]+")) return 0
        rest = substr($0, RSTART + length(label) + 1, RLENGTH - length(label) - 1)
        return rest + 0
    }
    /^frame / {
        n++; pose = after("pose"); bvh = after("BVH"); render = after("render")
        ps += pose; bs += bvh; rs += render
        if (pose > pmax) pmax = pose; if (bvh > bmax) bmax = bvh
    }
    END {
        if (n == 0) { print "no frames rendered"; exit 1 }
        printf "%d frames, %s, %s spp: pose mean %.3f ms (worst %.3f), BVH mean %.2f ms (worst %.2f), render mean %.3f s\n",
            n, "'"$resolution"'", "'"$spp"'", ps / n, pmax, bs / n, bmax, rs / n
    }' "$out/shot.log"

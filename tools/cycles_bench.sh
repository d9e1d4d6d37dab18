#!/usr/bin/env bash
# lightfarm against Blender 3.4's Cycles (CPU) at equal time, on the same scenes: prints Markdown
# tables of RMSE ratios against long references (issue 31). Not in CI. tools/cycles_bench.md says
# more and holds a measured table.
#
#   tools/cycles_bench.sh [--out DIR] [--scenes cornell,demo,room,many_lights] [--resolution 256]
#       [--spp-ladder 16,32,64,128,256] [--reference-spp 8192] [--threads 2]
#       [--thresholds 0.1,0.05,0.02,0.01] [--fresh]
#
# Scenes: cornell (tests/scenes/cornell_box.json), demo (tests/scenes/gltf_demo/demo.gltf), room
# (tests/scenes/cycles_room/room.gltf, built by tools/make_cycles_room.py), many_lights
# (tests/scenes/many_lights.json). tools/cycles_bench.py builds each in Blender: glTF through
# Blender's importer with tools/cycles_scene.py's fix-ups, JSON quads and lambert materials as
# meshes with diffuse BSDFs and one-sided emission; the camera is the one lightfarm logs.
#
# How it measures, one render at a time, none under nice:
# - RES x RES pixels, THREADS threads both, a box pixel filter one pixel wide both. lightfarm:
#   `render --method path` with its defaults (sobol sampler, bvh light sampling, unlimited depth
#   with Russian roulette), --seed 0. Cycles: unclamped, no denoising, no glossy filter, every
#   kind of bounce up to 64 (its defaults, 4 diffuse and 4 glossy, are biased: 1.4 % darker on
#   the Cornell box), seed 0, no adaptive sampling.
# - Times: lightfarm's is the wall time of the whole `lightfarm render` process (load, BVH,
#   render, EXR write); Cycles' is its render call alone (bpy.ops.render.render: sync, BVH, render,
#   EXR write), Blender's start-up and the scene's import or build excluded.
# - Each renderer is measured against its OWN reference of REF spp (lightfarm --seed 1, Cycles
#   seed 1), since their materials differ slightly (tools/khronos_vs_cycles.md) and a shared
#   reference would measure that bias, not noise. RMSE is over all pixels and R, G, B, nothing
#   subtracted (tools/exr_compare --rmse). The references' mean luminance ratio lightfarm/Cycles
#   (about 1 when both render the same scene) and the lightfarm reference's own RMSE, estimated
#   from its half-sample channels, are printed with them. References are kept in DIR and reused
#   by later runs with the same resolution, spp and binaries (lightfarm's by its checksum);
#   --fresh renders them again.
# - Per scene: speed at 64 spp (Cycles s / lightfarm s), RMSE ratio lightfarm/Cycles at 64 spp,
#   and at equal time: lightfarm's RMSE interpolated (log RMSE against log time over its ladder,
#   extrapolated from the nearest two points outside it, then marked *) at Cycles' 64-spp time,
#   over Cycles' RMSE at 64 spp. Then issue 31's targets: Cornell speed >= 2 and equal-time RMSE
#   ratio <= 0.6; the other scenes equal-time RMSE ratio <= 1.
# - Adaptive sampling, when `lightfarm render --help` offers --noise-threshold: Cycles with its
#   adaptive sampling (noise threshold 0.01, its default minimum samples, no time limit, the
#   ladder's top as the most samples) against lightfarm's --noise-threshold T --max-spp TOP over
#   the thresholds, lightfarm's RMSE interpolated at Cycles' time as above.
#
# Needs lightfarm and exr_compare (with --rmse) in LF_BIN_DIR (default build/bin:
# cmake --build build --target lightfarm exr_compare) and Blender 3.4 with numpy, which the script
# installs with apt-get (as root or through sudo) when blender is missing.
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${LF_BIN_DIR:-build/bin}"
out=/tmp/cycles_bench scenes=cornell,demo,room,many_lights res=256 ladder=16,32,64,128,256
ref_spp=8192 threads=2 thresholds=0.1,0.05,0.02,0.01 fresh=0 at_spp=64
usage="usage: $0 [--out DIR] [--scenes LIST] [--resolution N] [--spp-ladder LIST] [--reference-spp N] [--threads N] [--thresholds LIST] [--fresh]"
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out="$2"; shift 2 ;;
    --scenes) scenes="$2"; shift 2 ;;
    --resolution) res="$2"; shift 2 ;;
    --spp-ladder) ladder="$2"; shift 2 ;;
    --reference-spp) ref_spp="$2"; shift 2 ;;
    --threads) threads="$2"; shift 2 ;;
    --thresholds) thresholds="$2"; shift 2 ;;
    --fresh) fresh=1; shift ;;
    *) echo "$usage" >&2; exit 2 ;;
  esac
done
IFS=, read -r -a ladder_spp <<< "$ladder"
IFS=, read -r -a scene_names <<< "$scenes"
IFS=, read -r -a threshold_list <<< "$thresholds"
for n in "$res" "$ref_spp" "$threads" "${ladder_spp[@]}"; do
  if ! [[ "$n" =~ ^[1-9][0-9]*$ ]]; then echo "$0: not a positive integer: '$n'" >&2; exit 2; fi
done
if ! printf '%s\n' "${ladder_spp[@]}" | grep -qx "$at_spp"; then
  echo "$0: --spp-ladder $ladder must hold $at_spp (the tables compare at $at_spp spp)" >&2
  exit 2
fi
top_spp=$(printf '%s\n' "${ladder_spp[@]}" | sort -n | tail -n 1)

scene_file() {
  case "$1" in
    cornell) echo tests/scenes/cornell_box.json ;;
    demo) echo tests/scenes/gltf_demo/demo.gltf ;;
    room) echo tests/scenes/cycles_room/room.gltf ;;
    many_lights) echo tests/scenes/many_lights.json ;;
    *) echo "$0: unknown scene '$1' (cornell, demo, room, many_lights)" >&2; return 1 ;;
  esac
}
for name in "${scene_names[@]}"; do scene_file "$name" > /dev/null || exit 2; done

if ! command -v blender > /dev/null; then
  echo "$0: Blender is missing: installing Debian's blender and python3-numpy with apt-get" >&2
  sudo=()
  if [ "$(id -u)" != 0 ]; then sudo=(sudo); fi
  "${sudo[@]}" apt-get update
  "${sudo[@]}" apt-get install -y blender python3-numpy
fi
for tool in lightfarm exr_compare; do
  if [ ! -x "$bin/$tool" ]; then
    echo "$0: no $bin/$tool: cmake --build build --target lightfarm exr_compare" >&2
    exit 2
  fi
done
if ! "$bin/exr_compare" --help | grep -q -- --rmse; then
  echo "$0: $bin/exr_compare has no --rmse: build it from this tree" >&2
  exit 2
fi
adaptive=0
# Not `--help | grep -q`: under pipefail, grep leaving early fails the pipeline (SIGPIPE).
render_help=$("$bin/lightfarm" render --help)
if grep -q -- --noise-threshold <<< "$render_help"; then adaptive=1; fi
lf_sum=$(sha256sum "$bin/lightfarm" | cut -c1-12)
blender_version=$(blender --version 2> /dev/null | sed -n '1s/Blender //p')
mkdir -p "$out"

now() { date +%s.%N; }
# lightfarm render SCENE OUT.exr LOG ARGS...: the process's wall time in seconds.
lf_render() {
  local scene="$1" exr="$2" log="$3" start end
  shift 3
  start=$(now)
  if ! "$bin/lightfarm" render "$scene" --method path --resolution "$res" --threads "$threads" \
      --filter box --no-progress -o "$exr" "$@" > "$log" 2>&1; then
    echo "$0: lightfarm failed, see $log: $(tail -n 1 "$log")" >&2
    return 1
  fi
  end=$(now)
  awk -v a="$start" -v b="$end" 'BEGIN { printf "%.3f\n", b - a }'
}
# exr_compare IMAGE REFERENCE --rmse: prints "RMSE HALVES LUMINANCE_RATIO".
rmse() {
  "$bin/exr_compare" "$1" "$2" --rmse | awk '{ print $(NF - 2), $NF, $(NF - 4) }'
}
# Points "TIME RMSE" on stdin (any order): RMSE at time $1, log-log, extrapolated outside with a *.
at_time() {
  sort -g | awk -v t="$1" '
    BEGIN { n = 0 }
    { x[n] = log($1); y[n] = log($2); n++ }
    END {
      if (n < 2) { print "nan"; exit }
      lt = log(t); i = 0
      while (i < n - 2 && lt > x[i + 1]) i++
      mark = (lt < x[0] || lt > x[n - 1]) ? "*" : ""
      if (x[i + 1] == x[i]) { printf "%.6g%s\n", exp(y[i]), mark; exit }
      printf "%.6g%s\n", exp(y[i] + (y[i + 1] - y[i]) * (lt - x[i]) / (x[i + 1] - x[i])), mark
    }'
}
ratio() { awk -v a="${1%\*}" -v b="$2" -v m="${1//[^*]/}" 'BEGIN { printf "%.3f%s\n", a / b, m }'; }

echo "# lightfarm vs Cycles $blender_version, ${res}x${res}, $threads threads, ladder $ladder spp, references $ref_spp spp"
echo
echo "$(date -u '+%Y-%m-%d %H:%M UTC'), $(uptime | sed 's/.*load/load/'), lightfarm $lf_sum, commit $(git rev-parse --short HEAD 2> /dev/null || echo '?')"
summary=() targets=() adaptive_rows=()
for name in "${scene_names[@]}"; do
  scene_start=$(now)
  scene=$(scene_file "$name")
  dir="$out/$name"
  mkdir -p "$dir"
  declare -A lf_s=() lf_e=() cy_s=() cy_e=()
  for spp in "${ladder_spp[@]}"; do
    lf_s[$spp]=$(lf_render "$scene" "$dir/lf_$spp.exr" "$dir/lf_$spp.log" --spp "$spp" --seed 0)
  done
  lf_ref="$dir/lf_ref_${res}_${ref_spp}_$lf_sum.exr"
  if [ "$fresh" = 1 ] || [ ! -f "$lf_ref" ]; then
    lf_render "$scene" "$lf_ref" "$dir/lf_ref.log" --spp "$ref_spp" --seed 1 > /dev/null
  fi
  # "camera: perspective from (x, y, z) towards (x, y, z), up (x, y, z), vertical field of view F degrees"
  view=$(sed -n 's/.*camera: \(perspective\|orthographic\) from (\([^)]*\)) towards (\([^)]*\)), up (\([^)]*\)), [a-z ]* \([-0-9.e+]*\).*/\1 \2 \3 \4 \5/p' \
    "$dir/lf_$at_spp.log" | tr -d ',' | sed 's/^perspective/persp/; s/^orthographic/ortho/')
  renders=()
  for spp in "${ladder_spp[@]}"; do renders+=("cy_$spp:$spp:0"); done
  cy_ref_name="cy_ref_${res}_${ref_spp}_${blender_version// /_}"
  if [ "$fresh" = 1 ] || [ ! -f "$dir/$cy_ref_name.exr" ]; then renders+=("$cy_ref_name:$ref_spp:1"); fi
  if [ "$adaptive" = 1 ]; then renders+=("cy_adaptive:$top_spp:0:0.01"); fi
  # shellcheck disable=SC2086  # $view is the projection and ten numbers
  if ! blender -b --factory-startup --python-exit-code 1 --python tools/cycles_bench.py -- \
      "$PWD/$scene" "$dir" "$res" "$threads" $view "${renders[@]}" > "$dir/cycles.log" 2>&1; then
    echo "$0: Cycles failed on $name, see $dir/cycles.log" >&2
    exit 1
  fi
  while read -r _ render seconds; do
    case "$render" in cy_[0-9]*) cy_s[${render#cy_}]=$seconds ;; cy_adaptive) cy_adaptive_s=$seconds ;; esac
  done < <(grep '^CYCLES_SECONDS ' "$dir/cycles.log")
  for spp in "${ladder_spp[@]}"; do
    read -r "lf_e[$spp]" _ _ < <(rmse "$dir/lf_$spp.exr" "$lf_ref")
    read -r "cy_e[$spp]" _ _ < <(rmse "$dir/cy_$spp.exr" "$dir/$cy_ref_name.exr")
  done
  read -r _ ref_halves ref_ratio < <(rmse "$lf_ref" "$dir/$cy_ref_name.exr")

  echo
  echo "## $name ($scene)"
  echo
  echo "| spp | lightfarm s | lightfarm RMSE | Cycles s | Cycles RMSE | RMSE ratio |"
  echo "| ---: | ---: | ---: | ---: | ---: | ---: |"
  for spp in "${ladder_spp[@]}"; do
    echo "| $spp | ${lf_s[$spp]} | ${lf_e[$spp]} | ${cy_s[$spp]} | ${cy_e[$spp]} | $(ratio "${lf_e[$spp]}" "${cy_e[$spp]}") |"
  done
  t_c=${cy_s[$at_spp]}
  lf_at=$(for spp in "${ladder_spp[@]}"; do echo "${lf_s[$spp]} ${lf_e[$spp]}"; done | at_time "$t_c")
  speed=$(ratio "$t_c" "${lf_s[$at_spp]}")
  equal_spp=$(ratio "${lf_e[$at_spp]}" "${cy_e[$at_spp]}")
  equal_time=$(ratio "$lf_at" "${cy_e[$at_spp]}")
  # From $at_spp to $top_spp spp an RMSE should fall as 1/sqrt(spp); one that hardly falls is
  # the reference's own error (fireflies in it), and the scene's ratios are then meaningless.
  for who in lightfarm Cycles; do
    if [ "$who" = lightfarm ]; then e_at=${lf_e[$at_spp]} e_top=${lf_e[$top_spp]}; else e_at=${cy_e[$at_spp]} e_top=${cy_e[$top_spp]}; fi
    awk -v w="$who" -v a="$e_at" -v t="$e_top" -v n="$at_spp" -v m="$top_spp" 'BEGIN {
      if (m > n && t > 0.8 * a) printf("\nWARNING: %s'"'"'s RMSE falls only from %s to %s between %d and %d spp (1/sqrt(spp): %.3g): its reference is probably dominated by its own outliers; this scene'"'"'s ratios are not valid.\n", w, a, t, n, m, a * sqrt(n / m)) }'
  done
  echo
  echo "lightfarm's RMSE at Cycles' $at_spp-spp time ($t_c s): $lf_at; lightfarm reference's own estimated RMSE $ref_halves"
  summary+=("| $name | ${lf_s[$at_spp]} | $t_c | $speed | $equal_spp | $equal_time | $ref_ratio | $ref_halves |")
  if [ "$name" = cornell ]; then
    targets+=("| cornell | speed at $at_spp spp >= 2x | $speed | $(awk -v x="$speed" 'BEGIN { print (x + 0 >= 2 ? "met" : "not met") }') |")
    limit=0.6
  else
    limit=1
  fi
  targets+=("| $name | equal-time RMSE ratio <= $limit | $equal_time | $(awk -v x="${equal_time%\*}" -v l="$limit" 'BEGIN { print (x + 0 <= l ? "met" : "not met") }') |")

  if [ "$adaptive" = 1 ]; then
    points="" shown=()
    for t in "${threshold_list[@]}"; do
      s=$(lf_render "$scene" "$dir/lf_adaptive_$t.exr" "$dir/lf_adaptive_$t.log" \
        --noise-threshold "$t" --max-spp "$top_spp" --seed 0)
      read -r e _ _ < <(rmse "$dir/lf_adaptive_$t.exr" "$lf_ref")
      points+="$s $e"$'\n'
      shown+=("$t: $s s, $e")
    done
    read -r cy_adaptive_e _ _ < <(rmse "$dir/cy_adaptive.exr" "$dir/$cy_ref_name.exr")
    lf_adaptive_at=$(printf '%s' "$points" | at_time "$cy_adaptive_s")
    adaptive_rows+=("| $name | $cy_adaptive_s | $cy_adaptive_e | $(printf '%s; ' "${shown[@]}" | sed 's/; $//') | $lf_adaptive_at | $(ratio "$lf_adaptive_at" "$cy_adaptive_e") |")
  fi
  unset lf_s lf_e cy_s cy_e
  echo
  echo "$name: $(awk -v a="$scene_start" -v b="$(now)" 'BEGIN { printf "%.0f", b - a }') s elapsed"
done

echo
echo "## Summary ($at_spp spp; ratios lightfarm / Cycles except speed, Cycles s / lightfarm s)"
echo
echo "| scene | lightfarm s | Cycles s | speed | RMSE ratio, equal spp | RMSE ratio, equal time | reference mean ratio | lightfarm reference RMSE (est.) |"
echo "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
printf '%s\n' "${summary[@]}"
echo
echo "\* extrapolated beyond lightfarm's ladder."
echo
echo "## Issue 31's targets"
echo
echo "| scene | target | measured | |"
echo "| --- | --- | ---: | --- |"
printf '%s\n' "${targets[@]}"
echo
echo "## Adaptive sampling"
echo
if [ "$adaptive" = 1 ]; then
  echo "Cycles at noise threshold 0.01 against lightfarm --noise-threshold $thresholds (--max-spp $top_spp)"
  echo
  echo "| scene | Cycles s | Cycles RMSE | lightfarm per threshold (T: s, RMSE) | lightfarm RMSE at Cycles' time | ratio |"
  echo "| --- | ---: | ---: | --- | ---: | ---: |"
  printf '%s\n' "${adaptive_rows[@]}"
else
  echo "Skipped: \`lightfarm render --help\` ($bin/lightfarm) has no --noise-threshold."
fi
echo
echo "$(uptime | sed 's/.*load/load/') at the end; images and logs in $out"

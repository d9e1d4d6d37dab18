#!/usr/bin/env bash
# lightfarm against Blender's Cycles on Khronos' glTF sample assets (tests/scenes/khronos, as
# manifest.txt lists them; those it expects to fail to load are skipped). Not in CI.
#
#   tools/khronos_vs_cycles.sh [--size 128] [--spp 64] [--out DIR] [ASSET...]
#
# Each asset renders twice at SIZE x SIZE and SPP samples per pixel, one render at a time under
# nice: lightfarm (path tracer, box filter) through a JSON scene that includes the glTF and adds
# a uniform white sky of radiance 1, then Cycles (tools/khronos_cycles.py: the same sky, the
# file's own lights, Standard view transform, linear EXR, unclamped, no denoising, box filter)
# from the camera lightfarm logs (`--camera auto`, or the asset's own camera as the manifest
# says). The script checks lightfarm's auto framing against the same framing computed in Blender
# from the imported meshes. Prints a Markdown table: per asset the mean R, G, B over the pixels
# Cycles sees the asset in (its film is transparent), lightfarm / Cycles per channel and in
# luminance, and both times; writes DIR/ASSET.png (lightfarm left, Cycles right, sRGB, clamped).
#
# Needs build/bin/lightfarm and build/bin/exr_compare (cmake --build build --target lightfarm
# exr_compare; LF_BIN_DIR elsewhere) and Debian's Blender 3.4 with numpy:
# sudo apt-get install blender python3-numpy.
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${LF_BIN_DIR:-build/bin}"
size=128 spp=64 out=/tmp/khronos_vs_cycles
usage="usage: $0 [--size N] [--spp N] [--out DIR] [ASSET...]"
only=()
while [ $# -gt 0 ]; do
  case "$1" in
    --size) size="$2"; shift 2 ;;
    --spp) spp="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    -*) echo "$usage" >&2; exit 2 ;;
    *) only+=("$1"); shift ;;
  esac
done
if ! command -v blender >/dev/null; then
  echo "$0: needs Blender: sudo apt-get install blender python3-numpy" >&2
  exit 2
fi
for tool in lightfarm exr_compare; do
  if [ ! -x "$bin/$tool" ]; then
    echo "$0: no $bin/$tool: cmake --build build --target lightfarm exr_compare" >&2
    exit 2
  fi
done
mkdir -p "$out"
dir="$PWD/tests/scenes/khronos"

# "NAME CAMERA" per asset that should load, from the manifest.
assets=$(awk '
  function flush() { if (name != "" && !error) print name, camera }
  $1 == "asset" { flush(); name = $2; camera = "auto"; error = 0 }
  $1 == "camera" { camera = $2 }
  $1 == "error" { error = 1 }
  END { flush() }' "$dir/manifest.txt")

echo "lightfarm against Cycles, ${size}x${size}, $spp spp; means over the pixels Cycles sees the asset in"
echo
echo "| asset | pixels | lightfarm R, G, B | Cycles R, G, B | ratio R | ratio G | ratio B | ratio lum | lightfarm s | Cycles s |"
echo "| --- | ---: | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |"
while read -r name camera; do
  if [ ${#only[@]} -gt 0 ] && ! printf '%s\n' "${only[@]}" | grep -qx "$name"; then continue; fi
  scene="$out/$name.json"
  printf '{"materials": {}, "lights": [{"type": "environment", "radiance": 1}],\n "shapes": [{"type": "gltf", "file": "%s"}]}\n' \
    "$dir/$name/$name.gltf" > "$scene"
  if ! nice -n 15 "$bin/lightfarm" render "$scene" --camera "$camera" --resolution "$size" \
      --spp "$spp" --threads 2 --no-progress -o "$out/$name.lightfarm.exr" > "$out/$name.lightfarm.log" 2>&1; then
    echo "| $name | lightfarm failed: $(tail -n 1 "$out/$name.lightfarm.log") |"
    continue
  fi
  # "camera: perspective from (x, y, z) towards (x, y, z), up (x, y, z), vertical field of view F degrees"
  view=$(sed -n 's/.*camera: \(perspective\|orthographic\) from (\([^)]*\)) towards (\([^)]*\)), up (\([^)]*\)), [a-z ]* \([-0-9.e+]*\).*/\1 \2 \3 \4 \5/p' \
    "$out/$name.lightfarm.log" | tr -d ',' | sed 's/^perspective/persp/; s/^orthographic/ortho/')
  lf_seconds=$(sed -n 's/.* samples in \([0-9.]*\) s:.*/\1/p' "$out/$name.lightfarm.log")
  # shellcheck disable=SC2086  # $view is the projection and ten numbers
  if ! nice -n 15 blender -b --factory-startup --python tools/khronos_cycles.py -- \
      "$dir/$name/$name.gltf" "$out/$name.cycles.exr" "$size" "$spp" $view > "$out/$name.cycles.log" 2>&1 ||
      [ ! -f "$out/$name.cycles.exr" ]; then
    echo "| $name | Cycles failed: see $out/$name.cycles.log |"
    continue
  fi
  cycles_seconds=$(sed -n 's/^CYCLES_SECONDS //p' "$out/$name.cycles.log")
  if [ "$camera" = auto ]; then
    # Blender's framing of the same bounds: the same camera to 1e-4 of the viewing distance.
    read -r -a lf <<< "$view"
    read -r -a bl <<< "$(sed -n 's/^AUTO //p' "$out/$name.cycles.log")"
    awk -v n="$name" -v l="${lf[*]:1:6}" -v b="${bl[*]:0:6}" 'BEGIN {
      split(l, x, " "); split(b, y, " "); d = 0; e = 0
      for (i = 1; i <= 3; i++) { d += (x[i] - x[i + 3]) ^ 2; e += (x[i] - y[i]) ^ 2 + (x[i + 3] - y[i + 3]) ^ 2 }
      if (e > 1e-8 * d) printf("%s: auto camera differs: lightfarm %s, Blender %s\n", n, l, b) > "/dev/stderr" }'
  fi
  read -r _ pixels _ a_r a_g a_b _ _ b_r b_g b_b _ _ r_r r_g r_b r_l < <(
    "$bin/exr_compare" "$out/$name.lightfarm.exr" "$out/$name.cycles.exr" --png "$out/$name.png")
  echo "| $name | $pixels | $a_r, $a_g, $a_b | $b_r, $b_g, $b_b | $r_r | $r_g | $r_b | $r_l | $lf_seconds | $cycles_seconds |"
done <<< "$assets"
echo
echo "side by side (lightfarm left, Cycles right): $out/ASSET.png"

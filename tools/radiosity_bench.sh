#!/usr/bin/env bash
# The radiosity benchmark of issue 33 ("Speed and memory"), tools/radiosity_bench.md. For each
# scene (the Cornell box at --patch-size 0.02; offices of 10k, 100k, 1M triangles written by
# tools/make_office.py) and each solver (flat: today's dense form factors; hierarchical:
# --radiosity hierarchical --link-error E), runs `lightfarm render --method radiosity` under
# /usr/bin/time -v and prints the time to solution (the render's "radiosity" phase: meshing, form
# factors or links, solve), the render's CPU seconds, the peak RSS, the solve's statistics from
# the EXR header (lightfarm.radiosity.*: patches, links per element where the solver writes
# them) and the agreement with a path-traced render of the same camera, compared in 16x16-pixel
# blocks against the path tracer's own standard error (exr_compare --blocks). With
# --farm-rounds N, also times the Cornell box job (256^2, --patch-size 0.02) on a local farm of
# two 1-thread workers against `lightfarm render --threads 2`, N rounds, for each solver.
#
#   tools/radiosity_bench.sh [--scenes cornell,10k,100k,1M] [--solvers flat,hierarchical]
#       [--link-error 1e-4] [--spp 16] [--ref-spp 256] [--threads 2] [--timeout 900]
#       [--farm-rounds 0] [--out DIR]
#
# Flat is skipped above 20k triangles (its form factors are n^2: ~240 MiB at 10k patches, 24 GB
# at 100k). Hierarchical rows say "no --radiosity flag" on a build without the solver. Needs
# build/bin/{lightfarm,exr_compare} (or LF_BIN_DIR; lightfarm-server and lightfarm-worker for
# the farm) and Debian's python3 with python3-numpy. DIR keeps the scenes, the path references
# (reused by later runs with the same --ref-spp) and every log; a shared machine is noisy, so the
# load average is printed before and after.
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${LF_BIN_DIR:-build/bin}"
scenes=cornell,10k,100k,1M solvers=flat,hierarchical link_error=1e-4 spp=16 ref_spp=256
threads=2 timeout=900 farm_rounds=0 out=""
usage="usage: $0 [--scenes LIST] [--solvers LIST] [--link-error E] [--spp N] [--ref-spp N]"
usage+=" [--threads N] [--timeout S] [--farm-rounds N] [--out DIR]"
source tools/bench_options.sh
parse_options "scenes solvers link-error spp ref-spp threads timeout farm-rounds out" "$@"
for tool in lightfarm exr_compare; do
  [ -x "$bin/$tool" ] ||
    { echo "$0: no $bin/$tool: cmake --build build --target $tool" >&2; exit 1; }
done
"$bin/exr_compare" --help | grep -q -- --blocks ||
  { echo "$0: $bin/exr_compare has no --blocks: build it from this tree" >&2; exit 1; }
[ -n "$out" ] || out="$(mktemp -d /tmp/radiosity_bench.XXXXXX)"
mkdir -p "$out"
out="$(cd "$out" && pwd)"
hierarchical_built=0
"$bin/lightfarm" render --help | grep -q -- '--radiosity ' && hierarchical_built=1
echo "radiosity_bench: scenes $scenes, solvers $solvers (link error $link_error), display" \
  "$spp spp, path reference $ref_spp spp, $threads threads; output in $out"
echo "machine: $(nproc) cores, load average $(cut -d' ' -f1-3 /proc/loadavg) (1, 5, 15 min)"

# The scene file of a name, written on first use: cornell, or an office of 10k, 100k, 1M, ...
scene_file() {
  case "$1" in
    cornell) echo "$PWD/tests/scenes/cornell_box.json" ;;
    *)
      local n="${1/k/000}"
      n="${n/M/000000}"
      [ -f "$out/office_$1/office.json" ] ||
        /usr/bin/python3 tools/make_office.py --triangles "$n" --out "$out/office_$1" \
          >"$out/office_$1.log"
      echo "$out/office_$1/office.json"
      ;;
  esac
}

# The render options of a scene and solver, without the method.
radiosity_args() {
  local scene="$1" solver="$2"
  [ "$scene" != cornell ] || echo --patch-size 0.02
  [ "$solver" = flat ] || echo --radiosity hierarchical --link-error "$link_error"
}

# The actual triangle count: the generator's line, or the mesh's for the Cornell box.
triangles() {
  if [ "$1" = cornell ]; then
    echo 32
  else
    sed -n 's/.*, \([0-9]*\) triangles (.*/\1/p' "$out/office_$1.log"
  fi
}

printf '%-8s %9s %-13s %9s %9s %9s %8s %8s %10s %8s %8s %8s %8s %8s %8s\n' scene triangles \
  solver elements solve_s total_s cpu_s rss_MiB links/el mean_rel wtd_rel worst b3se_mn \
  b3se_max ref_se
# A row that says why a scene and solver has no figures.
row() { printf '%-8s %9s %-13s %s\n' "$scene" "$(triangles "$scene")" "$solver" "$*"; }
IFS=, read -r -a scene_list <<<"$scenes"
IFS=, read -r -a solver_list <<<"$solvers"
for scene in "${scene_list[@]}"; do
  file="$(scene_file "$scene")"
  ref="$out/path_${scene}_${ref_spp}.exr"
  for solver in "${solver_list[@]}"; do
    name="${scene}_${solver}"
    if [ "$solver" = flat ] && [ "$(triangles "$scene")" -gt 20000 ]; then
      row "skipped: dense n^2 form factors"
      continue
    fi
    if [ "$solver" != flat ] && [ "$hierarchical_built" = 0 ]; then
      row "not run: this lightfarm has no --radiosity flag"
      continue
    fi
    # shellcheck disable=SC2046  # radiosity_args prints separate words
    if ! /usr/bin/time -v timeout "$timeout" "$bin/lightfarm" render "$file" \
      -o "$out/$name.exr" --png "$out/$name.png" --method radiosity --spp "$spp" \
      --threads "$threads" --no-progress $(radiosity_args "$scene" "$solver") \
      >"$out/$name.log" 2>&1; then
      why=$(grep -m1 -i -E 'error|timeout|killed' "$out/$name.log" || tail -1 "$out/$name.log")
      row "failed: $why"
      continue
    fi
    # "time: load 0.02 s, radiosity 26.25 s (mesh ..., form factors ..., solve ...), ..."
    solve=$(sed -n 's/^time:.* radiosity \([0-9.]*\) s.*/\1/p' "$out/$name.log")
    total=$(sed -n 's/^time:.* total \([0-9.]*\) s.*/\1/p' "$out/$name.log")
    rss=$(awk '/Maximum resident set size/ { printf "%.0f", $NF / 1024 }' "$out/$name.log")
    # CPU seconds (user + system) of the whole render: what a busy machine does not inflate.
    cpu=$(awk '/(User|System) time \(seconds\)/ { t += $NF } END { printf "%.1f", t }' \
      "$out/$name.log")
    compare="$out/$name.compare"
    # The path-traced reference, once per scene (and kept in DIR for later runs).
    if [ ! -f "$ref" ]; then
      timeout "$timeout" "$bin/lightfarm" render "$file" -o "$ref" --method path \
        --spp "$ref_spp" --threads "$threads" --seed 7 --no-progress \
        >"$out/path_${scene}_${ref_spp}.log" 2>&1 || rm -f "$ref"
    fi
    if [ -f "$ref" ]; then
      "$bin/exr_compare" "$out/$name.exr" "$ref" --blocks 16 >"$compare"
    else
      echo "no path reference (see $out/path_${scene}_${ref_spp}.log)" >"$compare"
    fi
    # Elements: the hierarchy's leaves if the solver says, else the patches. Links per element
    # from whatever attribute the solver names so.
    elements=$(awk '$1 == "attribute" && $2 ~ /\.(elements|leaves)$/ { print $3 }' "$compare")
    [ -n "$elements" ] ||
      elements=$(awk '$1 == "attribute" && $2 ~ /\.patches$/ { print $3 }' "$compare")
    links=$(awk '$1 == "attribute" && tolower($2) ~ /links?per/ { print $3 }' "$compare")
    agreement=$(awk '$1 == "blocks" {
      for (i = 1; i < NF; i++) v[$i] = $(i + 1)
      printf "%8s %8s %8s %8s %8s %8s", v["mean_rel"], v["weighted_rel"], v["worst_rel"],
        v["mean_beyond_3se"], v["worst_beyond_3se"], v["median_se"] }' "$compare")
    printf '%-8s %9s %-13s %9s %9s %9s %8s %8s %10s %s\n' "$scene" "$(triangles "$scene")" \
      "$solver" "${elements:--}" "${solve:--}" "${total:--}" "${cpu:--}" "${rss:--}" \
      "${links:--}" "${agreement:-no comparison}"
  done
done
echo "machine after: load average $(cut -d' ' -f1-3 /proc/loadavg)"
[ "$farm_rounds" -gt 0 ] || exit 0

# The farm: the Cornell box job, 256^2, --patch-size 0.02, from submit to the end of watch, on
# two 1-thread workers, against the same render locally with 2 threads, round by round. Also as
# one command (`submit --watch`): the same job without the second client process.
for tool in lightfarm-server lightfarm-worker; do
  [ -x "$bin/$tool" ] || { echo "$0: no $bin/$tool" >&2; exit 1; }
done
# shellcheck source=tools/farm_common.sh  # sets work, address
source tools/farm_common.sh
start_farm radiosity_bench
now() { date +%s.%N; }
median() {
  printf '%s\n' "$@" | sort -n |
    awk '{r[NR] = $1} END {print (NR % 2) ? r[(NR + 1) / 2] : (r[NR / 2] + r[NR / 2 + 1]) / 2}'
}
scene="$PWD/tests/scenes/cornell_box.json"
for solver in "${solver_list[@]}"; do
  if [ "$solver" != flat ] && [ "$hierarchical_built" = 0 ]; then
    echo "farm $solver: not run: this lightfarm has no --radiosity flag"
    continue
  fi
  # shellcheck disable=SC2207  # radiosity_args prints separate words
  args=(--method radiosity --spp "$spp" $(radiosity_args cornell "$solver"))
  ratios=()
  ratios_one=()
  farm_s=
  one_s=
  # submit + watch (the job's id kept for the comparison with local mode's image) and
  # submit --watch, in turn first and second from round to round.
  two_commands() {
    job="$("$bin/lightfarm" submit "$scene" --server "$address" "${args[@]}" | tail -n 1)"
    "$bin/lightfarm" watch "$job" --server "$address" >/dev/null
  }
  one_command() {
    "$bin/lightfarm" submit "$scene" --server "$address" "${args[@]}" --watch >/dev/null
  }
  # timed VAR FUNCTION: FUNCTION's seconds into VAR (not in a subshell: two_commands sets job).
  timed() {
    local start
    start="$(now)"
    "$2"
    printf -v "$1" '%s' "$(awk -v a="$start" -v b="$(now)" 'BEGIN { printf "%.2f", b - a }')"
  }
  for round in $(seq "$farm_rounds"); do
    t0="$(now)"
    "$bin/lightfarm" render "$scene" -o "$work/local.exr" --threads 2 --no-progress "${args[@]}" \
      >/dev/null 2>&1
    local_s=$(awk -v a="$t0" -v b="$(now)" 'BEGIN { printf "%.2f", b - a }')
    if [ $((round % 2)) = 1 ]; then
      timed farm_s two_commands
      timed one_s one_command
    else
      timed one_s one_command
      timed farm_s two_commands
    fi
    # The farm promises local mode's bits: an RMSE of 0 between the two images.
    "$bin/lightfarm" fetch "$job" --server "$address" -o "$work/farm.exr" >/dev/null
    rmse=$("$bin/exr_compare" "$work/farm.exr" "$work/local.exr" --rmse |
      awk '{ for (i = 1; i < NF; i++) if ($i == "rmse") print $(i + 1) }')
    ratios+=("$(awk -v l="$local_s" -v f="$farm_s" 'BEGIN { printf "%.3f", l / f }')")
    ratios_one+=("$(awk -v l="$local_s" -v f="$one_s" 'BEGIN { printf "%.3f", l / f }')")
    echo "farm $solver round $round: local (2 threads) ${local_s} s, farm (2 x 1 thread)" \
      "${farm_s} s submit..watch (${one_s} s submit --watch), throughput farm/local" \
      "${ratios[-1]} (${ratios_one[-1]}), rmse farm-local $rmse"
  done
  echo "farm $solver: median throughput farm/local $(median "${ratios[@]}") (target >= 0.90)" \
    "($(median "${ratios_one[@]}") with submit --watch); load average" \
    "$(cut -d' ' -f1-3 /proc/loadavg)"
done

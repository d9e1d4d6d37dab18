#!/usr/bin/env bash
# CI's sanitizer and fuzz runs (README, Tests), after the normal suite:
#  1. a clang build (build-san/) of lf_core and lf_job with AddressSanitizer, UndefinedBehavior-
#     Sanitizer (any report aborts) and libFuzzer's coverage;
#  2. the core and job unit tests under those sanitizers, JOBS (default 2) programs at a time;
#  3. each fuzz target of tests/fuzz for FUZZ_SECONDS (default 15) from its seed corpus, JOBS at
#     a time. A crash fails the run and is kept as build-san/fuzz-crashes/TARGET-*: add it to
#     tests/fuzz/regressions/TARGET/, which every build's ctest replays.
#  4. a ThreadSanitizer build (build-tsan/) of the coordinator's scheduler, lease, store and
#     timeout tests and farm_concurrency_test (a Farm driven from many threads without gRPC)
#     (TSAN_TESTS), run there with tests/sanitizers/tsan.supp. The gRPC tests are not run under
#     it: Debian's gRPC and Abseil are not built with ThreadSanitizer, so it cannot see their
#     locks and reports their hand-offs between threads as races (fake_worker_farm_test: 1429
#     false reports with the suppressions, in gRPC's metadata maps and Abseil's Status and Cord).
# Prints how long each part took.
set -euo pipefail
cd "$(dirname "$0")/.."
fuzz_seconds=${FUZZ_SECONDS:-15}
# vdb_fuzz (its corpus and regressions replay in every build's ctest) is not fuzzed here: it
# finds OpenVDB's own unchecked sizes within a second (a forged blosc block of 64 GiB, which
# AddressSanitizer aborts on and a normal build refuses with bad_alloc), a limitation of the
# library that docs/scene-format.md states, not of lightfarm's code.
fuzzers=(scene_json_fuzz gltf_fuzz mesh_fuzz texture_fuzz codec_fuzz job_record_fuzz)
mapfile -t unit_tests < <(ls tests/unit/core/*_test.cc tests/unit/job/*_test.cc | xargs -n1 basename | sed 's/\.cc$//')
parallel=${JOBS:-2}
# in_parallel CMD ARG...: CMD ARG for each ARG, `parallel` at a time (each test program and fuzzer
# is mostly one thread); fails, after all have run, when any failed (each failure leaves a mark:
# a status reaped early by `wait -n` is not lost).
in_parallel() {
  local cmd=$1 arg marks
  shift
  marks=$(mktemp -d)
  for arg in "$@"; do
    while [ "$(jobs -rp | wc -l)" -ge "$parallel" ]; do wait -n || true; done
    { "$cmd" "$arg" || touch "$marks/$arg"; } &
  done
  wait
  local failed=0
  [ -z "$(ls -A "$marks")" ] || failed=1
  rm -rf "$marks"
  return $failed
}
# run_test DIR SANITIZERS PROGRAM: a test program built in DIR; a failure prints the end of its log.
run_test() {
  (cd "$test_dir" && LF_TEST_QUIET=1 "bin/$1" --gtest_brief=1 >"$1.log" 2>&1) || {
    echo "sanitize: $1 failed under $test_sanitizers:"; tail -80 "$test_dir/$1.log"; return 1; }
}
# run_tests DIR SANITIZERS PROGRAM...: each test program built in DIR; any failure ends the run.
run_tests() {
  test_dir=$1 test_sanitizers=$2
  shift 2
  in_parallel run_test "$@" || exit 1
}
t0=$(date +%s)
cmake -S . -B build-san -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" \
  -DCMAKE_CXX_COMPILER=clang++ \
  -DLF_SANITIZE=address,undefined -DLF_FUZZ=ON >/dev/null
cmake --build build-san -j"$parallel" --target "${unit_tests[@]}" "${fuzzers[@]}" >/dev/null
t1=$(date +%s)
echo "sanitize: build of ${#unit_tests[@]} unit test programs and ${#fuzzers[@]} fuzz targets with address,undefined: $((t1 - t0)) s"
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
export LSAN_OPTIONS=suppressions=$PWD/tests/sanitizers/lsan.supp
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
run_tests build-san address,undefined "${unit_tests[@]}"
t2=$(date +%s)
echo "sanitize: ${#unit_tests[@]} unit test programs passed under address,undefined: $((t2 - t1)) s"
mkdir -p build-san/fuzz-crashes
fuzz() {
  local f=$1
  rm -rf "build-san/corpus/$f" && mkdir -p "build-san/corpus/$f"
  # New inputs go to build-san/corpus; the seeds in the source tree are only read.
  if ! build-san/bin/$f -max_total_time="$fuzz_seconds" -print_final_stats=1 \
      -artifact_prefix="build-san/fuzz-crashes/$f-" "build-san/corpus/$f" "tests/fuzz/corpus/$f" \
      >"build-san/$f.log" 2>&1; then
    echo "sanitize: $f found a crash:"; tail -60 "build-san/$f.log"; ls build-san/fuzz-crashes; return 1
  fi
  echo "sanitize: $f: $(grep -o 'stat::number_of_executed_units: *[0-9]*' "build-san/$f.log" | grep -o '[0-9]*$') runs in ${fuzz_seconds} s, no crash"
}
in_parallel fuzz "${fuzzers[@]}" || exit 1
t3=$(date +%s)
echo "sanitize: fuzzing: $((t3 - t2)) s"
tsan_tests=(${TSAN_TESTS:-scheduler_test scheduler_tasks_test scheduling_policies_test splat_scheduler_test
  lease_table_test worker_registry_test job_store_test sqlite_job_store_test timeout_checker_test
  task_log_store_test farm_concurrency_test})
cmake -S . -B build-tsan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" \
  -DLF_SANITIZE=thread >/dev/null
cmake --build build-tsan -j"$parallel" --target "${tsan_tests[@]}" >/dev/null
t4=$(date +%s)
echo "sanitize: build of ${#tsan_tests[@]} coordinator test programs with thread: $((t4 - t3)) s"
export TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1:suppressions=$PWD/tests/sanitizers/tsan.supp
run_tests build-tsan thread "${tsan_tests[@]}"
t5=$(date +%s)
echo "sanitize: ${#tsan_tests[@]} coordinator test programs passed under thread: $((t5 - t4)) s; all: $((t5 - t0)) s"

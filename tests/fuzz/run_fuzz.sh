#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (ASan + UBSan) in their own build
# folder and runs each for a bounded time from the committed seed corpus.
# Exits non-zero if any target crashed, leaked, timed out on an input or broke
# an invariant; the offending inputs are left in $BUILD/artifacts/.
#
#   bash tests/fuzz/run_fuzz.sh [SECONDS_PER_TARGET (default 20)] [TARGET ...]
#
# Targets: mitsuba_xml gltf job_spec obj ply serialized (default: all).
# Environment: GDVR_FUZZ_BUILD_DIR (default build-fuzz), GDVR_FUZZ_JOBS (ninja -j, default 2).
# A crash found becomes a regression test in tests/core/... (docs/correctness.md).
set -euo pipefail
cd "$(dirname "$0")/../.."

SECONDS_PER=${1:-20}
shift || true
TARGETS=("$@")
[ ${#TARGETS[@]} -gt 0 ] || TARGETS=(mitsuba_xml gltf job_spec obj ply serialized)
BUILD=${GDVR_FUZZ_BUILD_DIR:-build-fuzz}

for tool in clang clang++; do
  command -v "$tool" >/dev/null || { echo "run_fuzz: $tool not found (deploy/install-deps.sh installs clang)" >&2; exit 1; }
done
mkdir -p "$BUILD"
if [ ! -f "$BUILD/build.ninja" ]; then
  CC=clang CXX=clang++ cmake -S tests/fuzz -B "$BUILD" -G Ninja >"$BUILD/configure.log" 2>&1 ||
    { cat "$BUILD/configure.log" >&2; exit 1; }
fi
ninja -C "$BUILD" -j"${GDVR_FUZZ_JOBS:-2}" $(printf 'fuzz_%s ' "${TARGETS[@]}") >/dev/null ||
  { ninja -C "$BUILD" -j1 $(printf 'fuzz_%s ' "${TARGETS[@]}") >&2; exit 1; }

mkdir -p "$BUILD/artifacts"
failed=()
for t in "${TARGETS[@]}"; do
  work="$BUILD/corpus/$t"  # new inputs land here, never in the committed seeds
  mkdir -p "$work"
  log="$BUILD/fuzz_$t.log"
  echo "run_fuzz: $t for ${SECONDS_PER}s"
  rc=0
  ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    "$BUILD/fuzz_$t" -max_total_time="$SECONDS_PER" -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
    -print_final_stats=1 -artifact_prefix="$BUILD/artifacts/$t-" "$work" "tests/fuzz/corpus/$t" >"$log" 2>&1 || rc=$?
  grep -E "^stat::number_of_executed_units|^#[0-9]+ *DONE" "$log" | tail -2 | sed "s/^/run_fuzz: $t: /"
  if [ $rc -ne 0 ]; then
    failed+=("$t")
    echo "run_fuzz: $t FAILED (exit $rc); log: $log" >&2
    grep -E "ERROR|runtime error|SUMMARY|invariant|Test unit written" "$log" | head -20 >&2
  fi
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "run_fuzz: crashes in: ${failed[*]}; inputs in $BUILD/artifacts/" >&2
  exit 1
fi
echo "run_fuzz: ${#TARGETS[@]} target(s) ran ${SECONDS_PER}s each without a crash"

#!/usr/bin/env bash
# Builds the libFuzzer targets with clang under ASan + UBSan into BUILD_DIR and runs each for
# SECONDS on a copy of its seed corpus (tests/fuzz/corpus/NAME). Fails on any crash, leak,
# sanitizer report, timeout or out-of-memory; the crashing input is left in BUILD_DIR/fuzz-artifacts.
# Third-party decoders run in child processes (src/lightvol/core/detail/isolated.h): when one of them fails, the
# child may leave an artifact too (libFuzzer's state is inherited) while lightvol returns an error
# and the run goes on. Each artifact is replayed after the run: those the target survives are
# moved to BUILD_DIR/fuzz-artifacts/contained and listed, not counted as failures. A sanitizer
# report that a child printed in lightvol's own code fails the run all the same.
#   tests/fuzz/run_fuzzers.sh BUILD_DIR [SECONDS=20] [TARGET...]
# With RUNS=N (and optionally SEED, default 1) each target stops after N inputs from a fixed seed,
# SECONDS still capping it: the same inputs on every machine, as CI wants.
set -euo pipefail
if [ $# -lt 1 ]; then
  echo "usage: $0 BUILD_DIR [SECONDS] [TARGET...]" >&2
  exit 2
fi
build_dir=$1
seconds=${2:-20}
shift $(( $# >= 2 ? 2 : 1 ))
source_dir=$(cd "$(dirname "$0")/../.." && pwd)
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(light depth_image mesh volumes jobs text)
cxx=${CXX:-clang++-14}; command -v "$cxx" >/dev/null || cxx=clang++

# Lean: only the library and the fuzz targets (no CLI, no GL, no tests).
cmake -S "$source_dir" -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_COMPILER="$cxx" \
  -DLIGHTVOL_BUILD_FUZZERS=ON -DLIGHTVOL_SANITIZE=address,undefined -DLIGHTVOL_WERROR=OFF \
  -DLIGHTVOL_BUILD_CLI=OFF -DLIGHTVOL_WITH_GL=OFF -DLIGHTVOL_BUILD_TESTS=OFF -DLIGHTVOL_BUILD_BENCH=OFF >/dev/null
ninja -C "$build_dir" -j2 $(printf 'fuzz_%s ' "${targets[@]}")

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:allocator_may_return_null=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$source_dir/tests/fuzz/lsan.supp}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
artifacts="$build_dir/fuzz-artifacts"
mkdir -p "$artifacts"
status=0
for t in "${targets[@]}"; do
  work="$build_dir/fuzz-corpus/$t"   # grows while fuzzing; the seeds in the tree stay untouched
  mkdir -p "$work"
  echo "== fuzz_$t for ${seconds}s"
  repeat=()
  [ -z "${RUNS:-}" ] || repeat=(-runs="$RUNS" -seed="${SEED:-1}")
  if ! "$build_dir/tests/fuzz/fuzz_$t" "$work" "$source_dir/tests/fuzz/corpus/$t" "${repeat[@]}" \
      -max_total_time="$seconds" -timeout=10 -rss_limit_mb=3072 -malloc_limit_mb=1024 -max_len=65536 \
      -artifact_prefix="$artifacts/${t}-" -print_final_stats=1 >"$build_dir/fuzz_$t.log" 2>&1; then
    echo "fuzz_$t: FAILED, see $build_dir/fuzz_$t.log and $artifacts" >&2
    tail -n 40 "$build_dir/fuzz_$t.log" >&2
    status=1
  else
    # The last lines only: a child that hit the malloc limit prints libFuzzer's statistics too.
    grep -E "^stat::number_of_executed_units|^Done" "$build_dir/fuzz_$t.log" | tail -n 2 || true
  fi
  # A child's report in our own code is a failure too (tests/fuzz/child_reports.py).
  python3 "$source_dir/tests/fuzz/child_reports.py" "$build_dir/fuzz_$t.log" "$source_dir" || status=1
  contained=0
  for a in "$artifacts/${t}-"*; do
    [ -f "$a" ] || continue
    if "$build_dir/tests/fuzz/fuzz_$t" -rss_limit_mb=3072 -malloc_limit_mb=1024 -timeout=10 "$a" >/dev/null 2>&1; then
      mkdir -p "$artifacts/contained"
      mv "$a" "$artifacts/contained/"
      contained=$((contained + 1))
    fi
  done
  [ "$contained" -eq 0 ] || echo "fuzz_$t: $contained artifact(s) left by decoders' child processes, which lightvol survived with an error: $artifacts/contained"
done
exit $status

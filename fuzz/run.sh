#!/usr/bin/env bash
# Builds the libFuzzer targets with clang++ in their own build directory and runs each
# for a bounded time from its seed corpus (fuzz/corpus/<reader>/). Exits non-zero on any
# finding (crash, sanitizer report, uncaught exception, timeout, out-of-memory); the
# input that caused it is left in <build>/findings/. Past findings, fixed, live in
# fuzz/regressions/<reader>/ (also read by the unit tests) and seed every run.
#
#   fuzz/run.sh [seconds per target, default 20] [target ...]   (nproc targets at a time)
#     (targets: csv uff58 mat abaqus matrix_market model campaign summary process)
#   JOINTLAB_FUZZ_BUILD=<dir> selects the build directory (default build-fuzz/ in the repo).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$here")"
build="${JOINTLAB_FUZZ_BUILD:-$root/build-fuzz}"
seconds="${1:-20}"
shift || true
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(csv uff58 mat abaqus matrix_market model campaign summary process)

if ! command -v clang++ >/dev/null 2>&1; then
  echo "fuzz: clang++ not found (Debian package clang-14)" >&2
  exit 1
fi
mkdir -p "$build"
cmake -S "$here" -B "$build" -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  > "$build/configure.log" 2>&1 || { cat "$build/configure.log" >&2; exit 1; }
cmake --build "$build" -j "$(nproc)" > "$build/build.log" 2>&1 || { cat "$build/build.log" >&2; exit 1; }

mkdir -p "$build/findings"
# A request no allocator can satisfy (matio computes some sizes from lying fields) fails
# with NULL in production, which matio and jointlab turn into an InputError; let ASan do
# the same instead of aborting. Large allocations that do succeed are still findings
# (libFuzzer's -malloc_limit_mb, equal to -rss_limit_mb).
export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}allocator_may_return_null=1"
export LSAN_OPTIONS="${LSAN_OPTIONS:+$LSAN_OPTIONS:}suppressions=$here/lsan.supp"
# One target per core at a time (each is single threaded): the same time and corpus for
# each target, in a fraction of the wall time. Results are printed in the targets' order.
jobs=$(nproc)
fuzz_one() {
  local t=$1 work="$build/corpus-$1" log="$build/fuzz_$1.log"
  mkdir -p "$work"   # new inputs go here; the seed corpus in git stays as it is
  # A hang is an input still running after 5 s; `process` is allowed 60 s: it continues any
  # record 0.5 s at each end (a 10 ms record at 100 kHz becomes 1e5 samples), and its band-gain
  # iteration on that took 13 s under the sanitizers (0.84 s in a release build).
  local timeout=5
  [ "$t" = process ] && timeout=60
  local dirs=("$work" "$here/corpus/$t")
  [ -d "$here/regressions/$t" ] && dirs+=("$here/regressions/$t")
  "$build/fuzz_$t" "${dirs[@]}" -max_total_time="$seconds" -rss_limit_mb=2048 \
    -timeout="$timeout" -max_len=16384 -print_final_stats=1 -artifact_prefix="$build/findings/$t-" \
    > "$log" 2>&1
}
pids=()
for t in "${targets[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "$jobs" ]; do wait -n || true; done
  fuzz_one "$t" &
  pids+=($!)
done
status=0
for i in "${!targets[@]}"; do
  t=${targets[$i]}
  log="$build/fuzz_$t.log"
  if wait "${pids[$i]}"; then
    runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo '?')
    echo "fuzz: $t: no finding in ${seconds}s ($runs inputs)"
  else
    status=1
    echo "fuzz: $t: FINDING (log $log, input in $build/findings/)" >&2
    grep -E 'ERROR|SUMMARY|terminate|what\(\)' "$log" | head -5 >&2 || true
  fi
done
exit $status

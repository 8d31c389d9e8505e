#!/usr/bin/env bash
# Speed and accuracy of `jointlab process` against the SciPy baseline on the same
# record (8 channels, 3 bands, fs 5120 Hz, 6 s), both in-process (file reading and
# Python's start-up left out of both): the baseline single threaded, jointlab with one
# channel worker and with two. The three are timed in turn, round after round, so a
# machine whose speed drifts slows all of them alike; medians are printed.
# Usage: bench/compare_scipy.sh [BUILD_DIR] [ROUNDS]
set -euo pipefail
build=${1:-build}
rounds=${2:-5}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$build/bin/jointlab_make_bench_record" "$work/record.csv" "$work/truth.csv"
bands=(--band 48:72 --band 140:185 --band 320:410)
"$build/bin/jointlab" process "$work/record.csv" "${bands[@]}" --threads 1 \
  --amplitude displacement --out "$work/jl" > /dev/null 2>&1
for ((r = 0; r < rounds; ++r)); do
  /usr/bin/python3 "$(dirname "$0")/scipy_baseline.py" "$work/record.csv" "$work/truth.csv" \
    "${bands[@]}" --repeat 3 | sed -n 's/^scipy baseline: \([0-9.]*\) ms.*/\1/p' >> "$work/scipy"
  for t in 1 2; do
    JOINTLAB_BENCH_RECORD="$work/record.csv" "$build/bin/jointlab_bench_process" \
      --benchmark_filter="BM_ProcessFile/$t/" --benchmark_repetitions=3 \
      --benchmark_report_aggregates_only=true --benchmark_format=csv 2> /dev/null |
      awk -F, '/_median"/ {print $3}' >> "$work/jl$t"
  done
done
median() { sort -g "$1" | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }
s=$(median "$work/scipy")
j1=$(median "$work/jl1")
j2=$(median "$work/jl2")
printf 'in-process time per record, median of %d rounds:\n' "$rounds"
printf '  SciPy baseline (1 thread)        %8.1f ms\n' "$s"
ratio() { awk -v a="$1" -v b="$2" 'BEGIN {printf "%.2f", a / b}'; }
printf '  jointlab process (1 thread)      %8.1f ms   %sx faster\n' "$j1" "$(ratio "$s" "$j1")"
printf '  jointlab process (2 threads)     %8.1f ms   %sx faster\n' "$j2" "$(ratio "$s" "$j2")"
/usr/bin/python3 "$(dirname "$0")/scipy_baseline.py" "$work/record.csv" "$work/truth.csv" \
  "${bands[@]}" --repeat 1 --jointlab "$work/jl" | tail -n +2

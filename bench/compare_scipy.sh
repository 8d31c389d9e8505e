#!/usr/bin/env bash
# Speed and accuracy of `jointlab process` against the SciPy baseline on the same
# record (8 channels, 3 bands, fs 5120 Hz, 6 s), both single threaded.
# Usage: bench/compare_scipy.sh [BUILD_DIR]
set -euo pipefail
build=${1:-build}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$build/bin/jointlab_make_bench_record" "$work/record.csv" "$work/truth.csv"
bands=(--band 48:72 --band 140:185 --band 320:410)
"$build/bin/jointlab" process "$work/record.csv" "${bands[@]}" --threads 1 \
  --amplitude displacement --out "$work/jl" > /dev/null 2>&1
JOINTLAB_BENCH_RECORD="$work/record.csv" "$build/bin/jointlab_bench_process" \
  --benchmark_filter=File --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
/usr/bin/python3 "$(dirname "$0")/scipy_baseline.py" "$work/record.csv" "$work/truth.csv" \
  "${bands[@]}" --jointlab "$work/jl"

#!/usr/bin/env bash
# check-consumer.sh [BUILD_DIR]: installs the built jointlab into a scratch prefix, builds
# examples/consumer against it with find_package(jointlab), and runs it on the Brake-Reuss
# record shipped in data/examples. Fails if any step does.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
build=$(cd "${1:-$here/build}" && pwd)
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
cmake --install "$build" --prefix "$scratch/prefix" > "$scratch/install.log"
cmake -S "$here/examples/consumer" -B "$scratch/build" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$scratch/prefix" > "$scratch/configure.log" 2>&1 \
  || { cat "$scratch/configure.log"; exit 1; }
cmake --build "$scratch/build" -j "$(nproc)" > "$scratch/build.log" 2>&1 \
  || { cat "$scratch/build.log"; exit 1; }
"$scratch/build/backbone" "$here/data/examples/brake-reuss-beam/hammer_impact.csv" acc1 70:90 \
  > "$scratch/backbone.csv"
rows=$(($(wc -l < "$scratch/backbone.csv") - 1))
echo "consumer: built against the installed package; acc1 70:90 backbone of $rows points"
[ "$rows" -gt 10 ]

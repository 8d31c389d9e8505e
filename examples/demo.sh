#!/usr/bin/env bash
# make demo: processes the measured Brake-Reuss beam hammer test shipped in
# data/examples/ (first mode, about 80.5 Hz, three accelerometers).
set -euo pipefail
build=${1:-build}
here=$(cd "$(dirname "$0")/.." && pwd)
out="$here/out/demo"
rm -rf "$out"
"$build/bin/jointlab" process "$here/data/examples/brake-reuss-beam/hammer_impact.csv" \
  --band 70:90 --band 280:315 --amplitude velocity --out "$out"
echo "demo: backbones (frequency and damping versus velocity amplitude) are in $out"
ls "$out"

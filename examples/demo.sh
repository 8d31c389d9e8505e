#!/usr/bin/env bash
# make demo: (1) processes the measured Brake-Reuss beam hammer test shipped in
# data/examples/ (first mode, about 80.5 Hz, three accelerometers); (2) runs the example
# test campaign data/examples/riveted-campaign (a riveted beam struck at three force
# levels, three hits each): model, backbones, scatter summaries, QSMA, linear updating,
# figures and the report.
set -euo pipefail
build=${1:-build}
here=$(cd "$(dirname "$0")/.." && pwd)
out="$here/out/demo"
rm -rf "$out"
"$build/bin/jointlab" process "$here/data/examples/brake-reuss-beam/hammer_impact.csv" \
  --band 70:90 --band 280:315 --amplitude velocity --out "$out"
echo "demo: backbones (frequency and damping versus velocity amplitude) are in $out"
ls "$out"

campaign="$here/out/campaign"
"$build/bin/jointlab" run "$here/data/examples/riveted-campaign/campaign.toml" --out "$campaign"
echo "demo: campaign report: $campaign/report.html (Markdown: $campaign/report.md)"
echo "demo: figures: $(ls "$campaign"/figures | tr '\n' ' ')"

#!/usr/bin/env bash
# Makes the example campaign: the riveted beam (examples/riveted_beam/description.toml with
# the joint parameters of truth.toml) struck at mid-span at three force levels, three hits
# each, every hit with its own K_T and F_S (hits.csv), recorded by two accelerometers
# (2e-4 white noise) for 3 s at 5 kHz. Samples are rounded to 7 significant digits (the
# noise is 2e-4 of the peak) to keep the folder small.
#
#   data/examples/riveted-campaign/make_campaign.sh [build-dir]     (about 2 minutes)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../../.." && pwd)
build=${1:-$root/build}
jl="$build/bin/jointlab"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# The true model: the example description with truth.toml's joint parameters.
sed -e 's/^Kt = [^#]*/Kt = 1.2e7 /' -e 's/^Fs = [^#]*/Fs = 40.0 /' \
    -e 's/^chi = [^#]*/chi = -0.4 /' -e 's/^beta = [^#]*/beta = 0.8 /' \
    "$root/examples/riveted_beam/description.toml" > "$work/truth_description.toml"
"$jl" build-model "$work/truth_description.toml" --out "$work/model" --quiet

grep -v '^#' "$here/hits.csv" | tail -n +2 | while IFS=, read -r group hit force kt fs seed; do
  # This hit's model: model.toml with its own K_T and F_S (same matrices).
  sed -e "s/^Kt = .*/Kt = $kt/" -e "s/^Fs = .*/Fs = $fs/" "$work/model/model.toml" \
    > "$work/model/hit.toml"
  mkdir -p "$here/$group"
  out="$here/$group/${group}_hit$hit.csv"
  "$jl" simulate "$work/model/hit.toml" --impact 9003:3 --force "$force" --pulse 0.002 \
    --duration 3 --fs 5000 --sensors 9001:3 9003:3 --noise 2e-4 --seed "$seed" --quiet \
    --out "$work/hit.csv"
  # 7 significant digits; the model path in the metadata names the source, not /tmp.
  awk -v kt="$kt" -v fs="$fs" -F, '
    /^# model:/ { print "# model: riveted beam (examples/riveted_beam), joints of truth.toml"; \
                  print "# joint_Kt: " kt; print "# joint_Fs: " fs; next }
    /^#/ || NR == 0 { print; next }
    !header { print; header = 1; next }
    { printf "%.7g,%.7g\n", $1, $2 }' "$work/hit.csv" > "$out"
  echo "wrote $out (force $force N, Kt $kt N/m, Fs $fs N)"
done

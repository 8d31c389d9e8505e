#!/usr/bin/env bash
# Installs the Debian 12 packages jointlab builds and tests with, only when missing
# (clang and its runtime serve the libFuzzer targets in fuzz/).
# Nothing else is downloaded. Run as root (or with the packages already installed).
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libeigen3-dev libfftw3-dev libceres-dev libspectra-dev libsuitesparse-dev
  libtomlplusplus-dev libcli11-dev libfmt-dev libcsv-dev libmatio-dev
  libplplot-dev plplot-driver-cairo libgtest-dev libbenchmark-dev
  libboost-dev
  python3-scipy
  pybind11-dev python3-pybind11 python3-numpy python3-pytest
  clang libclang-rt-14-dev
)

# One dpkg-query for all (a second in all, one per package, otherwise); a package never
# installed is not listed by it at all.
installed=$(dpkg-query -W -f='${Package} ${Status}\n' "${packages[@]}" 2>/dev/null \
  | awk '/ install ok installed$/ {print $1}' || true)
missing=()
for p in "${packages[@]}"; do
  if ! grep -qx -- "$p" <<< "$installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
if [ "$(id -u)" -ne 0 ]; then
  echo "install-deps: missing packages and not root; install them with: apt-get install ${missing[*]}" >&2
  exit 1
fi
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends "${missing[@]}"

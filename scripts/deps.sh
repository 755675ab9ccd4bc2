#!/usr/bin/env bash
# Installs the Debian packages mbsgen needs, if any is missing, plus any packages named as
# arguments (scripts/fuzz.sh adds clang and libclang-rt-14-dev; the test suite needs neither).
# As root: apt-get update, then apt-get install. Otherwise: prints the command and exits 1.
set -euo pipefail
packages=(cmake g++ make pkg-config libginac-dev libcln-dev libeigen3-dev libyaml-cpp-dev
          libcli11-dev libgtest-dev liblapacke-dev libopenblas-dev gnuplot-nox libjemalloc-dev
          libsundials-dev libboost-dev libopenmpi-dev openmpi-bin "$@")
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0
cmd="apt-get update && apt-get install -y --no-install-recommends ${missing[*]}"
if [ "$(id -u)" -ne 0 ]; then
  echo "mbsgen: missing Debian packages: ${missing[*]}" >&2
  echo "run as root:  $cmd" >&2
  exit 1
fi
echo "mbsgen: installing ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends "${missing[@]}"

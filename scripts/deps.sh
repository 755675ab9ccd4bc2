#!/usr/bin/env bash
# Installs the Debian packages mbsgen needs, if any is missing, plus any packages named as
# arguments (scripts/fuzz.sh adds clang and libclang-rt-14-dev; the test suite needs neither).
# As root: apt-get update, then apt-get install. Otherwise: prints the command and exits 1.
#
#   scripts/deps.sh [--demo] [PACKAGE...]
#
# --demo: only what scripts/demo.sh builds (the preset "demo": the runtime and the solver's command
# line, without the generator, the tests, simulation or MPI), and gnuplot for its plot: 75 fewer
# packages on a bare Debian 12 than the whole set (no GiNaC, OpenMPI, Boost, gfortran, SUNDIALS).
#
# SUNDIALS (CVODE, for simulate): the runtime library libsundials-cvode6 only, which holds CVODE
# with the serial vector and the dense matrix and solver mbsgen uses. Debian's libsundials-dev,
# the only package with the headers, depends on PETSc, HYPRE, MUMPS, Trilinos, HDF5 and gfortran
# (134 packages, 399 MB installed, on Debian 12); its headers are taken from its .deb instead
# (apt-get download, no root needed), into build/deps/sundials, where CMake finds them when
# /usr/include has none (docs/building.md, "Dependencies").
set -euo pipefail
cd "$(dirname "$0")/.."
demo=0
if [ "${1:-}" = --demo ]; then
  demo=1
  shift
fi
if [ "$demo" = 1 ]; then
  packages=(cmake g++ make pkg-config libeigen3-dev libcli11-dev liblapacke-dev libopenblas-dev gnuplot-nox "$@")
else
  packages=(cmake g++ make pkg-config libginac-dev libcln-dev libeigen3-dev libyaml-cpp-dev
            libcli11-dev libgtest-dev liblapacke-dev libopenblas-dev gnuplot-nox libjemalloc-dev
            libsundials-cvode6 libboost-dev libopenmpi-dev openmpi-bin
            pybind11-dev python3-dev python3-numpy python3-pytest libceres3 libgoogle-glog-dev
            liburdfdom-dev "$@")
fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
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
fi

[ "$demo" = 1 ] && exit 0  # the demo's solver does not simulate: no SUNDIALS

# The headers of an installed library's version from its -dev package's .deb, unless that package
# is installed: headers_from_deb DEV_PACKAGE RUNTIME_PACKAGE TEST_HEADER DIR
headers_from_deb() {
  local dev=$1 runtime=$2 test_header=$3 headers=$4 version work
  version=$(dpkg-query -W -f='${Version}' "$runtime")
  if [ -f "/usr/include/$test_header" ] || [ "$(cat "$headers/version" 2>/dev/null)" = "$version" ]; then
    return 0
  fi
  work=$(mktemp -d)
  download() { (cd "$work" && apt-get download -qq "$dev=$version" > log 2>&1); }
  if ! download && ! { [ "$(id -u)" -eq 0 ] && apt-get update -qq && download; }; then
    cat "$work/log" >&2
    echo "mbsgen: cannot download $dev=$version for its headers (run apt-get update, or install $dev)" >&2
    rm -rf "$work"
    exit 1
  fi
  dpkg-deb -x "$work"/"${dev}"_*.deb "$work/root"
  rm -rf "$headers"
  mkdir -p "$headers"
  cp -r "$work/root/usr/include" "$headers/include"
  echo "$version" > "$headers/version"
  rm -rf "$work"
  echo "mbsgen: $dev $version headers from its package in $headers" >&2
}
headers_from_deb libsundials-dev libsundials-cvode6 cvode/cvode.h build/deps/sundials
# Ceres Solver (the solver of `fit`, issue 42): the runtime library libceres3 and its headers;
# libceres-dev itself depends on SuiteSparse's and ATLAS's development packages and GraphBLAS
# (255 MB installed on Debian 12, against 22 MB for libceres3 with glog's headers).
headers_from_deb libceres-dev libceres3 ceres/ceres.h build/deps/ceres

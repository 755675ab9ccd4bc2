#!/usr/bin/env bash
# Issue 3 §7: runtime benchmarks and Octave (freqresp, a sparse-solve loop, polyeig) on the same
# matrices, in one run. Not part of the test suite. Installs octave and octave-control (Debian)
# if missing and running as root.
#   bench/runtime_compare.sh [--quick]      (--quick: n ≤ 200, no modes of n = 1000)
set -euo pipefail
cd "$(dirname "$0")/.."
quick=0
[ "${1:-}" = "--quick" ] && quick=1
if ! command -v octave >/dev/null || ! dpkg-query -W -f='${Status}' octave-control 2>/dev/null | grep -q "ok installed"; then
  if [ "$(id -u)" -eq 0 ]; then
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends octave octave-control
  else
    echo "runtime_compare: needs octave and octave-control (apt-get install octave octave-control)" >&2
    exit 1
  fi
fi
build=build/bench-runtime
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DMBSGEN_BUILD_BENCH=ON -DMBSGEN_BUILD_TESTS=OFF \
  -DMBSGEN_BUILD_GENERATOR=OFF >/dev/null
cmake --build "$build" --target runtime_bench -j 2 >/dev/null
out="$build/compare"
mkdir -p "$out"
"$build/bench/runtime_bench" --write-matrices "$out"
if [ $quick -eq 1 ]; then
  filter='frf/.*/n=(10|15|20|30|50|200)/'
  sizes="10 50 200"
  polyeig=""
else
  filter='.*'
  sizes="10 50 200 1000"
  polyeig="polyeig"
fi
echo "== mbsgen runtime (Google Benchmark) =="
"$build/bench/runtime_bench" --benchmark_filter="$filter" --benchmark_out="$out/mbsgen.json" \
  --benchmark_out_format=json 2>&1 | grep -v '^\*\*\*WARNING'
echo "== Octave $(octave --version | head -1 | awk '{print $4}') on the same matrices =="
echo "tool,benchmark,n,seconds_per_frequency_or_call,max_rel_err_vs_mbsgen_banded"
octave --no-gui -q bench/octave/runtime_compare.m "$out" "$sizes" $polyeig 2>&1 | tee "$out/octave.csv"

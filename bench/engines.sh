#!/usr/bin/env bash
# Per-call speed against numeric engines (issue 17 §2): builds and runs bench/engines_bench.cpp,
# our mass_matrix and residual kernels against MuJoCo and Orocos KDL on the spatial chains
# (N = 3, 6, 12, 30) and the PUMA 560, after checking that all three agree to 1e-12. Called by
# scripts/bench.sh (which installs libmujoco-dev and liborocos-kdl-dev); bench/report_engines.py
# turns the results into a section of docs/accuracy-vs-time.md.
#
#   bench/engines.sh [--quick] [--jobs N] [--processes K] [--build DIR] [--out DIR]
#
#   --processes K  engines_bench runs K times, each a new process; engines.csv has the median over
#                the processes (bench/engines_merge.py says why; default 5, 1 with --quick)
#   --build DIR  a build directory configured with -DMBSGEN_BUILD_BENCH=ON (default build/bench;
#                configured here in Release when it has no CMakeCache.txt)
#   --out DIR    results: engines.csv, engines_agreement.csv, engines_mjcf/, engines.log
#                (default DIR/results of the build directory); versions appended to system.txt
# Exit status 1 when the engines disagree or are missing.
set -euo pipefail
cd "$(dirname "$0")/.."
quick=()
jobs=1
processes=""
build=build/bench
out=""
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) quick=(--quick) ;;
    --jobs) jobs="$2"; shift ;;
    --processes) processes="$2"; shift ;;
    --build) build="$2"; shift ;;
    --out) out="$2"; shift ;;
    *) echo "usage: bench/engines.sh [--quick] [--jobs N] [--processes K] [--build DIR] [--out DIR]" >&2; exit 2 ;;
  esac
  shift
done
out=${out:-$build/results}
start=$(date +%s)
log() { printf '[engines %4ds] %s\n' $(( $(date +%s) - start )) "$*" >&2; }

if [ ! -f "$build/CMakeCache.txt" ]; then
  log "configuring $build (Release, benchmarks on, tests off)"
  cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DMBSGEN_BUILD_BENCH=ON -DMBSGEN_BUILD_TESTS=OFF >/dev/null
fi
log "building engines_bench (-j $jobs; the 30-link chain's kernels take minutes to compile)"
if ! cmake --build "$build" --target engines_bench -j "$jobs" >"$build/engines_build.log" 2>&1; then
  if grep -q "No rule to make target .engines_bench\|unknown target .engines_bench" "$build/engines_build.log"; then
    echo "engines: engines_bench was not configured (MuJoCo or KDL missing: apt-get install libmujoco-dev liborocos-kdl-dev)" >&2
  else
    tail -20 "$build/engines_build.log" >&2
  fi
  exit 1
fi
mkdir -p "$out"
ver() { dpkg-query -W -f='${Version}' "$1" 2>/dev/null || echo "?"; }
{
  echo "mujoco: $(ver libmujoco-dev)"
  echo "orocos_kdl: $(ver liborocos-kdl-dev)"
} >>"$out/system.txt"
if [ -z "$processes" ]; then processes=5; [ ${#quick[@]} -gt 0 ] && processes=1; fi
case "$processes" in ''|*[!0-9]*) echo "engines: --processes wants a positive integer" >&2; exit 2 ;; esac
if (( 10#$processes < 1 )); then echo "engines: --processes wants a positive integer" >&2; exit 2; fi
runs=()
# Nothing of an earlier run may pass for this one's (report_engines.py reads these).
rm -rf "$out/engines_runs" "$out/engines.csv" "$out/engines_agreement.csv" "$out/engines_mjcf"
: >"$out/engines.log"
for k in $(seq 1 "$((10#$processes))"); do
  log "MuJoCo and KDL against our kernels ${quick[*]:-} (process $k of $processes)"
  run="$out/engines_runs/$k"
  mkdir -p "$run"
  if ! "$build/bench/engines_bench" "$run" "${quick[@]}" 2>"$run/engines.log"; then
    cat "$run/engines.log" >>"$out/engines.log"
    cp "$run/engines_agreement.csv" "$out/engines_agreement.csv" 2>/dev/null || true
    tail -30 "$run/engines.log" >&2
    exit 1
  fi
  { echo "== process $k"; cat "$run/engines.log"; } >>"$out/engines.log"
  runs+=("$run/engines.csv")
done
cp "$out/engines_runs/1/engines_agreement.csv" "$out/engines_agreement.csv"
rm -rf "$out/engines_mjcf"
cp -r "$out/engines_runs/1/engines_mjcf" "$out/engines_mjcf" 2>/dev/null || true
python3 bench/engines_merge.py "$out/engines.csv" "${runs[@]}"
log "done"

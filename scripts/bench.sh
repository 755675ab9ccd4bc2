#!/usr/bin/env bash
# What accuracy costs in time (issue 7): builds the benchmarks in release mode, runs them and the
# peers (SymPy for generation, Octave for frequency responses and eigenvalues) in one run, and
# rewrites docs/accuracy-vs-time.md with its tables and plots (docs/accuracy-vs-time/*.svg, .png).
# Not part of the test suite (scripts/test.sh never builds bench/).
#
#   scripts/bench.sh [--quick] [--jobs N] [--out DIR] [--no-doc]
#
#   --quick   smaller sizes (chains to n = 100, generation to N = 20, SymPy to N = 5) and
#             shorter time limits: about 10 min instead of about 30 on a quiet 2-core machine
#   --jobs N  parallel build jobs (default 1: the machine is shared)
#   --out DIR where the raw results go (default build/bench/results)
#   --no-doc  leave docs/ alone (results and plots only under --out)
#
# Installs what is missing with apt-get when run as root (python3-sympy, octave, octave-control,
# libbenchmark-dev, gnuplot-nox and the build dependencies of scripts/deps.sh). Every BLAS call
# runs single-threaded (OPENBLAS_NUM_THREADS=1), ours and Octave's alike.
set -euo pipefail
cd "$(dirname "$0")/.."
quick=0
jobs=1
out=""
doc=1
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) quick=1 ;;
    --jobs) jobs="$2"; shift ;;
    --out) out="$2"; shift ;;
    --no-doc) doc=0 ;;
    *) echo "usage: scripts/bench.sh [--quick] [--jobs N] [--out DIR] [--no-doc]" >&2; exit 2 ;;
  esac
  shift
done
start=$(date +%s)
log() { printf '[bench %4ds] %s\n' $(( $(date +%s) - start )) "$*" >&2; }

# ---- dependencies -------------------------------------------------------------------------------
scripts/deps.sh
extra=(python3-sympy python3-scipy octave octave-control libbenchmark-dev gnuplot-nox libmujoco-dev liborocos-kdl-dev libkdl-parser-dev)
missing=()
for p in "${extra[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  if [ "$(id -u)" -ne 0 ]; then
    echo "bench: missing Debian packages: ${missing[*]} (run as root: apt-get install ${missing[*]})" >&2
    exit 1
  fi
  log "installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get install -y -qq --no-install-recommends "${missing[@]}" ||
    { apt-get update -qq && apt-get install -y -qq --no-install-recommends "${missing[@]}"; }
fi
python=/usr/bin/python3  # Debian's, with python3-sympy (not a pyenv or venv python)

# ---- build --------------------------------------------------------------------------------------
build=build/bench
out=${out:-$build/results}
log "configuring $build (Release, benchmarks on, tests off)"
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DMBSGEN_BUILD_BENCH=ON -DMBSGEN_BUILD_TESTS=OFF >/dev/null
log "building frf_accuracy modes_accuracy generation_cost (-j $jobs)"
cmake --build "$build" --target frf_accuracy modes_accuracy generation_cost kernel_call_timing mbsgen nonlinear_tones \
  simulation_timing -j "$jobs" >/dev/null
rm -rf "$out"
mkdir -p "$out"

# ---- the machine --------------------------------------------------------------------------------
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
ver() { dpkg-query -W -f='${Version}' "$1" 2>/dev/null || echo "?"; }
{
  echo "date: $(date -u '+%Y-%m-%d %H:%M UTC')"
  if [ -n "${MBSGEN_BENCH_COMMIT:-}" ]; then  # e.g. when run on an exported snapshot of a commit
    echo "commit: $MBSGEN_BENCH_COMMIT"
  else
    echo "commit: $(git rev-parse --short HEAD 2>/dev/null || echo '?')$(git diff --quiet HEAD 2>/dev/null || echo ' (with uncommitted changes)')"
  fi
  echo "cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')"
  echo "nproc: $(env -u OMP_NUM_THREADS nproc)"
  echo "load_start: $(cut -d' ' -f1-3 /proc/loadavg)"
  echo "compiler: $(c++ --version | head -1)"
  echo "openblas: $(ver libopenblas0-pthread) (OPENBLAS_NUM_THREADS=1)"
  echo "lapacke: $(ver liblapacke)"
  echo "eigen: $(ver libeigen3-dev)"
  echo "ginac: $(ver libginac11)"
  echo "cln: $(ver libcln6)"
  echo "benchmark_harness: bench/harness.hpp (medians of repetitions)"
  echo "octave: $(octave --version 2>/dev/null | head -1 | awk '{print $4}')"
  echo "octave_control: $(ver octave-control)"
  echo "sympy: $($python -c 'import sympy; print(sympy.__version__)')"
  echo "python: $($python --version 2>&1 | awk '{print $2}')"
  echo "gnuplot: $(gnuplot --version | awk '{print $2"."$4}')"
  echo "quick: $quick"
} >"$out/system.txt"

q=()
[ $quick -eq 1 ] && q=(--quick)

# ---- ours ---------------------------------------------------------------------------------------
log "frequency responses (frf_accuracy ${q[*]:-})"
"$build/bench/frf_accuracy" "$out" "${q[@]}" 2>"$out/frf.log"
log "the same with OpenBLAS's default threads (middle ear only)"
env -u OPENBLAS_NUM_THREADS -u OMP_NUM_THREADS "$build/bench/frf_accuracy" "$out/threads" --only middle_ear --reps 3 \
  2>"$out/threads.log"
log "modes (modes_accuracy ${q[*]:-})"
"$build/bench/modes_accuracy" "$out" "${q[@]}" 2>"$out/modes.log"
log "generation (generation_cost ${q[*]:-})"
"$build/bench/generation_cost" "$out" "${q[@]}" 2>"$out/generation.log"
# Large models (issue 17 §1): the spatial chains from model file to first answer, compile time and
# memory, and the kernels cut into parts against the whole ones (compiled only to N = 20: the
# 30-link chain's whole file takes GCC about 9 minutes and 3.5 GB).
if [ $quick -eq 1 ]; then scale_links="10,20"; whole_max=10; else scale_links="10,20,30,40,60"; whole_max=20; fi
log "large models (compile_scale.py, links $scale_links)"
"$python" bench/compile_scale.py "$build/generator/mbsgen" "$build/bench/kernel_call_timing" "$out" \
  --links "$scale_links" --whole-max "$whole_max" --jobs "$(env -u OMP_NUM_THREADS nproc)" 2>"$out/compile_scale.log" ||
  log "compile_scale: failed (see $out/compile_scale.log)"

# ---- peers --------------------------------------------------------------------------------------
if [ $quick -eq 1 ]; then sympy_sizes="2 5"; sympy_limit=60; oct_limit=60; else sympy_sizes="2 5 10 20 40"; sympy_limit=180; oct_limit=240; fi
echo "N,status,limit_s" >"$out/sympy_runs.csv"
stop=0
for N in $sympy_sizes; do
  if [ $stop -eq 1 ]; then
    echo "$N,skipped,$sympy_limit" >>"$out/sympy_runs.csv"
    continue
  fi
  log "SymPy KanesMethod, planar chain N = $N (limit ${sympy_limit} s)"
  status=done
  timeout "$sympy_limit" "$python" bench/peers/sympy_chain.py "$N" "$out/gen_matrices/planar_$N.txt" \
    >"$out/sympy_$N.txt" 2>"$out/sympy_$N.log" || status=timeout
  grep -q '^done' "$out/sympy_$N.txt" || status=timeout
  echo "$N,$status,$sympy_limit" >>"$out/sympy_runs.csv"
  [ $status = timeout ] && stop=1  # larger chains take longer still
done

echo "tool,problem,n,method,amortized_s,err_max,err_median,note" >"$out/octave_frf.csv"
for d in "$out"/frf_data/*/; do
  name=$(basename "$d")
  log "Octave freqresp and backslash: $name (limit ${oct_limit} s)"
  timeout "$oct_limit" octave --no-gui -q bench/peers/octave_frf.m "$d" "$name" >>"$out/octave_frf.csv" 2>/dev/null ||
    echo "octave,$name,,timeout,nan,nan,nan,stopped after ${oct_limit} s" >>"$out/octave_frf.csv"
done
echo "tool,problem,n,k,method,time_s,err_lowest_k" >"$out/octave_modes.csv"
for d in "$out"/modes_data/*/; do
  name=$(basename "$d")
  log "Octave polyeig, eig, eigs: $name (limit ${oct_limit} s)"
  timeout "$oct_limit" octave --no-gui -q bench/peers/octave_modes.m "$d" "$name" >>"$out/octave_modes.csv" 2>/dev/null ||
    echo "octave,$name,,,timeout,nan,nan" >>"$out/octave_modes.csv"
done
bench/engines.sh --build "$build" --out "$out" --jobs "$jobs" "${q[@]}" || log "engines: failed (see $out/engines.log)"
# The URDF robots (issue 43, docs/urdf.md): our kernels against MuJoCo and KDL, per call.
log "urdf_engines: the five URDF robots against MuJoCo and KDL"
if cmake --build "$build" --target urdf_engines -j "$jobs" >"$out/urdf_engines_build.log" 2>&1; then
  bench/urdf_speed.sh "$build/bench/urdf_engines" --processes 5 --out "$out/urdf_speed" >"$out/urdf_speed.md" 2>"$out/urdf_speed.log" ||
    log "urdf_speed: failed (see $out/urdf_speed.log)"
else
  log "urdf_engines: not built (see $out/urdf_engines_build.log)"
fi
# Time simulation (issue 18 §2–4): tones against the frequency response and the middle ear's growth
# with the level (about 7 min), simulate() timed (about 1 min), SciPy's solve_ivp through the same
# kernels (about 15 min).
log "simulation: nonlinear_tones, simulation_timing, simulation_compare.py (SciPy)"
"$build/bench/nonlinear_tones" "$out" >"$out/nonlinear_tones.log" 2>&1 || log "nonlinear_tones: failed"
"$build/bench/simulation_timing" "$out" 5 >"$out/simulation_timing.log" 2>&1 || log "simulation_timing: failed"
"$python" bench/simulation_compare.py "$build/generated/mbsgen" "$out" 3 >"$out/simulation_compare.log" 2>&1 ||
  log "simulation_compare: failed (see $out/simulation_compare.log)"
echo "load_end: $(cut -d' ' -f1-3 /proc/loadavg)" >>"$out/system.txt"
echo "duration_s: $(( $(date +%s) - start ))" >>"$out/system.txt"

# ---- report -------------------------------------------------------------------------------------
if [ $doc -eq 1 ]; then
  log "writing docs/accuracy-vs-time.md and docs/accuracy-vs-time/"
  "$python" bench/report.py "$out" docs/accuracy-vs-time.md docs/accuracy-vs-time
  "$python" bench/plot_simulation.py "$out" docs/simulation
else
  "$python" bench/plot_simulation.py "$out" "$out/simulation"
  "$python" bench/report.py "$out" "$out/accuracy-vs-time.md" "$out/accuracy-vs-time"
fi
log "done"

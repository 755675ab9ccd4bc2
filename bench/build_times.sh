#!/usr/bin/env bash
# Where a build's time goes (issue 40 §4): configures a fresh build directory with a launcher that
# times every compilation and link (bench/time_step.sh), builds TARGET with -j JOBS, and prints
# the wall time, the compile and link time summed per directory of the tree, and the heaviest
# translation units and links.
#
#   bench/build_times.sh [--preset dev|ci|asan|demo] [--target T] [--jobs N] [--dir DIR] [-DVAR=VALUE ...]
#
# -D options go to the configuration (-DCMAKE_DISABLE_PRECOMPILE_HEADERS=ON: without precompiled
# headers, for a comparison).
#
# Defaults: preset dev, target all, 2 jobs, build directory build/times-<preset>. Nothing else
# is touched; the raw times stay in DIR/times.tsv.
set -euo pipefail
cd "$(dirname "$0")/.."
preset=dev
target=all
jobs=2
dir=""
defines=()
while [ $# -gt 0 ]; do
  case "$1" in
    --preset) preset="$2"; shift ;;
    --target) target="$2"; shift ;;
    --jobs) jobs="$2"; shift ;;
    --dir) dir="$2"; shift ;;
    -D*) defines+=("$1") ;;
    *) echo "usage: bench/build_times.sh [--preset P] [--target T] [--jobs N] [--dir DIR]" >&2; exit 2 ;;
  esac
  shift
done
dir=${dir:-build/times-$preset}
rm -rf "$dir"
launcher="$PWD/bench/time_step.sh"
cmake --preset "$preset" -B "$dir" -DCMAKE_CXX_COMPILER_LAUNCHER="$launcher" \
  -DCMAKE_CXX_LINKER_LAUNCHER="$launcher" "${defines[@]}" > /dev/null
if [ "$preset" = asan ]; then
  # The sanitizers' options of the asan build preset (CMakePresets.json): the build runs the
  # instrumented generator and test executables, and CLN's one allocation at exit is suppressed.
  export ASAN_OPTIONS=detect_leaks=1:detect_stack_use_after_return=1:check_initialization_order=1:strict_init_order=1
  export LSAN_OPTIONS="suppressions=$PWD/fuzz/lsan.supp:print_suppressions=0"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:suppressions=$PWD/fuzz/ubsan.supp"
fi
export MBSGEN_BUILD_TIMES="$PWD/$dir/times.tsv"
: > "$MBSGEN_BUILD_TIMES"
start=$(date +%s)
cmake --build "$dir" -j "$jobs" --target "$target" > "$dir/build.log" 2>&1 || { tail -30 "$dir/build.log"; exit 1; }
wall=$(( $(date +%s) - start ))
echo "preset $preset ${defines[*]}, target $target, -j $jobs: wall $wall s"
awk -F'\t' '
  { out = $3
    target = "(other)"
    if (match(out, /CMakeFiles\/[^\/]+\.dir/)) target = substr(out, RSTART + 11, RLENGTH - 15)
    else if ($2 == "link") { n = split(out, p, "/"); target = p[n] }
    t[target] += $1; steps[target]++; total[$2] += $1; count[$2]++ }
  END {
    printf "compile %.0f s in %d units, link %.0f s in %d links (CPU-seconds of the steps)\n",
           total["compile"], count["compile"], total["link"], count["link"]
    print "per target (its compilations, or its link):"
    for (k in t) printf "  %8.1f s  %3d steps  %s\n", t[k], steps[k], k | "sort -rn | head -25"
    close("sort -rn | head -25")
  }' "$MBSGEN_BUILD_TIMES"
echo "heaviest steps:"
sort -rn "$MBSGEN_BUILD_TIMES" | head -20 | awk -F'\t' '{ printf "  %8.1f s  %-7s %s\n", $1, $2, $3 }'

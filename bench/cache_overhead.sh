#!/usr/bin/env bash
# What a warm `mbsgen run` adds to the solver's own time (issue 45), for every shipped model:
# `mbsgen run MODEL -- modes` (tape) against `mbsgen-tape ENTRY/tape modes` started directly, and
# `mbsgen run MODEL --compiled -- modes` against `ENTRY/solve modes`, alternating A B A B over
# RUNS pairs in one run; medians in ms and the median of the pairs' differences. Also each cached
# solver's size, and two concurrent loops of warm runs under a limit that evicts at every build.
#
#   bench/cache_overhead.sh MBSGEN MBSGEN_TAPE [RUNS]
set -euo pipefail
cd "$(dirname "$0")/.."
mbsgen=$(realpath "$1")
tape_solver=$(realpath "$2")
runs=${3:-21}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
source bench/shipped_models.sh

# median_pair A_COMMAND... :: B_COMMAND...: "A_ms B_ms (A-B)_ms" as medians over the pairs.
median_pair() {
  /usr/bin/python3 - "$runs" "$@" <<'EOF'
import statistics, subprocess, sys, time
runs = int(sys.argv[1]); args = sys.argv[2:]; cut = args.index('::')
a, b = args[:cut], args[cut + 1:]
def once(cmd):
    t = time.perf_counter()
    subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    return 1000 * (time.perf_counter() - t)
once(a); once(b)
ta, tb = [], []
for _ in range(runs):
    ta.append(once(a)); tb.append(once(b))
print(f"{statistics.median(ta):.1f} {statistics.median(tb):.1f} "
      f"{statistics.median([x - y for x, y in zip(ta, tb)]):.1f}")
EOF
}

printf '%-46s %8s %8s %8s | %9s %8s %8s %9s\n' model run_tape tape +ms run_comp solve +ms solve_MB
for model in "${models[@]}"; do
  cache="$work/cache"
  rm -rf "$cache"
  export MBSGEN_CACHE_DIR=$cache
  "$mbsgen" run "$model" -- modes >/dev/null 2>&1
  tape=$(ls "$cache"/*/tape)
  if [[ -s "$tape" ]]; then
    read -r rt dt ot < <(median_pair "$mbsgen" run "$model" -- modes :: "$tape_solver" "$tape" modes)
  else
    rt=- dt=- ot=-  # closed loops: no tape
  fi
  "$mbsgen" run "$model" --compiled -- modes >/dev/null 2>&1
  solve=$(ls "$cache"/*/solve)
  read -r rc dc oc < <(median_pair "$mbsgen" run "$model" --compiled -- modes :: "$solve" modes)
  size=$(stat -c %s "$solve")
  printf '%-46s %8s %8s %8s | %9s %8s %8s %9.1f\n' "$model" "$rt" "$dt" "$ot" "$rc" "$dc" "$oc" \
    "$(echo "$size / 1048576" | bc -l)"
done

# Two loops of warm runs at once, of two models, each build evicting every entry not in use.
cache="$work/concurrent"
export MBSGEN_CACHE_DIR=$cache MBSGEN_CACHE_MAX_SIZE=1
loop() {
  local failed=0
  for _ in $(seq 50); do "$mbsgen" run "$1" -- modes >/dev/null 2>&1 || failed=$((failed + 1)); done
  echo "$failed"
}
start=$(date +%s.%N)
loop models/textbook/double_pendulum.yaml >"$work/f1" &
loop models/textbook/simple_pendulum.yaml >"$work/f2" &
wait
end=$(date +%s.%N)
echo "concurrent: 2 x 50 warm runs under MBSGEN_CACHE_MAX_SIZE=1 in $(echo "$end - $start" | bc) s," \
  "failed $(cat "$work/f1") + $(cat "$work/f2"); left in the cache: $(ls "$cache" | tr '\n' ' ')"

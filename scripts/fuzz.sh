#!/usr/bin/env bash
# Fuzzes the model reader and the expression parser with libFuzzer (docs/testing.md).
#
#   scripts/fuzz.sh [TARGET...]        TARGET: model_reader, expression (default: both)
#
# Installs clang and libclang-rt-14-dev if missing, configures the "fuzz" preset (clang,
# build/fuzz), builds the libFuzzer binaries (generator instrumented with ASan + UBSan) and runs
# each target for a bounded time on a corpus kept in build/fuzz/corpus/TARGET, seeded with
# models/**/*.yaml and tests/data/bad_models/*.yaml (symlinks, not copies), the expression seeds
# and the regression inputs of tests/data/fuzz_regressions/TARGET. Prints executions, speed and
# coverage per target; exits 1 if any target found a crash, a hang, a leak, runaway memory or a
# sanitizer report (the reproducer is in build/fuzz/findings/TARGET/, the log next to it).
#
# Environment: FUZZ_SECONDS (per target, default 60), FUZZ_TIMEOUT (per input, s, default 10),
# FUZZ_RSS_MB (memory limit, default 2048), FUZZ_MAX_LEN (input size, default 20000), FUZZ_JOBS (build parallelism, default nproc),
# FUZZ_ARGS (extra libFuzzer flags).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/deps.sh clang libclang-rt-14-dev

seconds=${FUZZ_SECONDS:-60}
timeout=${FUZZ_TIMEOUT:-10}
rss_mb=${FUZZ_RSS_MB:-2048}
max_len=${FUZZ_MAX_LEN:-20000}  # bytes: the largest model (middle_ear.yaml, 17 kB) fits
jobs=${FUZZ_JOBS:-$(nproc)}
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(model_reader expression)

build=build/fuzz
cmake --preset fuzz > /dev/null
binaries=()
for t in "${targets[@]}"; do
  case "$t" in model_reader|expression) binaries+=("fuzz_$t") ;;
    *) echo "fuzz.sh: unknown target '$t' (model_reader, expression)" >&2; exit 2 ;; esac
done
cmake --build --preset fuzz -j "$jobs" --target "${binaries[@]}" > "$build/build.log" 2>&1 ||
  { cat "$build/build.log" >&2; exit 1; }

# Seeds: symlinks to the repository's files (model_reader) or one file per seed line (expression).
seeds_of() {
  local t=$1 dir=$build/seeds/$1
  rm -rf "$dir" && mkdir -p "$dir"
  if [ "$t" = model_reader ]; then
    local f
    while IFS= read -r f; do
      ln -s "$PWD/$f" "$dir/$(echo "$f" | tr / _)"
    done < <(find models -name '*.yaml'; ls tests/data/bad_models/*.yaml)
  else
    local n=0 line
    while IFS= read -r line; do
      case "$line" in ''|'#'*) continue ;; esac
      n=$((n + 1))
      printf '%s' "$line" > "$dir/seed_$n"
    done < fuzz/expression_seeds.txt
  fi
  echo "$dir"
}

status=0
summary=()
for t in "${targets[@]}"; do
  corpus=$build/corpus/$t
  findings=$build/findings/$t
  log=$build/fuzz_$t.log
  mkdir -p "$corpus" "$findings" "tests/data/fuzz_regressions/$t"
  seeds=$(seeds_of "$t")
  echo "== fuzz_$t: ${seconds} s, timeout ${timeout} s per input, rss limit ${rss_mb} MB =="
  set +e
  # ASan: report leaks too (but CLN's one-time static allocation, fuzz/lsan.supp); UBSan: stop
  # at the first report, with a stack (but a shift in CLN's headers, fuzz/ubsan.supp).
  ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1} \
  LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/fuzz/lsan.supp} \
  UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1:suppressions=$PWD/fuzz/ubsan.supp} \
  "$build/fuzz/fuzz_$t" -max_total_time="$seconds" -timeout="$timeout" -rss_limit_mb="$rss_mb" \
    -malloc_limit_mb="$rss_mb" -max_len="$max_len" -dict=fuzz/mbsgen.dict -print_final_stats=1 \
    -artifact_prefix="$findings/" ${FUZZ_ARGS:-} \
    "$corpus" "$seeds" "tests/data/fuzz_regressions/$t" > "$log" 2>&1
  rc=$?
  set -e
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  speed=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | cut -d' ' -f2)
  units=$(find "$corpus" -type f | wc -l)
  line="fuzz_$t: ${execs:-?} executions in ${seconds} s (${speed:-?}/s), coverage ${cov:-?} edges, corpus $units inputs"
  if [ $rc -ne 0 ]; then
    status=1
    line="$line: FINDING (exit $rc)"
    echo "$line" >&2
    grep -E '^==[0-9]+==ERROR|^SUMMARY|runtime error|ALARM|out-of-memory|deadly signal|uncaught|terminate called|what\(\)' "$log" | head -20 >&2 || true
    ls -1 "$findings" | sed "s|^|  reproducer: $findings/|" >&2
    echo "  log: $log; minimise: $build/fuzz/fuzz_$t -minimize_crash=1 -runs=100000 REPRODUCER" >&2
  fi
  summary+=("$line")
done
echo "== summary =="
printf '%s\n' "${summary[@]}"
exit $status

#!/usr/bin/env bash
# First answer of every shipped model (issue 40 §5): `mbsgen run MODEL -- modes` with an empty
# cache through the tape (no compiler) and with --compiled (generate, compile, link), and then
# warm, each in its own empty cache; wall seconds and peak memory (GNU time's maximum resident
# set of mbsgen itself; the compilers' is not included). Models with closed loops take the
# compiled path either way (they have no tape). Prints a table.
#
#   bench/first_answer.sh MBSGEN [EXTRA_MODEL.yaml ...]
set -euo pipefail
cd "$(dirname "$0")/.."
mbsgen=$1
shift
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
source bench/shipped_models.sh
models+=("$@")
timed() {  # cache, then the run's arguments: prints "seconds peak_MB"
  local cache=$1
  shift
  MBSGEN_CACHE_DIR=$cache /usr/bin/time -f '%e %M' -o "$work/time" "$mbsgen" run "$@" >/dev/null 2>&1 || echo "failed: $*" >&2
  awk '{ printf "%.2f %.0f\n", $1, $2 / 1024 }' "$work/time"
}
printf '%-48s %10s %8s %10s %12s %8s %10s\n' model tape_s tape_MB warm_s compiled_s comp_MB warm_s
for model in "${models[@]}"; do
  rm -rf "$work/t" "$work/c"
  read -r ts tm < <(timed "$work/t" "$model" -- modes)
  read -r tw _ < <(timed "$work/t" "$model" -- modes)
  read -r cs cm < <(timed "$work/c" "$model" --compiled -- modes)
  read -r cw _ < <(timed "$work/c" "$model" --compiled -- modes)
  printf '%-48s %10s %8s %10s %12s %8s %10s\n' "$model" "$ts" "$tm" "$tw" "$cs" "$cm" "$cw"
done

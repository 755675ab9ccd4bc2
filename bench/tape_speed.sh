#!/usr/bin/env bash
# The tape against the compiled kernels (issue 40 §5): for every shipped model of
# generated/models.txt that has a tape (no closed loops) and for the models given as arguments,
# `mbsgen generate --tape`, the kernels compiled as a shared library (-O2, as `mbsgen run`
# compiles them), and bench/kernel_call_timing timing both in one process, batch after batch in
# turn (medians of 51 batches of thread CPU time). Prints a table: per model and kernel, seconds
# per call compiled and through the tape, their ratio, and whether both computed the same
# checksum (they agree bit for bit: test tape_agrees_with_compiled).
#
#   bench/tape_speed.sh MBSGEN KERNEL_CALL_TIMING [EXTRA_MODEL.yaml ...]
# e.g. bench/tape_speed.sh build/bench/generator/mbsgen build/bench/bench/kernel_call_timing chain30.yaml
set -euo pipefail
cd "$(dirname "$0")/.."
mbsgen=$1 timing=$2
shift 2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cxx=${CXX:-c++}
models=()
while read -r id model scene flags; do
  [[ -z "$id" || "$id" == \#* || "$scene" != full ]] && continue
  models+=("$id:$model")
done < generated/models.txt
for extra in "$@"; do models+=("$(basename "$extra" .yaml | tr -c 'A-Za-z0-9_\n' _):$extra"); done
printf '%-28s %-12s %14s %14s %8s %s\n' model kernel compiled_s tape_s ratio same
for entry in "${models[@]}"; do
  id=${entry%%:*} model=${entry#*:}
  dir=$work/$id
  if ! "$mbsgen" generate "$model" --id "$id" --out "$dir" --tape >/dev/null 2>"$work/err"; then
    grep -q "closed loops" "$work/err" && continue
    cat "$work/err" >&2
    exit 1
  fi
  "$cxx" -O2 -std=c++17 -shared -fPIC "$dir/$id.cpp" -o "$dir/lib$id.so"
  "$timing" "$id" "$dir/lib$id.so" "$dir/$id.tape" > "$work/times" 2>/dev/null || continue  # a descriptor model: no M, Q, K
  for kernel in mass_matrix residual linear; do
    read -r _ _ tc cc < <(grep "^0 $kernel " "$work/times")
    read -r _ _ tt ct < <(grep "^1 $kernel " "$work/times")
    awk -v m="$id" -v k="$kernel" -v a="$tc" -v b="$tt" -v s="$([[ "$cc" == "$ct" ]] && echo yes || echo NO)" \
      'BEGIN { printf "%-28s %-12s %14.4g %14.4g %8.1f %s\n", m, k, a, b, b / a, s }'
  done
done

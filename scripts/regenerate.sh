#!/usr/bin/env bash
# Rewrites the committed kernels in generated/ from the models listed in generated/models.txt.
# Usage: scripts/regenerate.sh [MBSGEN]   (default: builds and uses build/dev/generator/mbsgen)
set -euo pipefail
cd "$(dirname "$0")/.."
mbsgen=${1:-}
if [[ -z "$mbsgen" ]]; then
  cmake --preset dev >/dev/null
  cmake --build build/dev --target mbsgen -j"$(nproc)"
  mbsgen=build/dev/generator/mbsgen
fi
while read -r id model scene flags; do
  [[ -z "$id" || "$id" == \#* ]] && continue
  extra=()
  IFS=, read -r -a names <<< "${flags:-}"
  for flag in "${names[@]}"; do extra+=("--$flag"); done  # dynamics, sensitivity
  "$mbsgen" generate "$model" --scene "$scene" --id "$id" --out "generated/$id" "${extra[@]}"
done < generated/models.txt

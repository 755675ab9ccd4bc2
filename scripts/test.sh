#!/usr/bin/env bash
# Installs what is missing, configures with the "ci" preset (-Werror), builds and runs ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/deps.sh
cmake --preset ci
cmake --build --preset ci -j "$(nproc)"
ctest --preset ci -j "$(nproc)" "$@"

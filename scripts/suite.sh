#!/usr/bin/env bash
# The test suite of one preset: installs what is missing, configures, builds and runs ctest,
# printing when each phase ended (docs/build-times.md). scripts/test.sh (preset ci) and
# scripts/sanitize.sh (preset asan) call it; arguments after the preset go to ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
preset="$1"
shift
phase() { echo "$preset suite: $1 ended after ${SECONDS} s" >&2; }
scripts/deps.sh
phase "packages"
cmake --preset "$preset"
cmake --build --preset "$preset" -j "$(nproc)"
phase "build"
ctest --preset "$preset" -j "$(nproc)" "$@"
phase "tests"

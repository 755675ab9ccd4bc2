#!/usr/bin/env bash
# Installs what is missing, then builds and runs the test suite twice (docs/testing.md):
#   1. preset "ci": gcc, RelWithDebInfo, -Werror;
#   2. preset "asan": gcc -O1 with AddressSanitizer and UndefinedBehaviorSanitizer (options and
#      suppressions in the preset's environment). MBSGEN_ASAN=0 skips this run.
# Arguments go to both ctest runs.
set -euo pipefail
cd "$(dirname "$0")/.."
phase() { echo "test.sh: $1 ended after ${SECONDS} s" >&2; }  # where the time goes (docs/build-times.md)
scripts/deps.sh
phase "packages"
cmake --preset ci
cmake --build --preset ci -j "$(nproc)"
phase "ci build"
ctest --preset ci -j "$(nproc)" "$@"
phase "ci tests"

if [ "${MBSGEN_ASAN:-1}" != 0 ]; then
  cmake --preset asan
  cmake --build --preset asan -j "$(nproc)"
  phase "asan build"
  # Every test runs under the sanitizers but consumer_builds_against_install: it links an
  # uninstrumented out-of-tree consumer against the installed, instrumented static libraries,
  # which cannot work; it checks packaging, which the "ci" run above covers.
  ctest --preset asan -j "$(nproc)" -E '^consumer_builds_against_install$' "$@"
  phase "asan tests"
fi

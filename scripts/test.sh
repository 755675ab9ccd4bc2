#!/usr/bin/env bash
# Installs what is missing, then builds and runs the test suite as built for use (preset "ci":
# gcc, RelWithDebInfo -O2 -g1, -Werror; the tests' own code at -O1, docs/build-times.md).
# CI (.ci/run) runs scripts/sanitize.sh after it: the same suite under AddressSanitizer and
# UndefinedBehaviorSanitizer (docs/testing.md). Arguments go to ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
phase() { echo "test.sh: $1 ended after ${SECONDS} s" >&2; }  # where the time goes (docs/build-times.md)
scripts/deps.sh
phase "packages"
cmake --preset ci
cmake --build --preset ci -j "$(nproc)"
phase "build"
ctest --preset ci -j "$(nproc)" "$@"
phase "tests"

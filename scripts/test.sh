#!/usr/bin/env bash
# Installs what is missing, then builds and runs the test suite as built for use (preset "ci":
# gcc, RelWithDebInfo -O2 -g1, -Werror; the tests' own code at -O1, docs/build-times.md).
# CI (.ci/run) runs scripts/sanitize.sh after it: the same suite under AddressSanitizer and
# UndefinedBehaviorSanitizer (docs/testing.md). Arguments go to ctest.
exec "$(dirname "$0")/suite.sh" ci "$@"

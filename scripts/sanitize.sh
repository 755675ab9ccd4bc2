#!/usr/bin/env bash
# Installs what is missing, then builds and runs the whole test suite under AddressSanitizer and
# UndefinedBehaviorSanitizer with warnings as errors (preset "asan": gcc -O1 -g1 -DNDEBUG; the
# sanitizers' options are in the preset's environment; docs/testing.md says which checks and why).
# CI (.ci/run) runs it after scripts/test.sh. Arguments go to ctest.
exec "$(dirname "$0")/suite.sh" asan "$@"

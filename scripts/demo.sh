#!/usr/bin/env bash
# Installs what is missing, builds mbsgen, generates the double pendulum's kernels, and runs them:
# the linear model, natural frequencies against the closed form, and a frequency response.
# (The middle-ear model will take the double pendulum's place here, issue 6.)
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/deps.sh
cmake --preset dev > /dev/null
cmake --build --preset dev -j "$(nproc)" --target demo_double_pendulum mbsgen
echo
build/dev/generator/mbsgen info models/textbook/double_pendulum.yaml
echo
build/dev/examples/demo/demo_double_pendulum

#!/usr/bin/env bash
# The Python examples (examples/python, docs/python.md): installs what they need besides the
# package's own packages (python3-matplotlib, when run as root), builds the package (preset ci)
# and runs each example, writing its plot into build/examples/. Not part of scripts/test.sh: the
# test suite needs no plotting library. The plots in docs/ were made by this script (pass --docs
# to write them there instead).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/deps.sh python3-matplotlib
cmake --preset ci > /dev/null
cmake --build --preset ci -j 2 --target _mbsgen mbsgen mbsgen-core mbsgen-tape > /dev/null
out=build/examples
[ "${1:-}" = --docs ] && out=docs
mkdir -p "$out"
export PYTHONPATH="$PWD/build/ci/python" MBSGEN="$PWD/build/ci/generator/mbsgen"
/usr/bin/python3 examples/python/middle_ear_bode.py "$out/python_middle_ear.png"
/usr/bin/python3 examples/python/double_pendulum_modes.py "$out/python_double_pendulum.png"
/usr/bin/python3 examples/python/bicycle_eigenvalues.py "$out/python_bicycle.png"
/usr/bin/python3 examples/python/pendulum_simulation_vs_frf.py "$out/python_pendulum_simulation.png"
/usr/bin/python3 examples/python/elastic_arm.py "$out/urdf_elastic_arm.png"

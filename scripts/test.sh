#!/usr/bin/env bash
# Fresh machine to green tests: install packages, build, run every test.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
cd build && ctest --output-on-failure -j"$(nproc)"
cd ..
# The Python module, installed the README's way into a virtual environment, and its tests.
python3_debian=/usr/bin/python3
"$python3_debian" -m venv --system-site-packages build/venv
build/venv/bin/pip install --no-build-isolation --no-index --quiet .
SDFCONTOUR_CLI="$PWD/build/sdfcontour" build/venv/bin/python -m pytest -q -p no:cacheprovider tests/python

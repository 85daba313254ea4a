#!/usr/bin/env bash
# Fresh machine to green tests: install packages, build, run the tests.
#   bash scripts/test.sh         every test but those labelled slow (ctest label, pytest marker)
#   bash scripts/test.sh --all   every test (what CI runs, .ci/run)
set -euo pipefail
cd "$(dirname "$0")/.."
ctest_select=(-LE slow)
pytest_select=(-m "not slow")
case "${1:-}" in
  --all) ctest_select=(); pytest_select=() ;;
  "") ;;
  *) echo "usage: bash scripts/test.sh [--all]" >&2; exit 2 ;;
esac
bash scripts/setup.sh
bash scripts/build.sh
cd build && ctest --output-on-failure -j"$(nproc)" "${ctest_select[@]}"
cd ..
# The Python module, installed the README's way into a virtual environment, and its tests.
python3_debian=/usr/bin/python3
"$python3_debian" -m venv --system-site-packages build/venv
build/venv/bin/pip install --no-build-isolation --no-index --quiet .
SDFCONTOUR_CLI="$PWD/build/sdfcontour" build/venv/bin/python -m pytest -q -p no:cacheprovider \
  "${pytest_select[@]}" tests/python

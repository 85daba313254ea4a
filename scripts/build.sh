#!/usr/bin/env bash
# Configures and builds sdfcontour (Release, -O3) into build/: every target, or only those named
# (scripts/example.sh builds the command-line tool alone: bash scripts/build.sh sdfcontour_cli).
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
targets=()
for t in "$@"; do targets+=(--target "$t"); done
cmake --build build -j"$(nproc)" "${targets[@]}"

#!/usr/bin/env bash
# Fresh machine to a mesh: install packages, build, contour a built-in torus.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh sdfcontour_cli  # the library and the tool: what the example runs
mkdir -p out
./build/sdfcontour contour builtin:torus@64 -o out/torus_gcp.ply --method gcp \
  --points out/torus_gcp_points.ply --stats out/torus_stats.json

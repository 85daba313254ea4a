#!/usr/bin/env bash
# Installs the Debian 12 packages sdfcontour needs to build, test and benchmark.
# Idempotent: apt-get skips what is already there. `--bench` adds what only the docs' renders
# need (VTK, drawn off screen under Xvfb: bench/vtk_render.py).
set -euo pipefail
packages=(
  cmake g++ make pkg-config
  libcgal-dev libgmp-dev libmpfr-dev libboost-dev
  libeigen3-dev libtbb-dev libcli11-dev nlohmann-json3-dev libgtest-dev libopenvdb-dev libboost-iostreams-dev
  python3-numpy python3-scipy python3-skimage python3-matplotlib
  python3-dev pybind11-dev python3-setuptools python3-wheel python3-venv python3-pip python3-pytest
  python3-dask python3-distributed python3-zarr python3-h5py
)
if [ "${1:-}" = "--bench" ]; then
  packages+=(python3-vtk9 xvfb xauth)
fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

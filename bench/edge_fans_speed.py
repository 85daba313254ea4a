"""Wall time of GCP with edge fans against scikit-image's marching cubes in the same run (issue 64's
ratios), with the local reconstruction's stages, on one shared mesh's grid.

scikit-image: best of 3 on the array in memory; sdfcontour: one run of the CLI each (reading the
grid and writing the mesh included), its stages from --stats.

    /usr/bin/python3 bench/edge_fans_speed.py [--mesh bunny] [--res 256] [--grid FILE.npy]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
from skimage.measure import marching_cubes

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from common import CLI, sample_shared_mesh  # noqa: E402

RUNS = [("marching cubes", ["--method", "mc"]),
        ("GCP default", []),
        ("edge fans", ["--edge-fans", "on"]),
        ("edge fans, lattice, band 4", ["--edge-fans", "on", "--gradient", "lattice", "--band", "4"]),
        ("edge fans, lattice, band 2", ["--edge-fans", "on", "--gradient", "lattice", "--band", "2"])]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", default="bunny")
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--grid", default="", help="a grid .npy to use instead of sampling the mesh")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as work:
        grid = args.grid or sample_shared_mesh(args.mesh, args.res, work) + ".npy"
        g = np.load(grid)
        best = float("inf")
        for _ in range(3):
            t = time.perf_counter()
            marching_cubes(g, 0.0)
            best = min(best, time.perf_counter() - t)
        print(f"{args.mesh} {g.shape[0]}^3: scikit-image's marching cubes {best:.3f} s\n")
        print("| method | seconds | / scikit-image | triangles | stages (s) |\n|---|---|---|---|---|")
        for label, options in RUNS:
            out, stats = os.path.join(work, "m.ply"), os.path.join(work, "s.json")
            t = time.perf_counter()
            subprocess.run([CLI, "contour", grid, "-o", out, "-q", "--stats", stats, *options],
                           check=True, capture_output=True)
            seconds = time.perf_counter() - t
            s = json.load(open(stats))
            stages = ", ".join(f"{k} {v:.2f}" for k, v in s.get("local_seconds", {}).items() if v)
            print(f"| {label} | {seconds:.2f} | {seconds / best:.1f} | {s.get('mesh', {}).get('triangles', '')} "
                  f"| {stages} |", flush=True)


if __name__ == "__main__":
    main()

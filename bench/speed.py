"""Wall time of sdfcontour's stages against peers measured in the same run, as ratios.

- marching cubes: `sdfcontour contour GRID --method mc` against scikit-image's marching_cubes
  (Lewiner) on the same grid, both including reading the grid from disk;
- the regular triangulation with parallel insertion against serial insertion.
Best of `--repeat` runs each. Usage: /usr/bin/python3 bench/speed.py [--cli build/sdfcontour]
"""
import argparse
import json
import os
import subprocess
import tempfile
import time

import numpy as np
from skimage.measure import marching_cubes


def torus_grid(n):
    x = np.linspace(-1, 1, n)
    X, Y, Z = np.meshgrid(x, x, x, indexing="ij")
    return np.sqrt((np.sqrt(X**2 + Y**2) - 0.55) ** 2 + Z**2) - 0.25


def best_of(repeat, fn):
    best = float("inf")
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", default="build/sdfcontour")
    ap.add_argument("--sizes", default="64,128,192")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print("| grid | ours MC (s) | scikit-image MC (s) | ratio ours/peer | RT parallel (s) | RT serial (s) | ratio |")
    print("|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as d:
        for n in map(int, args.sizes.split(",")):
            path = os.path.join(d, "g.npy")
            np.save(path, torus_grid(n))
            out = os.path.join(d, "m.ply")
            ours = best_of(args.repeat, lambda: subprocess.run(
                [args.cli, "contour", path, "-o", out, "--method", "mc", "-q"], check=True, stdout=subprocess.DEVNULL))
            peer = best_of(args.repeat, lambda: marching_cubes(np.load(path), 0.0, spacing=(2 / (n - 1),) * 3))
            tri = {}
            if n <= 128:
                for mode, flags in (("parallel", []), ("serial", ["--serial-triangulation"])):
                    stats = os.path.join(d, "s.json")
                    def run():
                        subprocess.run([args.cli, "contour", path, "-o", out, "--method", "mt-rt", "-q", "--stats", stats,
                                        *flags], check=True, stdout=subprocess.DEVNULL)
                    tri[mode] = min((run(), json.load(open(stats))["seconds"]["triangulation"])[1] for _ in range(2))
            rt = (f"{tri['parallel']:.2f} | {tri['serial']:.2f} | {tri['parallel'] / tri['serial']:.2f}" if tri
                  else "- | - | -")
            print(f"| {n}³ | {ours:.3f} | {peer:.3f} | {ours / peer:.2f} | {rt} |", flush=True)


if __name__ == "__main__":
    main()

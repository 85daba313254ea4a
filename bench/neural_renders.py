"""Renders for docs/notes/local.md: the neural SDF fixture (bench/data/neural_bunny.npz) sampled on a
grid, as a saved .npy is passed, contoured by marching cubes, by GCP taking the values as
distances (zero_set=False: its contact points miss by the samples' depth times the slope's
error), and by GCP as it chooses (the values found no exact distances: every vertex on the grid's
tricubic zero set); each titled with its L1 to the network's zero set (marching cubes at 512^3,
the first panel). Rendered with VTK (bench/vtk_render.py; runs itself under xvfb-run where there
is no display).

    /usr/bin/python3 bench/neural_renders.py [--res 64] [--out docs/img/neural_grid.png]

(with the sdfcontour package importable: installed, or on PYTHONPATH)
"""
import argparse
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from neural import grid_of  # noqa: E402
from neural_sdf import load  # noqa: E402
from vtk_render import ensure_display, render  # noqa: E402

ROOT = os.path.dirname(HERE)
import sdfcontour  # noqa: E402

METHODS = [("MC", dict(method="mc")),
           ("GCP, values as distances", dict(zero_set=False)),
           ("GCP (found no exact distances)", dict())]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", type=int, default=64)
    ap.add_argument("--reference", type=int, default=512)
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "img", "neural_grid.png"))
    args = ap.parse_args()
    ensure_display()
    f = load(os.path.join(HERE, "data", "neural_bunny.npz"))
    Vr, Fr = sdfcontour.contour(f, resolution=args.reference, method="mc")
    grid = grid_of(f, args.res)
    fig = plt.figure(figsize=(16, 4.3), dpi=100)
    panels = [(f"the network's zero set (MC {args.reference}³)", Vr, Fr, None)]
    for label, options in METHODS:
        V, F = sdfcontour.contour(grid, **options)
        l1 = sdfcontour.distances(V, F, Vr, Fr, samples=100000)["L1"]
        panels.append((f"{args.res}³ grid, {label}", V, F, l1))
        print(label, l1, flush=True)
    for col, (title, V, F, l1) in enumerate(panels):
        ax = fig.add_subplot(1, len(panels), col + 1)
        ax.imshow(render(V, F, azimuth=-60.0, elevation=15.0, zoom=1.3))
        ax.set_axis_off()
        ax.set_title(title + (f": L1 {l1:.1e}" if l1 is not None else ""), fontsize=10)
    fig.tight_layout()
    fig.savefig(args.out)


if __name__ == "__main__":
    main()

"""Renders for docs/local.md: a shared mesh with parts thinner than a spacing (the sword's blade)
on a fine grid, contoured by marching cubes and by GCP's local reconstruction without and with
thin parts ("auto" turns them on there from the grid's subspacing gaps), side by side, each titled
with its L1 to the ground truth (VTK, bench/vtk_render.py; under xvfb-run where there is no
display). The grid is sampled truncated at 8 spacings, as bench/local.py's 256^3 runs were.

    /usr/bin/python3 bench/thin_part_renders.py [--mesh sword] [--res 256]
        [--out docs/img/thin_part_renders.png]

(with the sdfcontour package importable: installed, or on PYTHONPATH)
"""
import argparse
import os
import subprocess
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from common import CLI, MESHES  # noqa: E402
from vtk_render import ensure_display, render  # noqa: E402

ROOT = os.path.dirname(HERE)
import numpy as np  # noqa: E402
import sdfcontour  # noqa: E402

METHODS = [("MC", dict(method="mc")),
           ("GCP-local, no thin parts", dict(method="gcp", thin_parts=False)),
           ("GCP-local, auto (thin parts)", dict(method="gcp"))]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", default="sword")
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "img", "thin_part_renders.png"))
    args = ap.parse_args()
    ensure_display()
    with tempfile.TemporaryDirectory() as d:
        prefix = os.path.join(d, args.mesh)
        subprocess.run([CLI, "sample", os.path.join(MESHES, args.mesh + ".obj"), "--res",
                        str(args.res), "--truncate", "8", "-o", prefix, "-q"], check=True,
                       stdout=subprocess.DEVNULL)
        V_gt, F_gt = sdfcontour.read_mesh(prefix + "_mesh.ply")
        grid = np.load(prefix + ".npy")
    fig = plt.figure(figsize=(15, 3.6), dpi=100)
    for col, (label, options) in enumerate(METHODS):
        V, F = sdfcontour.contour(grid, **options)
        l1 = sdfcontour.distances(V, F, V_gt, F_gt, samples=100000)["L1"]
        ax = fig.add_subplot(1, len(METHODS), col + 1)
        image = render(V, F, size=700, azimuth=-75.0, elevation=40.0, zoom=0.95)
        rows = np.flatnonzero((image < 0.98).any(axis=(1, 2)))  # the rows the sword is on
        ax.imshow(image[max(rows[0] - 10, 0):rows[-1] + 10] if len(rows) else image)
        ax.set_axis_off()
        ax.set_title(f"{args.mesh} {args.res}³, {label}: L1 {l1:.1e}", fontsize=10)
        print(args.mesh, label, l1, flush=True)
    fig.tight_layout()
    fig.savefig(args.out)


if __name__ == "__main__":
    main()

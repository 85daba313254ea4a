"""Renders for docs/notes/local.md: one CAD mesh and one organic mesh from the shared meshes at a coarse
grid, contoured by marching cubes, GCP with its Poisson reconstruction and GCP with its local
reconstruction (brick by brick), side by side, each titled with its L1 to the ground truth
(rendered with VTK, bench/vtk_render.py; runs itself under xvfb-run where there is no display).

    /usr/bin/python3 bench/local_renders.py [--meshes cube,wingnut,bunny] [--res 32]
        [--out docs/img/local_renders.png]

With --thin-parts: one mesh with parts thinner than a spacing (the sword's blade) on a fine grid
(256^3, truncated at 8 spacings as bench/local.py's 256^3 runs), by marching cubes and by the
local reconstruction without and with thin parts ("auto" turns them on there from the grid's
subspacing gaps), into docs/img/thin_part_renders.png.

(with the sdfcontour package importable: installed, or on PYTHONPATH)
"""
import argparse
import os
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from common import sample_shared_mesh  # noqa: E402
from vtk_render import ensure_display, render  # noqa: E402

ROOT = os.path.dirname(HERE)
import numpy as np  # noqa: E402
import sdfcontour  # noqa: E402

METHODS = [("MC", dict(method="mc")),
           ("GCP-Poisson", dict(method="gcp", reconstruction="poisson")),
           ("GCP-local", dict(method="gcp", reconstruction="local"))]


THIN_PART_METHODS = [("MC", dict(method="mc")),
                     ("GCP-local, no thin parts", dict(method="gcp", thin_parts=False)),
                     ("GCP-local, auto (thin parts)", dict(method="gcp"))]


def thin_parts_figure(name, res, out):
    with tempfile.TemporaryDirectory() as d:
        prefix = sample_shared_mesh(name, res, d, truncate=8)
        V_gt, F_gt = sdfcontour.read_mesh(prefix + "_mesh.ply")
        grid = np.load(prefix + ".npy")
    fig = plt.figure(figsize=(15, 3.6), dpi=100)
    for col, (label, options) in enumerate(THIN_PART_METHODS):
        V, F = sdfcontour.contour(grid, **options)
        l1 = sdfcontour.distances(V, F, V_gt, F_gt, samples=100000)["L1"]
        ax = fig.add_subplot(1, len(THIN_PART_METHODS), col + 1)
        image = render(V, F, size=700, azimuth=-75.0, elevation=40.0, zoom=0.95)
        rows = np.flatnonzero((image < 0.98).any(axis=(1, 2)))  # the rows the mesh is on
        ax.imshow(image[max(rows[0] - 10, 0):rows[-1] + 10] if len(rows) else image)
        ax.set_axis_off()
        ax.set_title(f"{name} {res}³, {label}: L1 {l1:.1e}", fontsize=10)
        print(name, label, l1, flush=True)
    fig.tight_layout()
    fig.savefig(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", help="default: cube,wingnut,bunny (--thin-parts: sword)")
    ap.add_argument("--res", type=int, help="default: 32 (--thin-parts: 256)")
    ap.add_argument("--out", help="default: docs/img/local_renders.png "
                                  "(--thin-parts: docs/img/thin_part_renders.png)")
    ap.add_argument("--thin-parts", action="store_true", help="the thin-part figure (see above)")
    args = ap.parse_args()
    ensure_display()
    if args.thin_parts:
        return thin_parts_figure(args.meshes or "sword", args.res or 256, args.out or os.path.join(
            ROOT, "docs", "img", "thin_part_renders.png"))
    args.meshes = args.meshes or "cube,wingnut,bunny"
    args.res = args.res or 32
    args.out = args.out or os.path.join(ROOT, "docs", "img", "local_renders.png")
    names = args.meshes.split(",")
    fig = plt.figure(figsize=(12, 4.1 * len(names)), dpi=100)
    for row, name in enumerate(names):
        with tempfile.TemporaryDirectory() as d:
            prefix = sample_shared_mesh(name, args.res, d)
            V_gt, F_gt = sdfcontour.read_mesh(prefix + "_mesh.ply")
            grid = np.load(prefix + ".npy")
        for col, (label, options) in enumerate(METHODS):
            V, F = sdfcontour.contour(grid, **options)
            l1 = sdfcontour.distances(V, F, V_gt, F_gt, samples=100000)["L1"]
            ax = fig.add_subplot(len(names), len(METHODS), row * len(METHODS) + col + 1)
            azimuth = -35.0 if name != "cube" else -30.0
            ax.imshow(render(V, F, azimuth=azimuth, elevation=25.0, zoom=1.0 if name == "cube" else 1.25))
            ax.set_axis_off()
            ax.set_title(f"{name} {args.res}³, {label}: L1 {l1:.1e}", fontsize=10)
            print(name, label, l1, flush=True)
    fig.tight_layout()
    fig.savefig(args.out)


if __name__ == "__main__":
    main()

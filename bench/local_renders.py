"""Renders for docs/local.md: one CAD mesh and one organic mesh from the shared meshes at a coarse
grid, contoured by marching cubes, GCP with its Poisson reconstruction and GCP with its local
reconstruction (brick by brick), side by side, each titled with its L1 to the ground truth
(rendered with VTK, bench/vtk_render.py; runs itself under xvfb-run where there is no display).

    /usr/bin/python3 bench/local_renders.py [--meshes cube,wingnut,bunny] [--res 32]
        [--out docs/img/local_renders.png]

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


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", default="cube,wingnut,bunny")
    ap.add_argument("--res", type=int, default=32)
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "img", "local_renders.png"))
    args = ap.parse_args()
    ensure_display()
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

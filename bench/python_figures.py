"""Pictures for docs/python.md, made with the Python module: marching cubes and GCP meshes of a
shared mesh's 32^3 grid beside the ground truth (rendered with VTK, bench/vtk_render.py), and L1
error against grid resolution.

Usage (with the module installed, e.g. scripts/test.sh's build/venv):
    build/venv/bin/python bench/python_figures.py [--mesh spot] [--out docs/img]
"""
import argparse
import os
import subprocess
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import sdfcontour
from vtk_render import ensure_display, render

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
MESHES = os.path.join(ROOT, "..", "shared", "data", "meshes")
CLI = os.path.join(ROOT, "build", "sdfcontour")


def draw(ax, V, F, title):
    ax.imshow(render(V, F))
    ax.set_axis_off()
    ax.set_title(title, fontsize=10)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mesh", default="spot")
    ap.add_argument("--res", type=int, default=32)
    ap.add_argument("--sweep", default="16,24,32,48,64,96")
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "img"))
    args = ap.parse_args()
    ensure_display()
    with tempfile.TemporaryDirectory() as d:
        # The normalised ground truth, from the CLI (sample scales it into [-0.9, 0.9]^3).
        subprocess.run([CLI, "sample", os.path.join(MESHES, args.mesh + ".obj"), "--res", "16", "-o",
                        os.path.join(d, "m"), "-q"], check=True, stdout=subprocess.DEVNULL)
        V_gt, F_gt = sdfcontour.read_mesh(os.path.join(d, "m_mesh.ply"))
    grids = {}
    def grid(n):
        if n not in grids:
            grids[n] = sdfcontour.sample(V_gt, F_gt, resolution=n, scale=None)
        return grids[n]
    g = grid(args.res)
    meshes = [("ground truth", (V_gt, F_gt))]
    for method in ("mc", "gcp"):
        V, F = sdfcontour.contour(g, method=method)
        l1 = sdfcontour.distances(V, F, V_gt, F_gt, samples=100000)["L1"]
        meshes.append((f"{method.upper()} {args.res}³, L1 {l1:.1e}", (V, F)))
    fig = plt.figure(figsize=(12, 4.2), dpi=110)
    for i, (title, (V, F)) in enumerate(meshes):
        draw(fig.add_subplot(1, 3, i + 1), V, F, title)
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "python_meshes.png"))
    sweep = [int(n) for n in args.sweep.split(",")]
    errors = {"mc": [], "gcp": []}
    for n in sweep:
        for method in errors:
            V, F = sdfcontour.contour(grid(n), method=method)
            errors[method].append(sdfcontour.distances(V, F, V_gt, F_gt, samples=100000)["L1"])
        print(n, {m: e[-1] for m, e in errors.items()}, flush=True)
    fig, ax = plt.subplots(figsize=(5.5, 4), dpi=110)
    for method, label in (("mc", "marching cubes"), ("gcp", "GCP")):
        ax.loglog(sweep, errors[method], "o-", label=label)
    ax.set_xlabel("grid samples per axis")
    ax.set_ylabel("L1 distance to the ground truth")
    ax.set_title(f"{args.mesh}: error against resolution")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "python_error.png"))
    with open(os.path.join(args.out, "python_error.csv"), "w") as f:
        f.write("resolution,mc_l1,gcp_l1\n")
        for n, a, b in zip(sweep, errors["mc"], errors["gcp"]):
            f.write(f"{n},{a:.6e},{b:.6e}\n")


if __name__ == "__main__":
    main()

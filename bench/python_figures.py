"""Pictures for docs/python.md, made with the Python module: marching cubes and GCP meshes of a
shared mesh's 32^3 grid beside the ground truth, and L1 error against grid resolution.

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
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

import sdfcontour

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
MESHES = os.path.join(ROOT, "..", "shared", "data", "meshes")
CLI = os.path.join(ROOT, "build", "sdfcontour")


def read_ply(path):
    with open(path, "rb") as f:
        header = []
        while True:
            line = f.readline().decode().strip()
            header.append(line)
            if line == "end_header":
                break
        counts = {w[1]: int(w[2]) for w in (l.split() for l in header) if w[0] == "element"}
        V = np.frombuffer(f.read(counts["vertex"] * 24), dtype="<f8").reshape(-1, 3)
        F = np.frombuffer(f.read(counts["face"] * 13), dtype=[("n", "u1"), ("i", "<i4", 3)])["i"]
    return V.copy(), F.copy()


def draw(ax, V, F, title):
    tris = V[F]
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
    light = np.array([0.4, -0.5, 0.75]) / np.linalg.norm([0.4, -0.5, 0.75])
    shade = 0.25 + 0.75 * np.clip(n @ light, 0, 1)
    colors = np.outer(shade, [0.62, 0.72, 0.86])
    ax.add_collection3d(Poly3DCollection(tris, facecolors=colors, edgecolors="none"))
    lo, hi = V.min(0), V.max(0)
    c, r = (lo + hi) / 2, (hi - lo).max() / 2
    ax.set_xlim(c[0] - r, c[0] + r)
    ax.set_ylim(c[1] - r, c[1] + r)
    ax.set_zlim(c[2] - r, c[2] + r)
    ax.view_init(elev=15, azim=-60)
    ax.set_axis_off()
    ax.set_title(title, fontsize=10)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mesh", default="spot")
    ap.add_argument("--res", type=int, default=32)
    ap.add_argument("--sweep", default="16,24,32,48,64,96")
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "img"))
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as d:
        # The normalised ground truth, from the CLI (sample scales it into [-0.9, 0.9]^3).
        subprocess.run([CLI, "sample", os.path.join(MESHES, args.mesh + ".obj"), "--res", "2", "-o",
                        os.path.join(d, "m"), "-q"], check=True, stdout=subprocess.DEVNULL)
        V_gt, F_gt = read_ply(os.path.join(d, "m_mesh.ply"))
    grids = {}
    def grid(n):
        if n not in grids:
            grids[n] = sdfcontour.sample(V_gt, F_gt, resolution=n)
        return grids[n]
    g = grid(args.res)
    meshes = [("ground truth", (V_gt, F_gt))]
    for method in ("mc", "gcp"):
        V, F = sdfcontour.contour(g, method=method)
        l1 = sdfcontour.distances(V, F, V_gt, F_gt, samples=100000)["L1"]
        meshes.append((f"{method.upper()} {args.res}³, L1 {l1:.1e}", (V, F)))
    fig = plt.figure(figsize=(12, 4.2), dpi=110)
    for i, (title, (V, F)) in enumerate(meshes):
        draw(fig.add_subplot(1, 3, i + 1, projection="3d"), V, F, title)
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

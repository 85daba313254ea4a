"""A picture for docs/edge_fans.md: one shared mesh on a coarse grid, contoured by marching cubes,
by the default local reconstruction and with edge fans (`--edge-fans on`), triangles drawn
(matplotlib), each titled with its triangle count and L1 to the ground truth.

    /usr/bin/python3 bench/edge_fan_renders.py [--mesh bunny] [--res 24] \\
        [--out docs/img/edge_fans.png]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402
import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from common import CLI, sample_shared_mesh  # noqa: E402
from local import read_ply  # noqa: E402

RUNS = [("marching cubes", ["--method", "mc"]), ("GCP, default", []),
        ("GCP, edge fans", ["--edge-fans", "on"])]


def draw(ax, V, F, title):
    light = np.array([0.4, 0.5, 0.75])
    light /= np.linalg.norm(light)
    n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    shade = 0.35 + 0.65 * np.clip(n @ light, 0, 1)
    colors = np.outer(shade, [0.62, 0.72, 0.86])
    poly = Poly3DCollection(V[F], facecolors=colors, edgecolors=(0.1, 0.15, 0.25, 0.6),
                            linewidths=0.25)
    ax.add_collection3d(poly)
    lo, hi = V.min(axis=0), V.max(axis=0)
    c, r = (lo + hi) / 2, (hi - lo).max() / 2
    ax.set_xlim(c[0] - r, c[0] + r)
    ax.set_ylim(c[2] - r, c[2] + r)
    ax.set_zlim(c[1] - r, c[1] + r)
    ax.view_init(elev=15, azim=-60)
    ax.set_axis_off()
    ax.set_title(title, fontsize=9)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", default="bunny")
    ap.add_argument("--res", type=int, default=24)
    ap.add_argument("--out", default=os.path.join(HERE, "..", "docs", "img", "edge_fans.png"))
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as work:
        prefix = sample_shared_mesh(args.mesh, args.res, work)
        fig = plt.figure(figsize=(12, 4.4))
        for col, (label, options) in enumerate(RUNS):
            out = os.path.join(work, f"{col}.ply")
            subprocess.run([CLI, "contour", prefix + ".npy", "-o", out, "-q", *options],
                           check=True, capture_output=True)
            e = json.loads(subprocess.run([CLI, "eval", out, prefix + "_mesh.ply"],
                                          capture_output=True, text=True, check=True).stdout)
            V, F = read_ply(out)
            V = V[:, [0, 2, 1]]  # y up
            ax = fig.add_subplot(1, len(RUNS), col + 1, projection="3d")
            draw(ax, V, F, f"{label}: {len(F):,} triangles, L1 {e['L1']:.1e}")
        fig.suptitle(f"{args.mesh} at {args.res}³", fontsize=11)
        fig.tight_layout()
        fig.savefig(args.out, dpi=150)
    print(args.out)


if __name__ == "__main__":
    main()

"""Where the sharp-edge distance of bench/local.py comes from: for one shared mesh and grid, the
mean distance from the ground truth's sharp-edge points (dihedral > 30 degrees, every h/4) to MC's
and GCP-local's meshes, by the turn between the two faces and by convexity, the share of points
on edges shorter than h/2, and the distance to the nearest GCP contact point.

Distances are to a dense sampling of each mesh (spacing h/30, so at most ~h/60 too large).

    /usr/bin/python3 bench/sharp_edges.py hammer 64 [--png docs/img/sharp_edges_hammer64.png]

With --png, a picture of the edge points coloured by their distance to each mesh (MC, GCP-local),
concave ones as triangles.
"""
import os
import subprocess
import sys
import tempfile

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import CLI, MESHES  # noqa: E402
from local import area_samples, read_ply, sharp_edges  # noqa: E402

TURNS = [(30, 45), (45, 100), (100, 180)]


def edge_points(V, F, step, angle=30.0):
    """Points every `step` along the sharp edges (as bench/local.py), with each point's turn
    (degrees), convexity and edge length."""
    edges, n = sharp_edges(V, F, angle)
    rows = []
    for a, b, f0, f1 in edges:
        length = np.linalg.norm(V[b] - V[a])
        other = [v for v in F[f1] if v not in (a, b)][0]
        convex = n[f0] @ (V[other] - V[a]) < 0
        turn = np.degrees(np.arccos(np.clip(n[f0] @ n[f1], -1, 1)))
        m = max(1, int(np.ceil(length / step)))
        for s in (np.arange(m) + 0.5) / m:
            rows.append((*(V[a] + s * (V[b] - V[a])), turn, convex, length))
    return np.array(rows).reshape(-1, 6)


def dense_points(V, F, step):
    """Points over the triangles' area, about `step` apart on average, and the vertices."""
    A = V[F]
    area = 0.5 * np.linalg.norm(np.cross(A[:, 1] - A[:, 0], A[:, 2] - A[:, 0]), axis=1).sum()
    return np.vstack([area_samples(V, F, count=int(2 * area / step ** 2)), V])


def plot(E, dist, h, title, path):
    """Edge points coloured by their distance (in spacings) to MC's and GCP-local's meshes."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    # View along the axis with the smallest extent, so the part is seen flat on.
    axes = np.argsort(np.ptp(E[:, :3], axis=0))[::-1][:2]
    # Framed on the far points (the worst fifth for GCP-local), where the two meshes differ.
    far = E[dist["local"] >= np.percentile(dist["local"], 80)][:, axes]
    lo, hi = far.min(axis=0) - 2 * h, far.max(axis=0) + 2 * h
    fig, panels = plt.subplots(1, 2, figsize=(11, 5.5), constrained_layout=True)
    for ax, method in zip(panels, ("mc", "local")):
        for convex, marker in ((True, "o"), (False, "^")):
            s = E[:, 4] == convex
            art = ax.scatter(E[s, axes[0]], E[s, axes[1]], c=dist[method][s], s=14, marker=marker,
                             cmap="viridis", vmin=0, vmax=0.5)
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_title(f"{'MC' if method == 'mc' else 'GCP-local'}: mean {dist[method].mean():.3f} h "
                     f"(concave {dist[method][E[:, 4] == 0].mean():.3f} h)")
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
    fig.colorbar(art, ax=panels, label="distance to the mesh (spacings); triangles: concave")
    fig.suptitle(title)
    fig.savefig(path, dpi=110)


def main():
    name, res = sys.argv[1], int(sys.argv[2])
    png = sys.argv[sys.argv.index("--png") + 1] if "--png" in sys.argv else ""
    h = 2.0 / (res - 1)
    work = tempfile.mkdtemp()
    prefix = os.path.join(work, f"{name}{res}")
    subprocess.run([CLI, "sample", os.path.join(MESHES, name + ".obj"), "--res", str(res), "-o",
                    prefix, "--quiet"], check=True, capture_output=True)
    E = edge_points(*read_ply(prefix + "_mesh.ply"), step=h / 4)
    runs = {"mc": ["--method", "mc"], "local": ["--method", "gcp", "--reconstruction", "local",
                                                "--points", prefix + "_points.ply"]}
    dist = {}
    for method, args in runs.items():
        subprocess.run([CLI, "contour", prefix + ".npy", "-o", f"{prefix}_{method}.ply", "--quiet",
                        *args], check=True, capture_output=True)
        tree = cKDTree(dense_points(*read_ply(f"{prefix}_{method}.ply"), h / 30))
        dist[method] = tree.query(E[:, :3])[0] / h
    nearest = cKDTree(read_ply(prefix + "_points.ply")[0]).query(E[:, :3])[0] / h
    print(f"{name} {res}^3: {len(E)} edge points, {int((E[:, 5] < h / 2).sum())} on edges shorter "
          "than h/2; mean distance in spacings\n")
    print("| edges | points | GCP-local | MC | nearest contact point (median) |")
    print("|---|---|---|---|---|")
    for lo, hi in TURNS:
        for convex in (True, False):
            s = (E[:, 3] >= lo) & (E[:, 3] < hi) & (E[:, 4] == convex)
            if s.any():
                print(f"| {'convex' if convex else 'concave'}, {lo}-{hi} deg | {int(s.sum())} | "
                      f"{dist['local'][s].mean():.3f} | {dist['mc'][s].mean():.3f} | "
                      f"{np.median(nearest[s]):.3f} |")
    print(f"| all | {len(E)} | {dist['local'].mean():.3f} | {dist['mc'].mean():.3f} | "
          f"{np.median(nearest):.3f} |")
    if png:
        plot(E, dist, h, f"{name} at {res}^3: sharp-edge points (dihedral > 30 deg) where the meshes "
             "differ most", png)


if __name__ == "__main__":
    main()

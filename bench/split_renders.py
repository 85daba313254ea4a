"""Where the local reconstruction splits its sagging edges (docs/notes/local.md, session 18): a close-up
of the bunny's ear tip at 128^3 (the triangles within 0.05 of a point just under its highest
vertex) with the triangles' edges drawn, for one subdivision level without
the split, one level with it (the default) and two uniform levels; each panel titled with its
triangles and its L1 (the whole mesh's, against the ground truth mesh).

    /usr/bin/python3 bench/split_renders.py --png docs/img/split_sag.png
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import CLI  # noqa: E402
from local import read_ply  # noqa: E402
from vtk_render import ensure_display, render  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
MESHES = os.path.join(HERE, "..", "..", "shared", "data", "meshes")
VARIANTS = [("one level, no split", ["--subdivisions", "1", "--split-sag", "0"]),
            ("one level, sagging edges split (default)", []),
            ("two uniform levels", ["--subdivisions", "2", "--split-sag", "0"])]


def close_up(V, F, centre, radius):
    """The triangles of (V, F) whose corners all lie within `radius` of `centre`."""
    inside = np.linalg.norm(V - centre, axis=1) < radius
    return V, F[inside[F].all(axis=1)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--mesh", default="bunny")
    ap.add_argument("--png", default="split_sag.png")
    ap.add_argument("--work", default=os.path.join(tempfile.gettempdir(), "sdfcontour-split"))
    args = ap.parse_args()
    ensure_display()
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    os.makedirs(args.work, exist_ok=True)
    prefix = os.path.join(args.work, f"{args.mesh}{args.res}")
    if not os.path.exists(prefix + ".npy"):
        subprocess.run([CLI, "sample", os.path.join(MESHES, args.mesh + ".obj"), "--res",
                        str(args.res), "-o", prefix, "--quiet"], check=True)
    fig, axes = plt.subplots(1, len(VARIANTS), figsize=(4.2 * len(VARIANTS), 4.6))
    centre = None
    for ax, (name, extra) in zip(axes, VARIANTS):
        out = prefix + f"_{len(name)}.ply"
        subprocess.run([CLI, "contour", prefix + ".npy", "-o", out, "--reconstruction", "local",
                        "--quiet", *extra], check=True, capture_output=True)
        e = json.loads(subprocess.run([CLI, "eval", out, prefix + "_mesh.ply"],
                                      capture_output=True, text=True, check=True).stdout)
        V, F = read_ply(out)
        if centre is None:  # the ear's tip: the highest vertex
            centre = V[np.argmax(V[:, 1])] - np.array([0.0, 0.05, 0.0])
        Vc, Fc = close_up(V, F, centre, 0.05)
        ax.imshow(render(Vc, Fc, size=520, edges=True, azimuth=70.0, elevation=15.0, zoom=1.2))
        ax.set_title(f"{name}\n{len(F):,} triangles, L1 {e['L1']:.2e}", fontsize=10)
        ax.axis("off")
    fig.tight_layout(rect=(0, 0, 1, 0.96))
    fig.savefig(args.png, dpi=110)
    print(args.png)


if __name__ == "__main__":
    main()

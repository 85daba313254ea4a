"""Smooth shapes (issue 35's target): the built-in sphere (radius 0.6) and torus (radii 0.55 and
0.25) on N^3 grids over [-1, 1]^3, contoured by marching cubes, GCP with Poisson and GCP's local
reconstruction. Per shape, grid and method: triangles, the mean distance from the mesh to the
exact surface over the mesh's area (200,000 area-uniform samples, one seed: the same for every
run) and the largest vertex distance, both in spacings, and the wall time. JSON lines on stdout;
--markdown writes the table.

    /usr/bin/python3 bench/smooth_shapes.py --res 64,256 --markdown docs/results/smooth_shapes.md
"""
import argparse
import os
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import CLI, keep, timed  # noqa: E402
from local import area_samples, read_ply  # noqa: E402

METHODS = {
    "mc": ["--method", "mc"],
    "gcp-poisson": ["--method", "gcp", "--reconstruction", "poisson"],
    "gcp-local": ["--method", "gcp", "--reconstruction", "local"],
}


def distance(shape, x):
    """The exact signed distance of the built-in shape at points x (k x 3)."""
    if shape == "sphere":
        return np.linalg.norm(x, axis=1) - 0.6
    ring = np.stack([np.hypot(x[:, 0], x[:, 1]) - 0.55, x[:, 2]], axis=1)
    return np.linalg.norm(ring, axis=1) - 0.25


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--res", default="64,256")
    ap.add_argument("--shapes", default="sphere,torus")
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--markdown", default="")
    a = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as work:
        for res in map(int, a.res.split(",")):
            h = 2.0 / (res - 1)
            for shape in a.shapes.split(","):
                for method in a.methods.split(","):
                    out = os.path.join(work, f"{shape}{res}_{method}.ply")
                    seconds, peak, _, err = timed([CLI, "contour", f"builtin:{shape}@{res}", "-o",
                                                   out, "--quiet", *METHODS[method]])
                    if err:
                        raise SystemExit(" ".join(err))
                    V, F = read_ply(out)
                    V = V.astype(float)
                    row = dict(shape=shape, res=res, method=method, triangles=len(F),
                               l1_h=float(np.abs(distance(shape, area_samples(V, F))).mean() / h),
                               worst_vertex_h=float(np.abs(distance(shape, V)).max() / h),
                               seconds=seconds, peak_mb=peak)
                    keep(rows, row)
    if a.markdown:
        with open(a.markdown, "w") as f:
            f.write(markdown_table(rows))


def markdown_table(rows):
    """The rows as docs/results/smooth_shapes.md shows them."""
    head = ("# Smooth shapes: the built-in sphere and torus\n\n"
            "`/usr/bin/python3 bench/smooth_shapes.py` (bench/smooth_shapes.py): mean distance "
            "from the mesh's area to the exact surface and the largest vertex distance, in "
            "spacings.\n\n"
            "| shape | grid | method | triangles | L1 (h) | worst vertex (h) | seconds |\n"
            "|---|---|---|---|---|---|---|\n")
    return head + "".join(
        f"| {r['shape']} | {r['res']}^3 | {r['method']} | {r['triangles']:,} | {r['l1_h']:.6f} | "
        f"{r['worst_vertex_h']:.2g} | {r['seconds']:.1f} |\n" for r in rows)


if __name__ == "__main__":
    main()

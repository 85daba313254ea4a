"""How much of a mesh's L1 is its vertices' and how much its triangles': the default local mesh
and the edge-fanned one (`--edge-fans on`) as GCP makes them, then with every vertex moved onto
its closest point on the true surface (the ground-truth mesh). What is left then is the triangle
layout's own L1 with its vertices exact (without the chord offset that GCP's projection adds on
curved parts, which the ground truths' flat facets do not have): what better vertex placement
alone could reach with the same triangles.

Grids as bench/scale.py samples them (float32; exact at <= 128^3, truncated at 8 spacings above,
which leaves the finer grid exact near the surface). L1 from `sdfcontour eval`; triangles against
our marching cubes' on the same grid.

Usage: /usr/bin/python3 bench/fan_floor.py [--res 128,256] [--meshes bunny,spot,armadillo]
       [--work /tmp/sdfcontour_scale] [--out docs/results/fan_floor.md]
"""
import argparse
import os
import subprocess
import sys

import numpy as np

from common import CLI, geomean, keep, l1, report, scale_grid
from local import read_ply
from scale import write_ply


def closest_on_triangles(P, A, B, C):
    """The closest point to each P[i] on triangle (A[i], B[i], C[i]) (Ericson's regions)."""
    ab, ac, ap = B - A, C - A, P - A
    d1, d2 = (ab * ap).sum(1), (ac * ap).sum(1)
    bp = P - B
    d3, d4 = (ab * bp).sum(1), (ac * bp).sum(1)
    cp = P - C
    d5, d6 = (ab * cp).sum(1), (ac * cp).sum(1)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = 1.0 / (va + vb + vc)
        out = A + ab * (vb * denom)[:, None] + ac * (vc * denom)[:, None]  # inside
        t = d1 / (d1 - d3)  # edge AB
        m = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
        out[m] = (A + t[:, None] * ab)[m]
        t = d2 / (d2 - d6)  # edge AC
        m = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
        out[m] = (A + t[:, None] * ac)[m]
        t = (d4 - d3) / ((d4 - d3) + (d5 - d6))  # edge BC
        m = (va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0)
        out[m] = (B + t[:, None] * (C - B))[m]
    for m, X in (((d1 <= 0) & (d2 <= 0), A), ((d3 >= 0) & (d4 <= d3), B),
                 ((d6 >= 0) & (d5 <= d6), C)):
        out[m] = X[m]
    return out


def onto_surface(V, gt_V, gt_F, k=24):
    """Each of V moved to its closest point on the mesh (gt_V, gt_F): the closest among the
    k triangles whose centroids lie nearest (the ground truths' triangles span several spacings,
    and the vertices lie within a few hundredths of one from them)."""
    from scipy.spatial import cKDTree
    tri = gt_V[gt_F]
    _, near = cKDTree(tri.mean(1)).query(V, k=k)
    best = V.copy()
    best_d = np.full(len(V), np.inf)
    for j in range(k):
        t = tri[near[:, j]]
        q = closest_on_triangles(V, t[:, 0], t[:, 1], t[:, 2])
        d = ((q - V) ** 2).sum(1)
        better = d < best_d
        best[better], best_d[better] = q[better], d[better]
    return best


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--res", default="128,256")
    ap.add_argument("--meshes", default="bunny,spot,armadillo")
    ap.add_argument("--work", default="/tmp/sdfcontour_scale")
    ap.add_argument("--out")
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    rows = []
    variants = {"default": [], "edge fans": ["--edge-fans", "on"]}
    for res in [int(r) for r in args.res.split(",")]:
        for name in args.meshes.split(","):
            prefix = scale_grid(CLI, args.work, name, res)
            gt = prefix + "_mesh.ply"
            mc = os.path.join(args.work, f"floor_{name}_{res}_mc.ply")
            subprocess.run([CLI, "contour", prefix + ".npy", "-o", mc, "--method", "mc", "-q"],
                           check=True)
            mc_triangles = len(read_ply(mc)[1])
            for label, options in variants.items():
                out = os.path.join(args.work, f"floor_{name}_{res}_{label.replace(' ', '_')}.ply")
                subprocess.run([CLI, "contour", prefix + ".npy", "-o", out, "-q", *options],
                               check=True)
                V, F = read_ply(out)
                exact = out[:-4] + "_exact.ply"
                write_ply(exact, onto_surface(V, *read_ply(gt)), F)
                keep(rows, {"mesh": name, "res": res, "method": label, "L1": l1(CLI, out, gt),
                            "L1_exact_vertices": l1(CLI, exact, gt),
                            "triangles_over_mc": len(F) / mc_triangles})
    lines = ["| grid | mesh | method | L1 | L1, every vertex on the surface | triangles / MC's |",
             "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['res']}³ | {r['mesh']} | {r['method']} | {r['L1']:.3e} | "
                     f"{r['L1_exact_vertices']:.3e} | {r['triangles_over_mc']:.2f} |")
    lines += ["", "Geometric means over the meshes, against the default's L1 on the same grid:", "",
              "| grid | method | L1 / default's | L1 with every vertex on the surface / default's |",
              "|---|---|---|---|"]
    for res in sorted({r["res"] for r in rows}):
        base = {r["mesh"]: r["L1"] for r in rows if r["res"] == res and r["method"] == "default"}
        for label in variants:
            sel = [r for r in rows if r["res"] == res and r["method"] == label]
            lines.append(f"| {res}³ | {label} | {geomean([r['L1'] / base[r['mesh']] for r in sel]):.3f} | "
                         f"{geomean([r['L1_exact_vertices'] / base[r['mesh']] for r in sel]):.3f} |")
    report("\n".join(lines) + "\n", args.out)


if __name__ == "__main__":
    sys.exit(main())

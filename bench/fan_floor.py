"""How much of a mesh's L1 is its vertices' and how much its triangles': the default local mesh
and the edge-fanned one (`--edge-fans on`) as GCP makes them, then with every vertex moved onto
its closest point on the true surface (the ground-truth mesh). What is left then is the triangle
layout's own L1 with its vertices exact (without the chord offset that GCP's projection adds on
curved parts, which the ground truths' flat facets do not have): what better vertex placement
alone could reach with the same triangles.

With `--best-offsets`, a third L1 for the edge fans: each exact vertex then moved along its normal
by the offsets that best fit the true surface in least squares (30 points sampled on it per
vertex, three Gauss-Newton rounds, each offset within 0.05 h): the layout's floor with its
vertices placed as well as the true surface allows, chord offsets and all, which no contourer
reaches from samples. (With fewer points than that per vertex the fit is underdetermined and
lands above the exact vertices' L1.)

Grids as bench/scale.py samples them (float32; exact at <= 128^3, truncated at 8 spacings above,
which leaves the finer grid exact near the surface). L1 from `sdfcontour eval`; triangles against
our marching cubes' on the same grid.

Usage: /usr/bin/python3 bench/fan_floor.py [--res 128,256] [--meshes bunny,spot,armadillo]
       [--work /tmp/sdfcontour_scale] [--out docs/results/fan_floor.md] [--best-offsets]
"""
import argparse
import os
import subprocess
import sys

import numpy as np

from common import CLI, geomean, keep, l1, read_jsonl, report, scale_grid
from local import area_samples, read_ply
from scale import write_ply


# The default issue 64 was filed against (bench/issue64_accuracy.py).
FILING = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "docs", "results",
                      "targets", "accuracy.jsonl")


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


def closest_triangles(P, V, F, k=12):
    """Each of P's closest point on the mesh (V, F) among the k triangles whose centroids lie
    nearest, and that triangle."""
    from scipy.spatial import cKDTree
    T = V[F]
    _, near = cKDTree(T.mean(1)).query(P, k=k)
    best = np.full(len(P), np.inf)
    tri = np.zeros(len(P), dtype=int)
    Q = P.copy()
    for j in range(k):
        t = near[:, j]
        q = closest_on_triangles(P, T[t, 0], T[t, 1], T[t, 2])
        d = ((q - P) ** 2).sum(1)
        better = d < best
        best[better], tri[better], Q[better] = d[better], t[better], q[better]
    return Q, tri


def onto_surface(V, gt_V, gt_F, k=24):
    """Each of V moved to its closest point on the mesh (gt_V, gt_F): the closest among the
    k triangles whose centroids lie nearest (the ground truths' triangles span several spacings,
    and the vertices lie within a few hundredths of one from them)."""
    return closest_triangles(V, gt_V, gt_F, k)[0]


def best_offsets(V, F, gt_V, gt_F, h, rounds=3, per_vertex=30):
    """V moved along its vertex normals by the offsets that fit the true surface (gt_V, gt_F) best
    in least squares: the signed gaps between surface points and their closest mesh points, along
    the mesh's normals, linearised in the offsets (barycentric weights times the normals' cosine),
    solved with a little damping and each offset kept within 0.05 h."""
    from scipy.sparse import csr_matrix
    from scipy.sparse.linalg import lsqr
    X = area_samples(gt_V, gt_F, per_vertex * len(V))
    W = V.copy()
    for _ in range(rounds):
        fn = np.cross(W[F[:, 1]] - W[F[:, 0]], W[F[:, 2]] - W[F[:, 0]])
        N = np.zeros_like(W)
        for j in range(3):
            np.add.at(N, F[:, j], fn)
        with np.errstate(invalid="ignore", divide="ignore"):  # (triangles the snap made flat)
            N = np.nan_to_num(N / np.linalg.norm(N, axis=1)[:, None])
            fn = np.nan_to_num(fn / np.linalg.norm(fn, axis=1)[:, None])
        Q, t = closest_triangles(X, W, F)
        gap = ((Q - X) * fn[t]).sum(1)
        a, b, c = (W[F[t, j]] for j in range(3))
        e0, e1, e2 = b - a, c - a, Q - a
        d00, d01, d11 = (e0 * e0).sum(1), (e0 * e1).sum(1), (e1 * e1).sum(1)
        d20, d21 = (e2 * e0).sum(1), (e2 * e1).sum(1)
        den = d00 * d11 - d01 * d01
        with np.errstate(invalid="ignore", divide="ignore"):
            bv, bw = (d11 * d20 - d01 * d21) / den, (d00 * d21 - d01 * d20) / den
            bary = np.stack([1 - bv - bw, bv, bw], 1)
        bary[~np.isfinite(bary).all(1)] = 0  # (a flat triangle's point moves with no vertex)
        bary = np.clip(bary, 0, 1)
        values = bary * np.einsum("pkj,pj->pk", N[F[t]], fn[t])
        A = csr_matrix((values.ravel(), (np.repeat(np.arange(len(X)), 3), F[t].ravel())),
                       shape=(len(X), len(W)))
        offset = lsqr(A, -gap, damp=0.05, atol=1e-10, btol=1e-10, iter_lim=300)[0]
        W = W + np.clip(offset, -0.05 * h, 0.05 * h)[:, None] * N
    return W


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--res", default="128,256")
    ap.add_argument("--meshes", default="bunny,spot,armadillo")
    ap.add_argument("--work", default="/tmp/sdfcontour_scale")
    ap.add_argument("--out")
    ap.add_argument("--best-offsets", action="store_true",
                    help="also the L1 with the least-squares best offsets along the normals")
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
                on = onto_surface(V, *read_ply(gt))
                write_ply(exact, on, F)
                row = {"mesh": name, "res": res, "method": label, "L1": l1(CLI, out, gt),
                       "L1_exact_vertices": l1(CLI, exact, gt),
                       "triangles_over_mc": len(F) / mc_triangles}
                if args.best_offsets and label == "edge fans":
                    best = out[:-4] + "_best.ply"
                    write_ply(best, best_offsets(on, F, *read_ply(gt), 2.0 / (res - 1)), F)
                    row["L1_best_offsets"] = l1(CLI, best, gt)
                keep(rows, row)
    best = args.best_offsets
    filing = {(r["mesh"], r["res"]): r["L1"] for r in read_jsonl(FILING)
              if r.get("method") == "gcp-local"}
    lines = ["| grid | mesh | method | L1 | L1, every vertex on the surface |"
             + (" L1, best offsets | best / the filing's |" if best else "")
             + " triangles / MC's |", "|---|---|---|---|---|" + ("---|---|" if best else "") + "---|"]
    for r in rows:
        extra = ""
        if best and "L1_best_offsets" in r:
            f = filing.get((r["mesh"], r["res"]))
            extra = (f" {r['L1_best_offsets']:.3e} | "
                     + (f"{r['L1_best_offsets'] / f:.3f}" if f else "") + " |")
        elif best:
            extra = " | |"
        lines.append(f"| {r['res']}³ | {r['mesh']} | {r['method']} | {r['L1']:.3e} | "
                     f"{r['L1_exact_vertices']:.3e} |{extra} {r['triangles_over_mc']:.2f} |")
    lines += ["", "Geometric means over the meshes, against the default's L1 on the same grid:", "",
              "| grid | method | L1 / default's | L1 with every vertex on the surface / default's |"
              + (" L1 with the best offsets / default's |" if best else ""),
              "|---|---|---|---|" + ("---|" if best else "")]
    for res in sorted({r["res"] for r in rows}):
        base = {r["mesh"]: r["L1"] for r in rows if r["res"] == res and r["method"] == "default"}
        for label in variants:
            sel = [r for r in rows if r["res"] == res and r["method"] == label]
            lines.append(f"| {res}³ | {label} | {geomean([r['L1'] / base[r['mesh']] for r in sel]):.3f} | "
                         f"{geomean([r['L1_exact_vertices'] / base[r['mesh']] for r in sel]):.3f} |"
                         + (f" {geomean([r['L1_best_offsets'] / base[r['mesh']] for r in sel]):.3f} |"
                            if best and label == "edge fans" else " |" if best else ""))
    report("\n".join(lines) + "\n", args.out)


if __name__ == "__main__":
    sys.exit(main())

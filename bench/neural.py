"""GCP on a neural SDF (bench/data/neural_bunny.npz, a 4x64 MLP fitted to the bunny, evaluated
with numpy), passed as a callable as users pass theirs: marching cubes, GCP with the Poisson
reconstruction and GCP with the local one (with and without the refinement on the callable), at
64^3 and 128^3; and the network sampled on a grid first (an array, as a saved .npy is passed):
marching cubes, GCP as it chooses (the values found no exact distances: the local reconstruction
on the grid's tricubic zero set), without the zero set, and with Poisson. The reference is the
network's own zero set: marching cubes of it at 512^3.
Reports L1 to the reference, the ratio to MC's L1 at the same grid, whether GCP fell back to
marching cubes, wall time and evaluations.

    /usr/bin/python3 bench/neural.py --res 64,128 --markdown docs/results/neural.md
"""
import argparse
import json
import os
import time

import numpy as np

import sdfcontour
from neural_sdf import load

HERE = os.path.dirname(os.path.abspath(__file__))
VARIANTS = {
    "mc": dict(method="mc"),
    "gcp-poisson": dict(reconstruction="poisson"),
    "gcp-local, no refine": dict(reconstruction="local", refine=False),
    "gcp-local": dict(reconstruction="local"),
}
GRID_VARIANTS = {
    "grid: mc": dict(method="mc"),
    "grid: gcp": dict(),
    "grid: gcp, zero_set off": dict(zero_set=False),
    "grid: gcp-poisson": dict(reconstruction="poisson"),
}


def grid_of(f, res):
    """The network's values on the res^3 grid over [-1, 1]^3, a[i, j, k] at (x_i, y_j, z_k)."""
    x = np.linspace(-1.0, 1.0, res)
    out = np.empty((res, res, res))
    for i in range(res):
        Y, Z = np.meshgrid(x, x, indexing="ij")
        out[i] = f(np.stack([np.full(Y.size, x[i]), Y.ravel(), Z.ravel()], axis=1)).reshape(res, res)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--weights", default=os.path.join(HERE, "data", "neural_bunny.npz"))
    ap.add_argument("--res", default="64,128")
    ap.add_argument("--reference", type=int, default=512)
    ap.add_argument("--markdown", default="")
    args = ap.parse_args()
    f = load(args.weights)
    t = time.time()
    Vr, Fr = sdfcontour.contour(f, resolution=args.reference, method="mc")
    print(json.dumps({"reference": args.reference, "seconds": time.time() - t,
                      "triangles": len(Fr)}), flush=True)
    rows = []
    for res in [int(r) for r in args.res.split(",")]:
        grid = grid_of(f, res)
        for name, options in list(VARIANTS.items()) + list(GRID_VARIANTS.items()):
            t = time.time()
            if name.startswith("grid: "):
                V, F, stats = sdfcontour.contour(grid, return_stats=True, **options)
                stats["evaluations"] = res ** 3
            else:
                V, F, stats = sdfcontour.contour(f, resolution=res, return_stats=True, **options)
            seconds = time.time() - t
            d = sdfcontour.distances(V, F, Vr, Fr, samples=200000)
            row = {"res": res, "variant": name, "L1": d["L1"], "L_inf": d["L_inf"],
                   "closed": d["closed"], "seconds": seconds, "triangles": len(F),
                   "fallback": stats.get("fallback", ""),
                   "evaluations": stats["evaluations"] + stats.get("refine_evaluations", 0)}
            rows.append(row)
            print(json.dumps(row), flush=True)
    if args.markdown:
        lines = ["# GCP on a neural SDF", "",
                 f"`/usr/bin/python3 bench/neural.py` (bench/neural.py): a 4x64 MLP fitted to the "
                 f"bunny, as a callable, and sampled on the grid first (`grid:` rows, an array; "
                 f"the grid's seconds leave its sampling out); L1 to the network's zero set "
                 f"(marching cubes at {args.reference}^3), over marching cubes' of the same "
                 f"input.", "",
                 "| grid | variant | L1 | L1 / MC | fallback | closed | triangles | evaluations | "
                 "seconds |", "|---|---|---|---|---|---|---|---|---|"]
        for res in sorted({r["res"] for r in rows}):
            for r in (r for r in rows if r["res"] == res):
                mc = next(q["L1"] for q in rows if q["res"] == res and q["variant"] ==
                          ("grid: mc" if r["variant"].startswith("grid: ") else "mc"))
                lines.append(f"| {res}³ | {r['variant']} | {r['L1']:.3e} | {r['L1'] / mc:.3f} | "
                             f"{r['fallback'] or 'no'} | {r['closed']} | {r['triangles']} | "
                             f"{r['evaluations']} | {r['seconds']:.1f} |")
        with open(args.markdown, "w") as out:
            out.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()

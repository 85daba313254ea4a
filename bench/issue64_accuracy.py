"""Issue 64's accuracy targets, read against the default it was filed against: L1 within 1.05x of
that default's (geometric mean of the L1 over MC's, per grid), no mesh more than 10% worse, and
L-infinity no worse than marching cubes' on any shared mesh from 64^3.

The default of the filing is docs/results/targets/accuracy.jsonl (bench/local_targets.py's run,
the one whose costs issue 64 quotes: bunny 64^3 4.5 s, 256^3 29.3 s). The runs to read are
bench/local.py's JSON lines on the same grids (exact up to 128^3, `--truncate 8` at 256^3), with
the method to read given by its label and marching cubes from the same run:

    /usr/bin/python3 bench/local.py --res 32,64,128 --methods mc --variant def:"" > now.jsonl
    /usr/bin/python3 bench/local.py --res 256 --truncate 8 --methods mc \
        --variant def:"" >> now.jsonl
    /usr/bin/python3 bench/issue64_accuracy.py now.jsonl --method def --out docs/results/x.md
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import geomean, read_jsonl, report  # noqa: E402

BASELINE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "docs", "results",
                        "targets", "accuracy.jsonl")


def runs_at(now, base, method, res):
    """(mesh, row, MC's row, the filing's row or None) per mesh that `method` ran at `res` with
    marching cubes in the same run: `now` and `base` keyed by (mesh, res, method)."""
    for mesh in sorted({k[0] for k in now if k[1] == res and k[2] == method}):
        mc = now.get((mesh, res, "mc"))
        if mc:
            yield mesh, now[(mesh, res, method)], mc, base.get((mesh, res, "gcp-local"))


def filing_summary(ratios):
    """From {mesh: L1 over the filing's}: the geometric mean, the same without the cube, the worst
    mesh, and the meshes more than 10% worse (as "mesh ratio")."""
    worst = max(ratios, key=ratios.get)
    return (geomean(list(ratios.values())),
            geomean([v for m, v in ratios.items() if m != "cube"]), worst,
            [f"{m} {v:.3f}" for m, v in sorted(ratios.items()) if v > 1.10])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("runs", nargs="+", help="bench/local.py JSON lines")
    ap.add_argument("--method", default="gcp-local", help="the label of the method to read")
    ap.add_argument("--baseline", default=BASELINE)
    ap.add_argument("--out")
    args = ap.parse_args()
    base = {(r["mesh"], r["res"], r["method"]): r
            for r in read_jsonl(args.baseline) if "method" in r}
    now = {}
    for path in args.runs:
        for r in read_jsonl(path):
            if "method" in r:
                now[(r["mesh"], r["res"], r["method"])] = r
    lines = ["| grid | mesh | L1 / the filing's | L1 / MC's (the filing's) | L∞ / MC's | "
             "triangles / MC's | seconds (the filing's) |", "|---|---|---|---|---|---|---|"]
    summary = ["| grid | meshes | geometric mean of L1 / the filing's (without the cube) | "
               "worst (mesh) | more than 10% worse | L∞ above MC's |",
               "|---|---|---|---|---|---|"]
    for res in sorted({k[1] for k in now if k[2] == args.method}):
        ratios, linf = {}, []
        for mesh, r, mc, b in runs_at(now, base, args.method, res):
            if not b:
                continue
            ratio = r["L1"] / b["L1"]
            ratios[mesh] = ratio
            linf_mc = r["Linf"] / mc["Linf"]
            if res >= 64 and linf_mc > 1:
                linf.append(f"{mesh} {linf_mc:.3f}")
            lines.append(f"| {res}³ | {mesh} | {ratio:.3f} | {r['L1'] / mc['L1']:.3f} "
                         f"({b['L1'] / mc['L1']:.3f}) | {linf_mc:.3f} | "
                         f"{r['triangles'] / mc['triangles']:.2f} | {r['seconds']:.2f} "
                         f"({b['seconds']:.2f}) |")
        if not ratios:
            continue
        mean, without_cube, worst, worse = filing_summary(ratios)
        summary.append(f"| {res}³ | {len(ratios)} | {mean:.3f} ({without_cube:.3f}) | "
                       f"{ratios[worst]:.3f} ({worst}) | {', '.join(worse) or 'none'} | "
                       f"{', '.join(linf) or 'none'} |")
    runs = ", ".join(os.path.basename(r) for r in args.runs)
    head = [f"Issue 64's accuracy targets: `{args.method}` in {runs} against the default the "
            "issue was filed against (docs/results/targets/accuracy.jsonl), marching cubes from "
            "the same runs (`bench/issue64_accuracy.py`).", ""]
    report("\n".join(head + summary + [""] + lines) + "\n", args.out)


if __name__ == "__main__":
    sys.exit(main())

"""Draws bench/scale.py's JSON lines as two panels: each method's time over scikit-image's on the
same grid, and its L1 over our MC's, against the grid's resolution (geometric means over the
meshes), with a time target (--target; 20x, the first scale issue's, by default).

Usage: /usr/bin/python3 bench/scale.py ... > run.jsonl   (the JSON lines it prints)
       /usr/bin/python3 bench/scale_plot.py run.jsonl [more.jsonl ...] --png docs/img/scale.png
"""
import argparse
import json
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from common import geomean  # noqa: E402

STYLE = {"gcp": ("GCP", "C3", "o"), "mt-rt": ("MT-RT", "C1", "s"), "mc": ("our MC", "C0", "^"),
         "openvdb": ("OpenVDB", "C2", "v"), "vtk": ("VTK flying edges", "C4", "D")}


def ratios(rows):
    """{method: {res: (time ratio, L1 ratio)}}, geometric means over the meshes."""
    by = {(r["mesh"], r["res"], r["method"]): r for r in rows}
    out = defaultdict(dict)
    for method in STYLE:
        for res in sorted({r["res"] for r in rows}):
            t, e = [], []
            for mesh in sorted({r["mesh"] for r in rows}):
                r, sk, mc = by.get((mesh, res, method)), by.get((mesh, res, "skimage")), by.get((mesh, res, "mc"))
                if not r or r["seconds"] is None or not sk or not mc:
                    continue
                t.append(r["seconds"] / sk["seconds"])
                if r["L1"] and mc["L1"]:
                    e.append(r["L1"] / mc["L1"])
            if t:
                out[method][res] = (geomean(t), geomean(e) if e else None)
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("jsonl", nargs="+")
    ap.add_argument("--png", required=True)
    ap.add_argument("--target", type=float, default=20,
                    help="GCP's time target over scikit-image's, drawn as a line (issue 35: 5)")
    args = ap.parse_args()
    rows = []
    for path in args.jsonl:
        with open(path) as f:
            rows += [r for r in map(json.loads, filter(str.strip, f)) if "method" in r]
    data = ratios(rows)
    fig, (ax_t, ax_e) = plt.subplots(1, 2, figsize=(10, 4))
    for method, (label, color, marker) in STYLE.items():
        if method not in data:
            continue
        res = sorted(data[method])
        ax_t.plot(res, [data[method][r][0] for r in res], marker=marker, color=color, label=label)
        if method != "mc":
            pts = [(r, data[method][r][1]) for r in res if data[method][r][1]]
            ax_e.plot([p[0] for p in pts], [p[1] for p in pts], marker=marker, color=color, label=label)
    ax_t.axhline(args.target, color="C3", ls=":", lw=1)
    ax_t.text(70, args.target * 1.1, f"target for GCP: {args.target:g}x", color="C3", fontsize=8)
    ax_t.axhline(1, color="gray", ls="-", lw=0.5)
    ax_e.axhline(1, color="C0", ls="-", lw=0.5)
    ax_e.text(70, 1.04, "our MC", color="C0", fontsize=8)
    for ax in (ax_t, ax_e):
        ax.set_xscale("log", base=2)
        ticks = sorted({r["res"] for r in rows})
        ax.set_xticks(ticks, [str(t) for t in ticks])
        ax.minorticks_off()
        ax.set_xlabel("grid samples per axis")
        ax.grid(True, which="both", alpha=0.3)
    ax_t.set_yscale("log")
    ax_t.set_ylabel("time / scikit-image's (np.load + marching_cubes)")
    ax_e.set_ylabel("L1 to the mesh / our MC's")
    ax_t.set_title("Time, 2 cores")
    ax_e.set_title("Distance to the true surface")
    ax_t.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(args.png, dpi=110)


if __name__ == "__main__":
    main()

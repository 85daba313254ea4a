"""Draws bench/scale.py's JSON lines as the choice a user makes: one panel per grid size, each
method or option set (scale.py's --variant) a point at its time over scikit-image's (x) and its
L1 over our MC's (y), labelled with its triangles over MC's (N×); geometric means over the
meshes.

Usage: /usr/bin/python3 bench/scale.py --res 64,256 --methods gcp,mc,skimage \\
           --variant 'fans:--edge-fans on' ... > run.jsonl
       /usr/bin/python3 bench/options_plot.py run.jsonl --png docs/img/options.png
"""
import argparse
import json

import matplotlib
import matplotlib.ticker

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from common import over_peer  # noqa: E402


def means(rows, res):
    """{method: (time / scikit-image, L1 / MC, triangles / MC)} at res^3, geometric means over the
    meshes (common.over_peer)."""
    methods = dict.fromkeys(r["method"] for r in rows if r["res"] == res and r.get("seconds"))
    out = {}
    for method in methods:
        t = over_peer(rows, res, method, "seconds", "skimage")
        if t == t:  # (nan: no mesh with scikit-image's time)
            out[method] = (t, over_peer(rows, res, method, "L1", "mc"),
                           over_peer(rows, res, method, "triangles", "mc"))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("jsonl", nargs="+")
    ap.add_argument("--png", required=True)
    args = ap.parse_args()
    rows = []
    for path in args.jsonl:
        with open(path) as f:
            rows += [json.loads(line) for line in f if line.strip().startswith("{")]
    sizes = sorted({r["res"] for r in rows})
    fig, axes = plt.subplots(1, len(sizes), figsize=(4.6 * len(sizes), 4.2), squeeze=False)
    methods = list(dict.fromkeys(r["method"] for r in rows))
    for ax, res in zip(axes[0], sizes):
        for method, (t, e, n) in means(rows, res).items():
            k = methods.index(method)
            ax.scatter([t], [e], color=f"C{k}", marker="os^vDP*X"[k % 8], s=45, zorder=3,
                       label=method)
            if method not in ("mc", "skimage"):  # (MC's own triangles)
                ax.annotate(f"{n:.1f}×", (t, e), textcoords="offset points", xytext=(6, 3),
                            fontsize=8)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.yaxis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%.2g"))
        ax.yaxis.set_minor_formatter(matplotlib.ticker.FormatStrFormatter("%.2g"))
        ax.set_xlabel("time / scikit-image's (2 cores)")
        ax.set_ylabel("L1 / our MC's")
        ax.set_title(f"{res}³")
        ax.grid(True, which="both", alpha=0.3)
        ax.margins(0.25)
    axes[0][-1].legend(fontsize=8, loc="upper right")
    fig.suptitle("time, L1 and (labels) triangles, each over the peers' on the same grids", fontsize=10)
    fig.tight_layout()
    fig.savefig(args.png, dpi=110)


if __name__ == "__main__":
    main()

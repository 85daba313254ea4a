"""bench/local.py's JSON lines drawn as L1 against triangles, both over marching cubes' from the
same run: one arrow per shared mesh from variant A to variant B, one panel per grid size, so that
a trade of triangles and time for accuracy shows mesh by mesh.

    /usr/bin/python3 bench/variants_plot.py runs.jsonl --from def --to s1a --png docs/img/x.png
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import geomean, read_jsonl  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("runs", nargs="+", help="bench/local.py JSON lines")
    ap.add_argument("--from", dest="a", required=True, help="the label the arrows start from")
    ap.add_argument("--to", dest="b", required=True, help="the label they end at")
    ap.add_argument("--png", required=True)
    ap.add_argument("--res", default="", help="comma-separated grid sizes (default: every one)")
    ap.add_argument("--title", default="")
    args = ap.parse_args()
    rows = {(r["mesh"], r["res"], r["method"]): r for path in args.runs
            for r in read_jsonl(path) if "L1" in r}
    sizes = sorted({res for (_, res, m) in rows if m == args.b and
                    (not args.res or str(res) in args.res.split(","))})
    if not sizes:
        sys.exit(f"no rows of '{args.b}' in " + ", ".join(args.runs))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(sizes), figsize=(5.2 * len(sizes), 4.6), squeeze=False)
    for ax, res in zip(axes[0], sizes):
        seconds, xs, ys = [], [], []
        for (mesh, r, m), b in sorted(rows.items()):
            if r != res or m != args.b or (mesh, res, args.a) not in rows or \
                    (mesh, res, "mc") not in rows:
                continue
            a, mc = rows[(mesh, res, args.a)], rows[(mesh, res, "mc")]
            if not (a["L1"] > 1e-3 * mc["L1"] and b["L1"] > 1e-3 * mc["L1"]):
                continue  # an exact mesh (the cube) has no place on the scale
            x0, y0 = a["triangles"] / mc["triangles"], a["L1"] / mc["L1"]
            x1, y1 = b["triangles"] / mc["triangles"], b["L1"] / mc["L1"]
            ax.annotate("", xy=(x1, y1), xytext=(x0, y0),
                        arrowprops=dict(arrowstyle="->", color="tab:blue", lw=1))
            ax.plot([x0], [y0], "o", color="0.6", ms=3)
            ax.text(x1, y1, " " + mesh, fontsize=7, va="center")
            seconds.append(b["seconds"] / a["seconds"])
            xs += [x0, x1]
            ys += [y0, y1]
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("triangles / marching cubes'")
        ax.set_ylabel("L1 / marching cubes'")
        share = f"time {geomean(seconds):.2f}x" if seconds else ""
        ax.set_title(f"{res}³: {args.a} (grey) → {args.b} (arrow heads), {share}")
        ax.grid(True, which="both", alpha=0.3)
        if xs:
            ax.set_xlim(min(xs) / 1.15, max(xs) * 1.6)
            ax.set_ylim(min(ys) / 1.15, max(ys) * 1.15)
    if args.title:
        fig.suptitle(args.title)
    fig.tight_layout()
    fig.savefig(args.png, dpi=110)
    print(f"wrote {args.png}")


if __name__ == "__main__":
    main()

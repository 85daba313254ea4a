"""bench/two_builds.py's JSON lines drawn: each mesh's L1 of build B over build A's, one row of
points per grid size (log scale), so that a change's gains and losses show mesh by mesh.

    /usr/bin/python3 bench/two_builds_plot.py runs.jsonl [more.jsonl ...] --png docs/img/x.png
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import read_jsonl  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("runs", nargs="+", help="bench/two_builds.py JSON lines")
    ap.add_argument("--png", required=True)
    ap.add_argument("--title", default="L1 of build B over build A's, per shared mesh")
    args = ap.parse_args()
    rows = [r for path in args.runs for r in read_jsonl(path) if "a" in r and "b" in r]
    if not rows:
        sys.exit("no two_builds.py rows in " + ", ".join(args.runs))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    meshes = sorted({r["mesh"] for r in rows})
    sizes = sorted({r["res"] for r in rows})
    fig, ax = plt.subplots(figsize=(9, 4.2))
    for n, res in enumerate(sizes):
        x, y = [], []
        for r in rows:
            if r["res"] == res and r["a"]["L1"] > 0:
                x.append(meshes.index(r["mesh"]) + (n - (len(sizes) - 1) / 2) * 0.18)
                y.append(r["b"]["L1"] / r["a"]["L1"])
        ax.scatter(x, y, label=f"{res}³", s=22)
    ax.axhline(1, color="black", lw=0.8)
    ax.set_yscale("log")
    ax.set_xticks(range(len(meshes)))
    ax.set_xticklabels(meshes, rotation=45, ha="right")
    ax.set_ylabel("L1, B / A")
    ax.set_title(args.title)
    ax.grid(True, which="both", axis="y", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(args.png, dpi=110)


if __name__ == "__main__":
    main()

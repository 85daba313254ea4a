"""Draws what bench/adaptivity.py measures: per shared mesh, triangles against L1 (top figure)
and against the mean distance from points along its sharp edges (bottom figure, meshes with
sharp edges only), for our merges (--adaptivity TOL, the TOL-0 mesh marked), CGAL's
Garland-Heckbert decimation of the TOL-0 mesh and OpenVDB's adaptive mesher at the same counts.
One panel per mesh, both axes logarithmic; rows of several grids (e.g. 128 and 256) share a
panel with one line style per grid.

Usage: /usr/bin/python3 bench/adaptivity_plot.py docs/notes/results/adaptivity_128_session17.jsonl \
           docs/notes/results/adaptivity_256_session17.jsonl --png docs/img/adaptivity_l1.png \
           --edges-png docs/img/adaptivity_edges.png
"""
import argparse
import json
import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402

METHODS = [("adaptivity", "ours (--adaptivity)", "C0"), ("cgal-gh", "CGAL GH decimation", "C1"),
           ("openvdb", "OpenVDB adaptive", "C2")]
STYLES = ["-", "--", ":"]


def load(paths):
    """Rows keyed (mesh, res, method, tol); a later file's row replaces an earlier one's."""
    rows = {}
    for path in paths:
        for line in open(path):
            r = json.loads(line)
            rows[(r["mesh"], r["res"], r["method"], r["tol"])] = r
    return list(rows.values())


def draw(rows, key, ylabel, title, png):
    """One panel per mesh: `key` over the TOL-0 mesh's against triangles. The y range covers ours
    and GH's; OpenVDB's, far above on most meshes, runs off the top."""
    meshes = sorted({r["mesh"] for r in rows if r.get(key)})
    grids = sorted({r["res"] for r in rows})
    columns = min(6, len(meshes))
    lines = math.ceil(len(meshes) / columns)
    fig, axes = plt.subplots(lines, columns, figsize=(3.0 * columns, 2.6 * lines), squeeze=False)
    for ax, mesh in zip(axes.flat, meshes):
        shown = []
        for g, res in enumerate(grids):
            here = [r for r in rows if r["mesh"] == mesh and r["res"] == res and r.get(key)]
            zero = [r for r in here if r["method"] == "adaptivity" and r["tol"] == 0]
            if not zero:
                continue
            base = zero[0][key]
            for method, label, colour in METHODS:
                pts = [(r["triangles"], r[key] / base) for r in here if r["method"] == method]
                if method != "adaptivity":  # the peers start from our TOL-0 mesh
                    pts.append((zero[0]["triangles"], 1.0))
                pts.sort()
                if method != "openvdb":
                    shown += [y for _, y in pts]
                if pts:
                    ax.plot(*zip(*pts), STYLES[g % len(STYLES)], color=colour, marker=".",
                            label=f"{label}, {res}³")
            ax.plot(zero[0]["triangles"], 1.0, "ks", ms=4)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        if shown:
            ax.set_ylim(min(shown) / 1.15, max(shown) * 1.15)
        if shown and max(shown) / min(shown) < 100:  # ratios near 1: label the minor ticks too
            label = matplotlib.ticker.FuncFormatter(lambda y, _: f"{y:g}")
            ax.yaxis.set_major_formatter(label)
            ax.yaxis.set_minor_formatter(label)
        else:
            ax.yaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_title(mesh, fontsize=9)
        ax.tick_params(labelsize=7)
    for ax in list(axes.flat)[len(meshes):]:
        ax.axis("off")
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=min(6, len(labels)), fontsize=8)
    fig.suptitle(f"{title} (black square: TOL 0, the unmerged mesh)", fontsize=11)
    fig.supxlabel("triangles", fontsize=9, y=0.06)
    fig.supylabel(ylabel, fontsize=9)
    fig.tight_layout(rect=(0.01, 0.08, 1, 0.97))
    fig.savefig(png, dpi=110)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("jsonl", nargs="+")
    ap.add_argument("--png", required=True)
    ap.add_argument("--edges-png", default="")
    a = ap.parse_args()
    rows = load(a.jsonl)
    draw(rows, "L1", "L1 / TOL 0's L1", "Triangles against L1", a.png)
    if a.edges_png:
        draw(rows, "edge_h", "sharp-edge distance / TOL 0's",
             "Triangles against the distance from the sharp edges", a.edges_png)


if __name__ == "__main__":
    main()

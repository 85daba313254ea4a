"""Edge fans (`--edge-fans on`: a mesh that cannot cross itself, no repair stages) against the
default local reconstruction and marching cubes on the shared meshes (also on the grid of twice
the resolution that shows the thin parts, `--thin-parts on`): L1 and L-infinity over MC's,
triangles over MC's, crossings, closedness and time, one table per grid size, and each mesh's L1
against the default's.

    /usr/bin/python3 bench/edge_fans.py --res 32,64 \\
        --jsonl docs/results/edge_fans_32_64.jsonl --markdown docs/results/edge_fans_32_64.md

With --jsonl naming rows that exist (bench/local.py's), only the tables are made.
"""
import argparse
import json
import os
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import geomean  # noqa: E402

VARIANTS = ["--variant", "fans:--edge-fans on",
            "--variant", "fans-lattice-b4:--edge-fans on --gradient lattice --band 4",
            "--variant", "fans-finer:--edge-fans on --thin-parts on",
            "--variant", "fans-finer-lattice:--edge-fans on --thin-parts on --gradient lattice"]
METHODS = ["gcp-local", "fans", "fans-lattice-b4", "fans-finer", "fans-finer-lattice"]
LABELS = {"gcp-local": "default", "fans": "edge fans", "fans-lattice-b4":
          "edge fans, lattice gradients, band 4", "fans-finer": "edge fans on the finer grid",
          "fans-finer-lattice": "edge fans on the finer grid, lattice gradients"}


def tables(rows):
    lines = []
    for res in sorted({r["res"] for r in rows}):
        at = [r for r in rows if r["res"] == res and r.get("L1")]
        mc = {r["mesh"]: r for r in at if r["method"] == "mc"}
        default = {r["mesh"]: r for r in at if r["method"] == "gcp-local"}
        lines += [f"## {res}³ ({len(mc)} meshes)", "",
                  "| method | L1 / MC | L∞ / MC | meshes with L∞ above MC's | worst L1 / default's "
                  "| triangles / MC | crossing pairs | closed and 2-manifold | median seconds "
                  "(/ default's) |", "|---|---|---|---|---|---|---|---|---|"]
        base = np.median([default[m]["seconds"] for m in default])
        for method in METHODS:
            rs = [r for r in at if r["method"] == method and r["mesh"] in mc]
            if not rs:
                continue
            l1 = [r["L1"] / mc[r["mesh"]]["L1"] for r in rs]
            linf = [r["Linf"] / mc[r["mesh"]]["Linf"] for r in rs]
            tris = [r["triangles"] / mc[r["mesh"]]["triangles"] for r in rs]
            vs = [(r["L1"] / default[r["mesh"]]["L1"], r["mesh"]) for r in rs
                  if r["mesh"] in default]
            worst = max(vs) if vs else (float("nan"), "")
            secs = np.median([r["seconds"] for r in rs])
            lines.append(
                f"| {LABELS[method]} | {geomean(l1):.3f} | {geomean(linf):.3f} | "
                f"{sum(x > 1 for x in linf)} of {len(rs)} | {worst[0]:.2f} ({worst[1]}) | "
                f"{geomean(tris):.2f} ({min(tris):.2f}–{max(tris):.2f}) | "
                f"{sum(r['self_intersections'] for r in rs)} | "
                f"{sum(bool(r['closed'] and r['manifold']) for r in rs)} of {len(rs)} | "
                f"{secs:.2f} ({secs / base:.2f}) |")
        lines += ["", "| mesh | " + " | ".join(f"{LABELS[m]}: L1 / MC" for m in METHODS) +
                  " | " + " | ".join(f"{LABELS[m]}: triangles / MC" for m in METHODS) + " |",
                  "|---" * (2 * len(METHODS) + 1) + "|"]
        for name in sorted(mc):
            cells, tri = [], []
            for method in METHODS:
                r = next((x for x in at if x["mesh"] == name and x["method"] == method), None)
                cells.append(f"{r['L1'] / mc[name]['L1']:.3f}" if r else "–")
                tri.append(f"{r['triangles'] / mc[name]['triangles']:.2f}" if r else "–")
            lines.append(f"| {name} | " + " | ".join(cells) + " | " + " | ".join(tri) + " |")
        lines.append("")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", default="32,64")
    ap.add_argument("--meshes", default="")
    ap.add_argument("--jsonl", required=True)
    ap.add_argument("--markdown", default="")
    args = ap.parse_args()
    if not os.path.exists(args.jsonl):
        here = os.path.dirname(os.path.abspath(__file__))
        cmd = [sys.executable, os.path.join(here, "local.py"), "--res", args.res,
               "--methods", "mc,gcp-local", *VARIANTS]
        if args.meshes:
            cmd += ["--meshes", args.meshes]
        with open(args.jsonl, "w") as out:
            subprocess.run(cmd, stdout=out, check=True)
    rows = [json.loads(line) for line in open(args.jsonl)]
    text = tables(rows)
    if args.markdown:
        with open(args.markdown, "w") as f:
            f.write(text + "\n")
    print(text)


if __name__ == "__main__":
    main()

"""Adaptivity brick by brick (issue 39): the same local mesh merged with --adaptivity TOL in
bricks of B spacings (two passes, the second shifted by half a brick) against the whole mesh
merged as one brick in one sequential pass (--adaptivity-bricks 0), in the same run. Per mesh,
grid, TOL and B: triangles, L1 to the ground truth, the sharp-edge distance (in spacings),
self-intersections, and the adaptivity stage's seconds (--stats), each as a ratio to one
brick's. JSON lines on stdout; --markdown writes the table.

    /usr/bin/python3 bench/adaptivity_bricks.py --res 256 --tol 0.02,0.05 --bricks 0,32,64 \
        --meshes bunny,wingnut,spot --markdown docs/results/adaptivity_bricks.md
"""
import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from adaptivity import add_case_arguments, cases, evaluate  # noqa: E402
from common import CLI, geomean, keep, timed  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    add_case_arguments(ap, "0.02,0.05", "bunny,wingnut,spot")
    ap.add_argument("--bricks", default="0,32,64")
    a = ap.parse_args()
    rows = []
    for res, name, tol, prefix, gt, edges, h in cases(a):
        for bricks in map(int, a.bricks.split(",")):
            out = f"{prefix}_adapt{tol:g}_b{bricks}.ply"
            stats = out + ".json"
            seconds, peak, _, err = timed(
                [CLI, "contour", prefix + ".npy", "-o", out, "--quiet", "--reconstruction",
                 "local", "--adaptivity", str(tol), "--adaptivity-bricks", str(bricks),
                 "--stats", stats])
            if err:
                raise SystemExit(" ".join(err))
            with open(stats) as f:
                s = json.load(f)
            row = dict(mesh=name, res=res, tol=tol, bricks=bricks, seconds=seconds,
                       peak_mb=peak, adaptivity_seconds=s["seconds"]["adaptivity"],
                       freeze_rounds=s["adaptivity"]["freeze_rounds"],
                       **evaluate(out, gt, edges, h))
            keep(rows, row)
    return rows, a.markdown


def write_markdown(rows, path):
    lines = ["# Adaptivity brick by brick against one sequential pass", "",
             "`/usr/bin/python3 bench/adaptivity_bricks.py` (2 cores, same run): the local mesh "
             "merged with `--adaptivity TOL` in bricks of B spacings (two passes, the second "
             "shifted by half a brick; the bricks in parallel), against B = 0 (the whole mesh as "
             "one brick, one sequential pass). Ratios to B = 0's on the same mesh and TOL; edge: "
             "mean distance from points along the ground truth's sharp edges, in spacings; "
             "seconds: the adaptivity stage alone.", "",
             "| grid | mesh | TOL | B | triangles | / B 0 | L1 / B 0 | edge (h) | crossings | "
             "seconds | / B 0 |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    ratios = {}
    for r in rows:
        base = next(x for x in rows if x["mesh"] == r["mesh"] and x["res"] == r["res"] and
                    x["tol"] == r["tol"] and x["bricks"] == 0)
        t, l1, s = (r["triangles"] / base["triangles"], r["L1"] / base["L1"],
                    r["adaptivity_seconds"] / base["adaptivity_seconds"])
        if r["bricks"]:
            ratios.setdefault((r["res"], r["tol"], r["bricks"]), []).append((t, l1, s))
        edge = f"{r['edge_h']:.3f}" if r.get("edge_h") is not None else "–"
        lines.append(f"| {r['res']}³ | {r['mesh']} | {r['tol']:g} | {r['bricks']} | "
                     f"{r['triangles']:,} | {t:.3f} | {l1:.3f} | {edge} | "
                     f"{r['self_intersections']} | {r['adaptivity_seconds']:.1f} | {s:.2f} |")
    lines += ["", "| grid | TOL | B | geometric mean: triangles / B 0 | L1 / B 0 | seconds / B 0 |",
              "|---|---|---|---|---|---|"]
    for (res, tol, bricks), v in sorted(ratios.items()):
        lines.append(f"| {res}³ | {tol:g} | {bricks} | {geomean([x[0] for x in v]):.3f} | "
                     f"{geomean([x[1] for x in v]):.3f} | {geomean([x[2] for x in v]):.2f} |")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    measured, markdown = main()
    if markdown:
        write_markdown(measured, markdown)

"""Issue 64's targets in one table: each target, what the runs given measured, met or missed and by
how much. It reads runs made by other benchmarks (no measuring of its own):

- accuracy, triangles, sharp edges, closedness and crossings: bench/local.py's JSON lines at
  32^3-256^3 (`--accuracy FILE[:LABEL[:GRIDS]]`: the default's rows under LABEL, `def` unless
  given, on the grids listed, all unless given, with marching cubes from the same file), against
  the default the issue was filed against (bench/issue64_accuracy.py's baseline);
- speed: bench/builds_vs_skimage.py's JSON lines (`--speed`; build B's time over scikit-image's,
  geometric means over the grids of each size);
- facts measured apart (`--fact NAME=TEXT`, repeated): `rss1024` (peak RSS at 1024^3, in GB, then
  where it comes from), `threads` (the speed-up from 1 to 2 threads, then where from).

    /usr/bin/python3 bench/issue64_targets.py --accuracy docs/results/accuracy_s56.jsonl \\
        --accuracy docs/results/one_level_64_s57.jsonl:s1a:64 \\
        --speed docs/results/speed_s59.jsonl \\
        --fact rss1024="0.99 bunny, session 58" --fact threads="1.91 bunny 64^3, session 51" \\
        --out docs/issue64_targets.md

Where two accuracy sources hold the same mesh and grid, the later one counts (a run that changed
the default at one size goes last).
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import geomean, read_jsonl, report  # noqa: E402
from issue64_accuracy import BASELINE, filing_summary, runs_at  # noqa: E402

SPEED = {64: 20.0, 256: 5.0, 512: 3.0}  # issue 64's, 2 cores, over scikit-image's


def verdict(met):
    return "**met**" if met else "**missed**"


def read_accuracy(sources):
    """{(mesh, res, "def" or "mc"): row} from FILE[:LABEL[:GRIDS]] sources, later ones first."""
    now = {}
    for source in sources:
        path, label, grids = (source.split(":") + ["def", ""])[:3]
        wanted = {int(g) for g in grids.split(",") if g}
        for r in read_jsonl(path):
            if "method" not in r or (wanted and r["res"] not in wanted):
                continue
            if r["method"] in (label, "mc"):
                now[(r["mesh"], r["res"], "def" if r["method"] == label else "mc")] = r
    return now


def accuracy_rows(now, base):
    """The accuracy targets' rows: per grid the L1 over the filing's, then L-infinity, sharp
    edges, triangles and soundness over all grids."""
    rows = []
    linf_over, tri_ratio, unsound, sharp_worse, sharp_count = [], {}, [], [], 0
    for res in sorted({k[1] for k in now if k[2] == "def"}):
        ratios = {}
        for mesh, r, mc, b in runs_at(now, base, "def", res):
            tri_ratio.setdefault(res, {})[mesh] = r["triangles"] / mc["triangles"]
            if not (r.get("closed") and r.get("manifold") and r.get("self_intersections") == 0):
                unsound.append(f"{mesh} {res}³")
            if res >= 64 and r["Linf"] > mc["Linf"]:
                linf_over.append(f"{mesh} {res}³ {r['Linf'] / mc['Linf']:.3f}×")
            if not b:
                continue
            ratios[mesh] = r["L1"] / b["L1"]
            if res == 64 and b.get("edge_distance_h", 0) > 0:
                sharp_count += 1
                if r["edge_distance_h"] > b["edge_distance_h"]:
                    sharp_worse.append(f"{mesh} {r['edge_distance_h'] / b['edge_distance_h']:.3f}×")
        if not ratios:
            continue
        mean, without_cube, worst, over = filing_summary(ratios)
        rows.append((f"{res}³: geometric mean of L1 over the filing's ≤ 1.05 ({len(ratios)} meshes)",
                     f"{mean:.3f} (without the cube {without_cube:.3f})", verdict(mean <= 1.05),
                     ""))
        rows.append((f"{res}³: no mesh more than 10% worse than the filing's",
                     f"worst {worst} {ratios[worst]:.3f}×", verdict(not over),
                     ", ".join(f"{o}×" for o in over)))
    if sharp_count:
        rows.append(("64³: sharp-edge distances no worse than the filing's, per mesh",
                     f"{sharp_count - len(sharp_worse)} of {sharp_count} no worse",
                     verdict(not sharp_worse), ", ".join(sharp_worse)))
    rows.append(("L∞ no worse than MC's on any mesh, 64³ and up",
                 f"{len(linf_over)} above", verdict(not linf_over), ", ".join(linf_over)))
    for res in sorted(tri_ratio):
        t = tri_ratio[res]
        worst = max(t, key=t.get)
        rows.append((f"{res}³: at most 3× MC's triangles",
                     f"geometric mean {geomean(list(t.values())):.2f}×, most {worst} "
                     f"{t[worst]:.2f}×", verdict(max(t.values()) <= 3), ""))
    rows.append(("closed, 2-manifold, no self-intersections on every mesh and grid",
                 f"{sum(len(t) for t in tri_ratio.values()) - len(unsound)} of "
                 f"{sum(len(t) for t in tri_ratio.values())} runs", verdict(not unsound),
                 ", ".join(unsound)))
    return rows


def speed_rows(speed):
    rows = []
    for res in sorted({r["res"] for r in speed}):
        ratios = [r["B/sk"] for r in speed if r["res"] == res]
        g = geomean(ratios)
        target = SPEED.get(res)
        grids = ", ".join(f"{r['grid'].split('_')[0]} {r['B/sk']:.1f}×" for r in speed
                          if r["res"] == res)
        name = (f"{res}³ on 2 cores: ≤ {target:g}× scikit-image's" if target
                else f"{res}³ on 2 cores (no target)")
        why = f"{g / target:.1f}× the target" if target and g > target else ""
        rows.append((name, f"{g:.1f}× ({grids})", verdict(g <= target) if target else "",
                     why))
    return rows


def fact_row(facts, name, label, limit, above_is_met):
    if name not in facts:
        return (label, "not measured", "", "")
    text = facts[name]
    value = float(text.split()[0])
    met = value >= limit if above_is_met else value <= limit
    return (label, text, verdict(met), "")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--accuracy", action="append", default=[], metavar="FILE[:LABEL[:GRIDS]]",
                    help="bench/local.py JSON lines")
    ap.add_argument("--speed", action="append", default=[],
                    help="bench/builds_vs_skimage.py JSON lines (build B)")
    ap.add_argument("--fact", action="append", default=[], metavar="NAME=TEXT")
    ap.add_argument("--baseline", default=BASELINE)
    ap.add_argument("--out")
    args = ap.parse_args()
    facts = dict(f.split("=", 1) for f in args.fact)
    base = {(r["mesh"], r["res"], r["method"]): r
            for r in read_jsonl(args.baseline) if "method" in r}
    now = read_accuracy(args.accuracy)
    speed = [r for path in args.speed for r in read_jsonl(path)]
    rows = speed_rows(speed)
    rows.append(fact_row(facts, "rss1024", "peak RSS at 1024³ ≤ 2.5 GB (GB)", 2.5, False))
    rows.append(fact_row(facts, "threads", "from 1 to 2 threads ≥ 1.9×", 1.9, True))
    rows.append(("16 cores: 256³ ≤ 1.5×, 1024³ ≤ 1× scikit-image's", "not measured", "",
                 "no 16-core machine was lent"))
    rows += accuracy_rows(now, base)
    rows.append(("every sample on its own side", "not in these runs", "",
                 "bench/wrong_side.py measures it; the fans hold it by construction "
                 "(EdgeFans.AdversarialFieldsNeitherCrossNorLeaveASampleOnTheWrongSide)"))
    rows.append(("the same bytes for any thread count, brick size and on Dask", "tests", "**met**",
                 "LocalBrick.BricksEqualOneBrickBitForBit, LocalBrick.BricksOf8And16EqualOneBrick"
                 "WithTheDefaults, NearestTriangles.TheSameAnswerForAnyThreadCount, "
                 "tests/python/test_dask.py"))
    sources = ", ".join(os.path.basename(p) for p in args.speed + args.accuracy)
    lines = [f"Issue 64's targets (`bench/issue64_targets.py`; runs: {sources}).", "",
             "| target | measured | verdict | where missed, or what shows it |", "|---|---|---|---|"]
    lines += [f"| {a} | {b} | {c} | {d} |" for a, b, c, d in rows]
    report("\n".join(lines) + "\n", args.out)


if __name__ == "__main__":
    sys.exit(main())

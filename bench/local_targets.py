"""Issue 35's benchmark in one command: GCP's local reconstruction against its targets. Runs the
benchmarks that measure them (with --run; about 1.5 hours on 2 cores) into a results folder, then
writes one page (docs/local_targets.md) with every target, what was measured, met or missed, by
how much, and why where missed. Without --run the page is written again from the results there.

    /usr/bin/python3 bench/local_targets.py --run --results docs/results/targets \\
        --out docs/local_targets.md

What each results file holds, and the command --run gives it:
    accuracy.jsonl  bench/local.py --res 16,32,64,128 (exact grids) and --res 256 (grids truncated
                    at 8 spacings), methods mc, mt-rt, gcp-poisson, gcp-local: L1, L-inf,
                    sharp-edge distance, closed / manifold / self-intersections
    vdb.jsonl       bench/local.py --res 64,128, the grid as a .vdb level set (half width 3)
    smooth.jsonl    bench/smooth_shapes.py --res 64,256 (the built-in sphere and torus)
    neural.jsonl    bench/neural.py --res 64,128 (the MLP fixture, as a callable and as a grid)
    scale.jsonl     bench/scale.py --res 64,128,256,512 --meshes bunny (gcp, mc, skimage)
(with the sdfcontour package importable for smooth_shapes and neural: installed, or on PYTHONPATH)
"""
import argparse
import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from common import geomean, read_jsonl as read_lines  # noqa: E402

SHARP = ("cube", "wingnut", "hammer", "sword", "boot")  # the sharp meshes


def read_jsonl(path):
    return read_lines(path) if os.path.exists(path) else []


def run_all(results):
    """The benchmarks, each into its file in `results`."""
    os.makedirs(results, exist_ok=True)
    py = sys.executable

    def to(name, args, cwd=None):
        with open(os.path.join(results, name), "a") as out:
            subprocess.run([py, *args], stdout=out, check=True, cwd=cwd)

    methods = "mc,mt-rt,gcp-poisson,gcp-local"
    to("accuracy.jsonl", [os.path.join(HERE, "local.py"), "--res", "16,32,64,128",
                          "--methods", methods])
    to("accuracy.jsonl", [os.path.join(HERE, "local.py"), "--res", "256", "--methods", methods,
                          "--truncate", "8"])
    to("vdb.jsonl", [os.path.join(HERE, "local.py"), "--res", "64,128",
                     "--methods", "mc,gcp-local-vdb,gcp-poisson-vdb"])
    to("smooth.jsonl", [os.path.join(HERE, "smooth_shapes.py"), "--res", "64,256"])
    to("neural.jsonl", ["neural.py", "--res", "64,128"], cwd=HERE)
    to("scale.jsonl", [os.path.join(HERE, "scale.py"), "--res", "64,128,256,512", "--meshes",
                       "bunny", "--methods", "gcp,mc,skimage", "--vdb-res", "",
                       "--out", os.path.join(results, "scale.md")])


def ratios(rows, method, res, key="L1"):
    """{mesh: L1 / MC's L1} (or another distance `key`) of `method` at `res` (the last row of
    each mesh wins)."""
    mc = {r["mesh"]: r.get(key) for r in rows if r["res"] == res and r.get("method") == "mc"}
    out = {}
    for r in rows:
        if r["res"] == res and r.get("method") == method and r.get(key) and mc.get(r["mesh"]):
            out[r["mesh"]] = r[key] / mc[r["mesh"]]
    return out


def verdict(ok):
    return "**met**" if ok else "**missed**"


def accuracy_rows(acc):
    lines = []
    for res, goal in ((32, 0.25), (64, 0.25), (128, 0.30), (256, 0.30)):
        local = ratios(acc, "gcp-local", res)
        if not local:
            continue
        mean = geomean(list(local.values()))
        no_cube = geomean([v for m, v in local.items() if m != "cube"])
        mtrt = geomean(list(ratios(acc, "mt-rt", res).values()) or [float("nan")])
        poisson = geomean(list(ratios(acc, "gcp-poisson", res).values()) or [float("nan")])
        worst = max(local, key=local.get)
        lines.append(f"| L1 ≤ {goal:.2f}x MC's at {res}³ (geometric mean, {len(local)} meshes) | "
                     f"{mean:.3f}x ({no_cube:.3f}x without the exact cube); MT-RT {mtrt:.3f}x, "
                     f"GCP-Poisson {poisson:.3f}x | {verdict(mean <= goal)} | |")
        why = ("" if local[worst] <= 0.6 else
               "the boot's facets, tread and seams are smaller than a spacing: 39% of its area "
               "lies within 0.75 h of a turn of more than 60°, where its error is 0.10 h (MC "
               "0.16 h) against 0.003 h on its flat parts; no option tried brought it under 0.6x "
               "(docs/notes/local.md, sessions 20 and 23)")
        lines.append(f"| no mesh worse than 0.6x MC's at {res}³ | worst: {worst} "
                     f"{local[worst]:.3f}x | {verdict(local[worst] <= 0.6)} | {why} |")
    return lines


def coarse_rows(acc):
    local = ratios(acc, "gcp-local", 16)
    if not local:
        return []
    fallback = [r["mesh"] for r in acc if r["res"] == 16 and r.get("method") == "gcp-local" and
                r.get("error")]
    mean = geomean(list(local.values()))
    return [f"| 16³: no whole-mesh fallback, geometric mean ≤ 0.45x MC's | {mean:.3f}x over "
            f"{len(local)} meshes; failed runs: {', '.join(fallback) or 'none'} (a whole-mesh "
            f"fallback would return MC's mesh: 1.000x) | {verdict(mean <= 0.45 and not fallback)} "
            f"| |"]


def topology_rows(acc):
    bad = [f"{r['mesh']} {r['res']}³" for r in acc if r.get("method") == "gcp-local" and
           r.get("L1") and not (r.get("closed") and r.get("manifold") and
                                r.get("self_intersections") == 0)]
    runs = sum(1 for r in acc if r.get("method") == "gcp-local" and r.get("L1"))
    return [f"| closed, 2-manifold, no self-intersection on every shared mesh and grid | "
            f"{runs - len(bad)} of {runs} runs; not: {', '.join(bad) or 'none'} | "
            f"{verdict(not bad)} | |"]


def edge_rows(acc):
    at = {r["mesh"]: r.get("edge_distance_h") for r in acc
          if r["res"] == 64 and r.get("method") == "gcp-local" and r["mesh"] in SHARP}
    mc = {r["mesh"]: r.get("edge_distance_h") for r in acc
          if r["res"] == 64 and r.get("method") == "mc" and r["mesh"] in SHARP}
    if not at:
        return []
    text = ", ".join(f"{m} {at[m]:.3f} h (MC {mc.get(m, float('nan')):.3f})" for m in SHARP
                     if at.get(m) is not None)
    ok = all(v is not None and v <= 0.05 for v in at.values())
    why = ("" if ok else "the edges missed lie on facets smaller than a spacing (937 of the "
           "hammer's 949 edge points on mesh edges shorter than h/2; the sword's blade is "
           "thinner than a spacing): no contact point lands on them, the nearest 0.3-0.4 h away "
           "(docs/notes/local.md, session 10)")
    return [f"| sharp edges ≤ 0.05 h at 64³ | {text} | {verdict(ok)} | {why} |"]


def smooth_rows(smooth):
    lines = []
    for shape in ("sphere", "torus"):
        for res in (64, 256):
            by = {r["method"]: r for r in smooth if r["shape"] == shape and r["res"] == res}
            local, poisson = by.get("gcp-local"), by.get("gcp-poisson")
            if not local or not poisson:
                continue
            ok = local["l1_h"] <= poisson["l1_h"] and local["triangles"] <= poisson["triangles"]
            lines.append(f"| smooth {shape} {res}³: local's L1 ≤ Poisson's, triangles ≤ | "
                         f"{local['l1_h']:.2e} h with {local['triangles']:,} triangles against "
                         f"{poisson['l1_h']:.2e} h with {poisson['triangles']:,} (MC "
                         f"{by['mc']['l1_h']:.2e} h) | {verdict(ok)} | |")
    return lines


def neural_rows(neural):
    lines = []
    for res in (64, 128):
        by = {r["variant"]: r for r in neural if r.get("res") == res}
        local, mc = by.get("gcp-local"), by.get("mc")
        if not local or not mc:
            continue
        ratio = mc["L1"] / local["L1"]
        ok = not local.get("fallback") and ratio >= 2
        lines.append(f"| neural SDF {res}³: no fallback, ≥ 2x closer than MC to its zero set | "
                     f"{ratio:.1f}x closer (L1 {local['L1']:.2e} against {mc['L1']:.2e}), "
                     f"fallback: {local.get('fallback') or 'none'} | {verdict(ok)} | |")
    return lines


def cost_rows(scale):
    by = {(r["res"], r["method"]): r for r in scale if "res" in r and "method" in r}
    lines = []
    for res in (64, 128, 256, 512):
        gcp, sk = by.get((res, "gcp")), by.get((res, "skimage"))
        if not gcp or not sk or not gcp.get("seconds") or not sk.get("seconds"):
            continue
        ratio = gcp["seconds"] / sk["seconds"]
        target = res == 256
        why = ("the band's regular triangulation alone (CGAL, 2 M weighted samples at band 8) "
               "takes 62x scikit-image's time at 256³ (28x with --band 3), and CGAL runs as fast "
               "on random points: no reconstruction of GCP's contact points reaches 5x on 2 "
               "cores (docs/notes/local.md, session 22)") if target and ratio > 5 else ""
        goal = "≤ 5x scikit-image on 2 cores" if target else "(cost)"
        lines.append(f"| bunny {res}³ {goal} | {gcp['seconds']:.1f} s = {ratio:.0f}x "
                     f"scikit-image's {sk['seconds']:.2f} s; peak {gcp.get('rss_mb', 0):.0f} MB "
                     f"| {verdict(ratio <= 5) if target else ''} | {why} |")
    return lines


def write_page(results, out):
    acc = read_jsonl(os.path.join(results, "accuracy.jsonl"))
    repo = os.path.join(HERE, "..")
    link = os.path.relpath(results, os.path.dirname(os.path.abspath(out)))
    lines = ["# Issue 35's targets, measured", "",
             "`/usr/bin/python3 bench/local_targets.py --results " +
             os.path.relpath(results, repo) + "` (bench/local_targets.py; `--run` measures "
             "again). GCP's local reconstruction (`gcp-local`, the default on grids) against "
             "marching cubes (MC) on the 17 shared meshes; ratios are of L1 to MC's on the same "
             f"grid. The results, and which run made each: [{link}]({link}).", "",
             "| target | measured | verdict | why, where missed |", "|---|---|---|---|"]
    lines += accuracy_rows(acc)
    lines += coarse_rows(acc)
    lines += topology_rows(acc)
    lines += edge_rows(acc)
    lines += smooth_rows(read_jsonl(os.path.join(results, "smooth.jsonl")))
    lines += neural_rows(read_jsonl(os.path.join(results, "neural.jsonl")))
    lines += cost_rows(read_jsonl(os.path.join(results, "scale.jsonl")))
    lines += ["| ≤ 2x scikit-image at 256³ and ≤ 1x at 1024³ on 16 cores | not measured: no "
              "16-core machine was lent in sessions 12-23 (session 11's: 18.9x at 256³, 5.2x "
              "at 1024³); on 2 cores 1 -> 2 threads is 1.84x at 256³, the same mesh "
              "(session 22) | **missed** (not measured) | no device |",
              "| peak RSS at 1024³ ≤ 4 GB | 3.49 GB on 2 cores (bunny, session 12); not measured "
              "on 16 threads | met on 2 cores | |",
              "| byte-identical for 1 and 2 threads, bricked and unbricked | tests "
              "`LocalBrick.BricksEqualOneBrickBitForBit`, `LocalBrick.GridReadBlockByBlockEquals"
              "TheGridInMemory`, tests/python/test_dask.py (Dask bricks equal one process) | "
              "**met** | |", ""]
    lines += pictures(out)
    lines += per_mesh_tables(acc)
    lines += vdb_table(read_jsonl(os.path.join(results, "vdb.jsonl")))
    with open(out, "w") as f:
        f.write("\n".join(lines) + "\n")


# The figures that go with the targets (made by the scripts named), where they exist.
FIGURES = (
    ("local_renders.png", "One CAD and one organic mesh at 32³: MC, GCP-Poisson, GCP-local "
     "(bench/local_renders.py)"),
    ("thin_part_renders.png", "Parts thinner than a spacing at 256³ (bench/local_renders.py "
     "--thin-parts)"),
    ("sharp_edges_hammer64.png", "The hammer's sharp-edge points at 64³ by their distance to MC's "
     "and GCP-local's meshes (bench/sharp_edges.py)"),
    ("scale_session22.png", "Time against scikit-image, 64³ to 512³ (bench/scale_plot.py)"),
)


def pictures(out):
    img = os.path.join(os.path.dirname(os.path.abspath(out)), "img")
    lines = ["## Pictures", ""]
    for name, caption in FIGURES:
        if os.path.exists(os.path.join(img, name)):
            lines += [f"![{caption}](img/{name})", "", f"*{caption}*", ""]
    return lines if len(lines) > 2 else []


def per_mesh_tables(acc):
    """Per mesh and grid: L1 / MC's of each method, and local's sharp-edge distance."""
    methods = ("mt-rt", "gcp-poisson", "gcp-local")
    lines = ["## Per mesh (L1 over MC's; the last row: L∞ over MC's)", ""]
    for res in sorted({r["res"] for r in acc}):
        table = {m: ratios(acc, m, res) for m in methods}
        meshes = sorted(set().union(*[set(t) for t in table.values()]))
        if not meshes:
            continue
        lines += [f"### {res}³", "", "| mesh | " + " | ".join(methods) + " |",
                  "|---" * (len(methods) + 1) + "|"]
        for mesh in meshes:
            lines.append(f"| {mesh} | " + " | ".join(
                f"{table[m][mesh]:.3f}" if mesh in table[m] else "–" for m in methods) + " |")
        lines.append("| **geometric mean** | " + " | ".join(
            f"**{geomean(list(table[m].values())):.3f}**" if table[m] else "–"
            for m in methods) + " |")
        linf = {m: ratios(acc, m, res, "Linf") for m in methods}
        lines.append("| L∞ over MC's, geometric mean | " + " | ".join(
            f"{geomean(list(linf[m].values())):.3f}" if linf[m] else "–" for m in methods) + " |")
        lines.append("")
    return lines


def vdb_table(vdb):
    if not vdb:
        return []
    lines = ["## OpenVDB level sets (half width 3): local, read box by box, against Poisson", "",
             "| mesh | grid | local L1 / MC | Poisson L1 / MC | local s | Poisson s |",
             "|---|---|---|---|---|---|"]
    for res in sorted({r["res"] for r in vdb}):
        local, poisson = ratios(vdb, "gcp-local-vdb", res), ratios(vdb, "gcp-poisson-vdb", res)
        secs = {(r["mesh"], r.get("method")): r.get("seconds") for r in vdb if r["res"] == res}
        for mesh in sorted(local):
            lines.append(f"| {mesh} | {res}³ | {local[mesh]:.3f} | {poisson.get(mesh, np.nan):.3f}"
                         f" | {secs.get((mesh, 'gcp-local-vdb'), np.nan):.1f}"
                         f" | {secs.get((mesh, 'gcp-poisson-vdb'), np.nan):.1f} |")
        lines.append(f"| **geometric mean** | {res}³ | **{geomean(list(local.values())):.3f}** | "
                     f"**{geomean(list(poisson.values())):.3f}** | | |")
    lines.append("")
    return lines


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--results", default=os.path.join(HERE, "..", "docs", "results", "targets"))
    ap.add_argument("--out", default=os.path.join(HERE, "..", "docs", "local_targets.md"))
    ap.add_argument("--run", action="store_true", help="measure first (about 1.5 hours)")
    args = ap.parse_args()
    if args.run:
        run_all(args.results)
    write_page(args.results, args.out)


if __name__ == "__main__":
    main()

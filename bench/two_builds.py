"""Two builds of `sdfcontour` on the shared meshes' grids, with the same options: each one's L1
and L-infinity (`sdfcontour eval` against the mesh), triangles and wall seconds, and marching
cubes' (from the first build) for scale. One table per grid size: B over A, per mesh and as
geometric means. The grids are bench/local.py's (sampled there if missing).

    /usr/bin/python3 bench/two_builds.py old/sdfcontour build/sdfcontour --res 32,64 \\
        --markdown docs/results/no_uniform_level_32_64.md

A run time from here shares the machine with nothing else but is one run: for speed, use
bench/binaries_pairs.py.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import MESHES, evaluate, geomean, mesh_names, report, timed  # noqa: E402


def run(cli, grid, gt, out, options):
    seconds, _, _, err = timed([cli, "contour", grid, "-o", out, "--quiet", *options])
    if err is not None:
        return {"error": " ".join(err)}
    e = evaluate(cli, out, gt)
    if e is None:
        return {"error": f"eval of {out} failed"}
    return {"L1": e["L1"], "Linf": e["L_inf"], "triangles": e["recon_mesh"]["triangles"],
            "crossings": e["recon_mesh"]["self_intersections"], "seconds": seconds}


def table(res, rows):
    lines = [f"## {res}³", "", "| mesh | L1 B/A | L∞ B/A | triangles B/A | seconds B/A | "
             "triangles / MC (A, B) | L1 / MC (A, B) | crossing pairs (B) |",
             "|---|---|---|---|---|---|---|---|"]
    ratios = {k: [] for k in ("l1", "linf", "tri", "sec", "tri_a", "tri_b", "mc_a", "mc_b")}
    for mesh, (mc, a, b) in sorted(rows.items()):
        if "L1" not in a or "L1" not in b or "L1" not in mc:
            lines.append(f"| {mesh} | failed: {a.get('error', '')} {b.get('error', '')} |")
            continue
        r = {"l1": b["L1"] / a["L1"], "linf": b["Linf"] / a["Linf"],
             "tri": b["triangles"] / a["triangles"], "sec": b["seconds"] / a["seconds"],
             "tri_a": a["triangles"] / mc["triangles"], "tri_b": b["triangles"] / mc["triangles"],
             "mc_a": a["L1"] / mc["L1"], "mc_b": b["L1"] / mc["L1"]}
        for k, v in r.items():
            ratios[k].append(v)
        lines.append(f"| {mesh} | {r['l1']:.3f} | {r['linf']:.3f} | {r['tri']:.2f} | "
                     f"{r['sec']:.2f} | {r['tri_a']:.1f}, {r['tri_b']:.1f} | "
                     f"{r['mc_a']:.3f}, {r['mc_b']:.3f} | {b['crossings']} |")
    g = {k: geomean(v) for k, v in ratios.items()}
    worst = max(ratios["l1"]) if ratios["l1"] else float("nan")
    lines.append(f"| **geometric mean** (worst L1 B/A {worst:.3f}) | **{g['l1']:.3f}** | "
                 f"{g['linf']:.3f} | **{g['tri']:.2f}** | {g['sec']:.2f} | "
                 f"{g['tri_a']:.1f}, {g['tri_b']:.1f} | {g['mc_a']:.3f}, {g['mc_b']:.3f} | |")
    return lines + [""]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("a", help="the first build's CLI (A)")
    ap.add_argument("b", help="the second build's CLI (B)")
    ap.add_argument("--res", default="32,64")
    ap.add_argument("--meshes", default="", help="comma-separated names (default: all shared)")
    ap.add_argument("--options", default="", help="contour options for both builds")
    ap.add_argument("--work", default=os.path.join(tempfile.gettempdir(), "sdfcontour-local"))
    ap.add_argument("--markdown", default="")
    args = ap.parse_args()
    if not os.path.isdir(MESHES):
        sys.exit(f"no shared meshes at {MESHES}")
    names = mesh_names(args.meshes)
    options = args.options.split()
    os.makedirs(args.work, exist_ok=True)
    lines = [f"# Two builds on the shared meshes: A `{args.a}`, B `{args.b}`", "",
             f"`/usr/bin/python3 bench/two_builds.py A B --res {args.res}"
             + (f" --options '{args.options}'" if options else "") + "` (bench/two_builds.py), "
             "2 cores, one run each; L1 and L∞ from `sdfcontour eval` against the mesh.", ""]
    for res in [int(r) for r in args.res.split(",")]:
        rows = {}
        for name in names:
            prefix = os.path.join(args.work, f"{name}{res}")
            if not os.path.exists(prefix + ".npy"):
                subprocess.run([args.a, "sample", os.path.join(MESHES, name + ".obj"), "--res",
                                str(res), "-o", prefix, "--quiet"], capture_output=True)
            if not os.path.exists(prefix + ".npy"):
                continue
            grid, gt = prefix + ".npy", prefix + "_mesh.ply"
            out = os.path.join(args.work, f"{name}{res}_two_builds.ply")
            mc = run(args.a, grid, gt, out, ["--method", "mc"])
            a, b = run(args.a, grid, gt, out, options), run(args.b, grid, gt, out, options)
            rows[name] = (mc, a, b)
            print(json.dumps({"mesh": name, "res": res, "mc": mc, "a": a, "b": b}), flush=True)
        lines += table(res, rows)
    report("\n".join(lines), args.markdown)


if __name__ == "__main__":
    main()

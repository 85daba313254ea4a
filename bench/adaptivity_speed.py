"""What `--adaptivity TOL` costs and buys on the default local reconstruction: triangles over
marching cubes', L1 over the unmerged mesh's and over MC's, the whole run's seconds over the
unmerged run's, and the merging's own seconds (`--stats`), on the same grids as bench/scale.py
(exact at <= 128^3, truncated at 8 spacings above, float32).

With --before CLI (an earlier build) the merged runs are repeated with it, for the speed-up of the
merging and the change in triangles and L1.

Usage: /usr/bin/python3 bench/adaptivity_speed.py [--res 64,128,256] [--meshes bunny,spot,armadillo]
       [--tolerances 0.005,0.01] [--before OLD_CLI] [--work /tmp/sdfcontour_scale] [--out FILE]
"""
import argparse
import json
import os
import subprocess
import sys

from common import CLI, geomean, l1, report, scale_grid


def run(cli, grid, out, stats, *options):
    """One `contour` run with --stats: (total seconds, adaptivity seconds, triangles)."""
    subprocess.run([cli, "contour", grid, "-o", out, "--quiet", "--stats", stats, *options], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(stats) as f:
        d = json.load(f)
    return d["seconds_total"], d["seconds"].get("adaptivity", 0.0), d["mesh"]["triangles"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", default=CLI)
    ap.add_argument("--before", default=None, help="an earlier build's CLI, for the merging's speed-up")
    ap.add_argument("--res", default="64,128,256")
    ap.add_argument("--meshes", default="bunny,spot,armadillo")
    ap.add_argument("--tolerances", default="0.005,0.01")
    ap.add_argument("--work", default="/tmp/sdfcontour_scale")
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    tolerances = args.tolerances.split(",")
    rows = []
    for res in map(int, args.res.split(",")):
        for name in args.meshes.split(","):
            try:
                prefix = scale_grid(args.cli, args.work, name, res)
            except subprocess.CalledProcessError:
                # (A mesh thinner than a spacing everywhere has no inside sample: the sword at 32^3.)
                print(f"{name} at {res}^3: could not be sampled (see `sdfcontour sample`); left out",
                      file=sys.stderr)
                continue
            grid, gt = prefix + ".npy", prefix + "_mesh.ply"
            out, stats = os.path.join(args.work, "out_adapt.ply"), os.path.join(args.work, "out_adapt.json")
            _, _, mc_triangles = run(args.cli, grid, out, stats, "--method", "mc")
            mc_l1 = l1(args.cli, out, gt)
            base_s, _, base_triangles = run(args.cli, grid, out, stats)
            base_l1 = l1(args.cli, out, gt)
            for tol in tolerances:
                s, merge_s, triangles = run(args.cli, grid, out, stats, "--adaptivity", tol)
                row = dict(mesh=name, res=res, tol=float(tol), triangles_over_mc=triangles / mc_triangles,
                           default_triangles_over_mc=base_triangles / mc_triangles,
                           l1_over_default=l1(args.cli, out, gt) / base_l1, l1_over_mc=None,
                           time_over_default=s / base_s, adaptivity_s=merge_s, default_s=base_s)
                row["l1_over_mc"] = row["l1_over_default"] * base_l1 / mc_l1
                if args.before:
                    s0, merge0, triangles0 = run(args.before, grid, out, stats, "--adaptivity", tol)
                    row.update(before_adaptivity_s=merge0, before_triangles_over_mc=triangles0 / mc_triangles,
                               before_l1_over_default=l1(args.cli, out, gt) / base_l1)
                rows.append(row)
                print(json.dumps(row), flush=True)

    text = ["# Adaptivity: what it costs and buys on the default mesh", "",
            f"`/usr/bin/python3 bench/adaptivity_speed.py --res {args.res} --meshes {args.meshes} "
            f"--tolerances {args.tolerances}{' --before OLD' if args.before else ''}` on 2 cores. "
            "Ratios per grid are geometric means over the meshes; the default's own triangles over "
            "marching cubes' are in the first row of each grid.", "",
            "| grid | TOL | triangles / MC | L1 / default's | L1 / MC's | time / default's | merging (s, mean) |"
            + (" merging before (s, mean) | triangles / MC before | L1 / default's before |" if args.before else ""),
            "|---|---|---|---|---|---|---|" + ("---|---|---|" if args.before else "")]
    for res in map(int, args.res.split(",")):
        here = [r for r in rows if r["res"] == res]
        text.append(f"| {res}³ | 0 (default) | {geomean([r['default_triangles_over_mc'] for r in here]):.2f} | 1 | "
                    f"{geomean([r['l1_over_mc'] / r['l1_over_default'] for r in here]):.3f} | 1 | 0 |"
                    + (" | | |" if args.before else ""))
        for tol in map(float, tolerances):
            sel = [r for r in here if r["tol"] == tol]
            line = (f"| {res}³ | {tol:g} | {geomean([r['triangles_over_mc'] for r in sel]):.2f} | "
                    f"{geomean([r['l1_over_default'] for r in sel]):.3f} | {geomean([r['l1_over_mc'] for r in sel]):.3f} | "
                    f"{geomean([r['time_over_default'] for r in sel]):.2f} | "
                    f"{sum(r['adaptivity_s'] for r in sel) / len(sel):.2f} |")
            if args.before:
                line += (f" {sum(r['before_adaptivity_s'] for r in sel) / len(sel):.2f} | "
                         f"{geomean([r['before_triangles_over_mc'] for r in sel]):.2f} | "
                         f"{geomean([r['before_l1_over_default'] for r in sel]):.3f} |")
            text.append(line)
    text += ["", "## Rows", "",
             "| mesh | grid | TOL | triangles / MC | L1 / default's | time / default's | merging (s) |"
             + (" before (s) |" if args.before else ""),
             "|---|---|---|---|---|---|---|" + ("---|" if args.before else "")]
    for r in rows:
        text.append(f"| {r['mesh']} | {r['res']}³ | {r['tol']:g} | {r['triangles_over_mc']:.2f} | "
                    f"{r['l1_over_default']:.3f} | {r['time_over_default']:.2f} | {r['adaptivity_s']:.2f} |"
                    + (f" {r['before_adaptivity_s']:.2f} |" if args.before else ""))
    report("\n".join(text) + "\n", args.out)


if __name__ == "__main__":
    main()

"""Chooses the screened Poisson defaults from measurement: GCP meshes of every test mesh's SDF
grid for alpha in {1, 4, 10} and depth in {8, 9, 10}, L1 and Hausdorff distance to the ground
truth and wall time, with marching cubes on the same grid for reference.

Usage: /usr/bin/python3 bench/poisson_defaults.py [--grids 32,64] [--alphas 1,4,10]
       [--depths 8,9,10] [--meshes bunny,spot] [--out docs/poisson_defaults.md]
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
MESHES = os.path.join(ROOT, "..", "shared", "data", "meshes")


def run(cmd):
    start = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - start


def evaluate(cli, mesh, gt):
    r = subprocess.run([cli, "eval", mesh, gt, "--samples", "50000"], capture_output=True, text=True, check=True)
    e = json.loads(r.stdout)
    return e["L1"], e["L_inf"]


def geomean(v):
    return math.exp(sum(math.log(x) for x in v) / len(v))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cli", default=os.path.join(ROOT, "build", "sdfcontour"))
    ap.add_argument("--grids", default="32,64")
    ap.add_argument("--alphas", default="1,4,10")
    ap.add_argument("--depths", default="8,9,10")
    ap.add_argument("--meshes", default="")
    ap.add_argument("--out", default="")
    args = ap.parse_args()
    names = args.meshes.split(",") if args.meshes else sorted(f[:-4] for f in os.listdir(MESHES) if f.endswith(".obj"))
    configs = [(float(a), int(d)) for a in args.alphas.split(",") for d in args.depths.split(",")]
    # results[grid][config] = list of (l1 / mc_l1, hausdorff / mc_hausdorff, seconds)
    results = {}
    skipped = []
    with tempfile.TemporaryDirectory() as d:
        for grid in map(int, args.grids.split(",")):
            results[grid] = {c: [] for c in configs}
            for name in names:
                prefix = os.path.join(d, f"{name}{grid}")
                run([args.cli, "sample", os.path.join(MESHES, name + ".obj"), "--res", str(grid), "-o", prefix, "-q"])
                gt = prefix + "_mesh.ply"
                try:
                    run([args.cli, "contour", prefix + ".npy", "-o", prefix + "_mc.ply", "--method", "mc", "-q"])
                except subprocess.CalledProcessError:
                    print(f"{name} {grid}^3: no sample inside (no surface to contour), skipped", flush=True)
                    skipped.append(f"{name} at {grid}³")
                    continue
                mc_l1, mc_linf = evaluate(args.cli, prefix + "_mc.ply", gt)
                gcp_seconds = run([args.cli, "contour", prefix + ".npy", "--points", prefix + "_gcp.ply", "-q"])
                line = [f"{name} {grid}^3 mc L1 {mc_l1:.2e}"]
                for alpha, depth in configs:
                    out = f"{prefix}_a{alpha}_d{depth}.ply"
                    seconds = run([args.cli, "poisson", prefix + "_gcp.ply", "-o", out, "--alpha", str(alpha),
                                   "--depth", str(depth), "-q"])
                    l1, linf = evaluate(args.cli, out, gt)
                    results[grid][(alpha, depth)].append((l1 / mc_l1, linf / mc_linf, gcp_seconds + seconds))
                    line.append(f"a{alpha:g}/d{depth} {l1 / mc_l1:.3f}")
                print(", ".join(line), flush=True)
    rows = ["| grid | alpha | depth | L1 / MC's L1 (geometric mean) | worst mesh | Hausdorff / MC's | GCP seconds (mean) |",
            "|---|---|---|---|---|---|---|"]
    for grid, per in results.items():
        for (alpha, depth), v in per.items():
            rows.append(f"| {grid}³ | {alpha:g} | {depth} | {geomean([x[0] for x in v]):.3f} | {max(x[0] for x in v):.3f} | "
                        f"{geomean([x[1] for x in v]):.3f} | {sum(x[2] for x in v) / len(v):.2f} |")
    print("\n".join(rows))
    if args.out:
        with open(args.out, "w") as f:
            f.write("# Screened Poisson defaults for GCP\n\nGCP meshes (James weights, regular triangulation) of each "
                    f"test mesh's SDF grid, {len(names)} meshes; distances to the ground truth relative to marching "
                    "cubes on the same grid (below 1: GCP is closer). "
                    f"Skipped, no sample inside the shape: {', '.join(skipped) or 'none'}. Made by `/usr/bin/python3 "
                    f"bench/poisson_defaults.py {' '.join(sys.argv[1:])}`.\n\n" + "\n".join(rows) + "\n")


if __name__ == "__main__":
    main()

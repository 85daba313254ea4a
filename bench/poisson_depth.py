"""Chooses GCP's automatic screened Poisson depth for coarse grids from measurement: the whole
pipeline (`sdfcontour contour --reconstruction poisson --depth D`) on every shared mesh's SDF grid,
L1 to the ground truth and triangle count relative to marching cubes on the same grid, and wall
time.

Usage: /usr/bin/python3 bench/poisson_depth.py [--grids 16,32,64] [--depths 6,7,8]
       [--meshes bunny,spot] [--out docs/results/poisson_depth.md]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

from common import CLI, MESHES, geomean, report


def run(cmd):
    start = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - start


def l1_and_triangles(mesh, gt):
    e = json.loads(subprocess.run([CLI, "eval", mesh, gt, "--samples", "50000"], capture_output=True,
                                  text=True, check=True).stdout)
    with open(mesh, "rb") as f:
        header = f.read(400).split(b"end_header")[0].decode("ascii", "replace")
    triangles = int(header.split("element face ")[1].split()[0])
    return e["L1"], triangles


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--grids", default="16,32,64")
    ap.add_argument("--depths", default="6,7,8")
    ap.add_argument("--meshes", default="")
    ap.add_argument("--out", default="")
    a = ap.parse_args()
    names = a.meshes.split(",") if a.meshes else sorted(
        f[:-4] for f in os.listdir(MESHES) if f.endswith(".obj"))
    depths = [int(d) for d in a.depths.split(",")]
    rows = ["| grid | depth | L1 / MC's (geometric mean) | worst mesh | triangles / MC's (mean) "
            "| seconds (mean) | fallbacks |", "|---|---|---|---|---|---|---|"]
    with tempfile.TemporaryDirectory() as d:
        for grid in map(int, a.grids.split(",")):
            per = {depth: [] for depth in depths}
            for name in names:
                prefix = os.path.join(d, f"{name}{grid}")
                gt = prefix + "_mesh.ply"
                try:  # a mesh thinner than a spacing has no sample inside: skipped
                    run([CLI, "sample", os.path.join(MESHES, name + ".obj"), "--res", str(grid),
                         "-o", prefix, "-q"])
                    run([CLI, "contour", prefix + ".npy", "-o", prefix + "_mc.ply", "--method", "mc",
                         "-q"])
                except subprocess.CalledProcessError:
                    continue  # no sample inside at this grid
                mc_l1, mc_triangles = l1_and_triangles(prefix + "_mc.ply", gt)
                line = [f"{name} {grid}^3"]
                for depth in depths:
                    out, stats = f"{prefix}_d{depth}.ply", f"{prefix}_d{depth}.json"
                    seconds = run([CLI, "contour", prefix + ".npy", "-o", out, "--reconstruction",
                                   "poisson", "--depth", str(depth), "--stats", stats, "-q"])
                    with open(stats) as f:
                        fell_back = bool(json.load(f).get("fallback"))
                    l1, triangles = l1_and_triangles(out, gt)
                    per[depth].append((l1 / mc_l1, triangles / mc_triangles, seconds, fell_back))
                    line.append(f"d{depth} {l1 / mc_l1:.3f} ({triangles / mc_triangles:.1f}x tri)")
                print(", ".join(line), flush=True)
            for depth, v in per.items():
                rows.append(f"| {grid}³ | {depth} | {geomean([x[0] for x in v]):.3f} | "
                            f"{max(x[0] for x in v):.3f} | {sum(x[1] for x in v) / len(v):.1f} | "
                            f"{sum(x[2] for x in v) / len(v):.2f} | {sum(x[3] for x in v)} |")
    text = ("# GCP's Poisson depth on coarse grids\n\nThe whole GCP pipeline with the screened "
            f"Poisson reconstruction at a given depth, on the SDF grids of {len(names)} shared "
            "meshes; L1 to the ground truth and triangles relative to marching cubes on the same "
            "grid. Made by `/usr/bin/python3 bench/poisson_depth.py "
            f"{' '.join(sys.argv[1:])}`.\n\n" + "\n".join(rows) + "\n")
    report(text, a.out)


if __name__ == "__main__":
    main()

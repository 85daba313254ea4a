"""Our screened Poisson reconstruction against two builds of Kazhdan's code run side by side:
MeshLab's filter (meshlabserver under xvfb-run; pointWeight, depth, samplesPerNode as ours) and
Open3D's (point weight fixed at 2, Neumann, degree 1).

Inputs, for each mesh in ../shared/data/meshes scaled to [-0.9, 0.9]^3:
  - surface: --points oriented points sampled uniformly by area, with face normals;
  - gtcp: the exact contact points of the mesh's SDF on a --grid^3 grid over [-1, 1]^3.
Each tool runs as its own process on the same PLY file; we report its wall time and peak memory
(/usr/bin/time), and the L1 and Hausdorff distances of its mesh to the ground truth
(`sdfcontour eval`). Ratios are ours / peer; the geometric means are over all rows.

Usage: /usr/bin/python3 bench/poisson_compare.py [--depth 8] [--alpha 2] [--degree 1] [--points 100000]
       [--grid 64] [--meshes bunny,spot] [--inputs surface,gtcp] [--peers meshlab,open3d]
       [--out docs/poisson_comparison.md]
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

import numpy as np
import open3d as o3d

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
MESHES = os.path.join(ROOT, "..", "shared", "data", "meshes")

MLX = """<!DOCTYPE FilterScript>
<FilterScript>
 <filter name="Surface Reconstruction: Screened Poisson">
  <Param type="RichBool" value="false" name="visibleLayer"/>
  <Param type="RichInt" value="{depth}" name="depth"/>
  <Param type="RichInt" value="5" name="fullDepth"/>
  <Param type="RichInt" value="0" name="cgDepth"/>
  <Param type="RichFloat" value="1.1" name="scale"/>
  <Param type="RichFloat" value="1.5" name="samplesPerNode"/>
  <Param type="RichFloat" value="{alpha}" name="pointWeight"/>
  <Param type="RichInt" value="8" name="iters"/>
  <Param type="RichBool" value="false" name="confidence"/>
  <Param type="RichBool" value="false" name="preClean"/>
 </filter>
</FilterScript>
"""


def timed(cmd, cwd=None):
    """Runs cmd; returns (wall seconds, peak resident MB)."""
    r = subprocess.run(["/usr/bin/time", "-f", "%e %M", *cmd], capture_output=True, text=True, cwd=cwd)
    if r.returncode != 0:
        raise RuntimeError(f"{cmd[0]} failed: {r.stderr[-500:]}")
    wall, kb = r.stderr.strip().splitlines()[-1].split()
    return float(wall), float(kb) / 1024


def evaluate(cli, mesh, gt):
    r = subprocess.run([cli, "eval", mesh, gt, "--samples", "100000"], capture_output=True, text=True, check=True)
    e = json.loads(r.stdout)
    return e["L1"], e["L_inf"], e["recon_mesh"]["closed"]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cli", default=os.path.join(ROOT, "build", "sdfcontour"))
    ap.add_argument("--depth", type=int, default=8)
    ap.add_argument("--degree", type=int, default=1, help="our elements: 1 trilinear, 2 quadratic")
    ap.add_argument("--alpha", type=float, default=2.0, help="screening weight for ours and MeshLab (Open3D: 2)")
    ap.add_argument("--points", type=int, default=100000)
    ap.add_argument("--grid", type=int, default=64)
    ap.add_argument("--meshes", default="", help="comma-separated names (default: all)")
    ap.add_argument("--inputs", default="surface,gtcp")
    ap.add_argument("--peers", default="meshlab,open3d", help="peers to run (Open3D's alpha is always 2)")
    ap.add_argument("--out", default="")
    args = ap.parse_args()
    peers = args.peers.split(",")
    names = args.meshes.split(",") if args.meshes else sorted(f[:-4] for f in os.listdir(MESHES) if f.endswith(".obj"))
    tools = ["ours"] + peers
    rows, ratios = [], {f"{measure}_{peer}": [] for measure in ("l1", "time") for peer in peers}
    with tempfile.TemporaryDirectory() as d:
        mlx = os.path.join(d, "poisson.mlx")
        open(mlx, "w").write(MLX.format(depth=args.depth, alpha=args.alpha))
        for name in names:
            prefix = os.path.join(d, name)
            subprocess.run([args.cli, "sample", os.path.join(MESHES, name + ".obj"), "--res", str(args.grid), "-o", prefix,
                            "-q"], check=True, stdout=subprocess.DEVNULL)
            gt = prefix + "_mesh.ply"
            surface = o3d.io.read_triangle_mesh(gt).sample_points_uniformly(args.points, use_triangle_normal=True)
            o3d.io.write_point_cloud(prefix + "_surface.ply", surface)
            inputs = {"surface": prefix + "_surface.ply", "gtcp": prefix + "_gtcp.ply"}
            for kind in args.inputs.split(","):
                pts = inputs[kind]
                result = {}
                for tool in tools:
                    out = f"{prefix}_{kind}_{tool}.ply"
                    if tool == "ours":
                        cmd = [args.cli, "poisson", pts, "-o", out, "--depth", str(args.depth), "--alpha", str(args.alpha),
                               "--degree", str(args.degree), "-q"]
                    elif tool == "meshlab":
                        cmd = ["xvfb-run", "-a", "meshlabserver", "-i", pts, "-o", out, "-s", mlx]
                    else:
                        cmd = [sys.executable, os.path.join(HERE, "open3d_poisson.py"), pts, out, str(args.depth)]
                    wall, mb = timed(cmd, cwd=d)
                    l1, linf, closed = evaluate(args.cli, out, gt)
                    result[tool] = (l1, linf, wall, mb, closed)
                ours = result["ours"]
                for peer in peers:
                    ratios["l1_" + peer].append(ours[0] / result[peer][0])
                    ratios["time_" + peer].append(ours[2] / result[peer][2])
                row = (f"| {name} | {kind} | " + " | ".join(
                    f"{result[t][0]:.2e} / {result[t][1]:.2e}" for t in tools) + " | " + " | ".join(
                    f"{result[t][2]:.2f} s, {result[t][3]:.0f} MB" for t in tools) + " | " +
                    "".join(f"{ours[0] / result[t][0]:.2f} | " for t in peers) +
                    "".join(f"{ours[2] / result[t][2]:.2f} | " for t in peers) + f"{'yes' if ours[4] else 'NO'} |")
                rows.append(row)
                print(row, flush=True)
    geo = {k: math.exp(sum(map(math.log, v)) / len(v)) for k, v in ratios.items() if v}
    names_of = {"ours": "ours", "meshlab": "MeshLab", "open3d": "Open3D"}
    columns = (["mesh", "input"] + [f"L1 / Hausdorff: {names_of[t]}" for t in tools] +
               [f"time, peak memory: {names_of[t]}" for t in tools] +
               [f"L1 ours/{names_of[t]}" for t in peers] + [f"time ours/{names_of[t]}" for t in peers] +
               ["ours closed"])
    header = "| " + " | ".join(columns) + " |\n|" + "---|" * len(columns)
    summary = "Geometric means of ours/peer: " + "; ".join(
        f"L1 vs {names_of[t]} {geo['l1_' + t]:.3f} (worst {max(ratios['l1_' + t]):.2f}, "
        f"{sum(r <= 1.05 for r in ratios['l1_' + t])} of {len(ratios['l1_' + t])} within 5%), "
        f"wall time vs {names_of[t]} {geo['time_' + t]:.3f} (worst {max(ratios['time_' + t]):.2f})"
        for t in peers) + "."
    print(summary)
    if args.out:
        with open(args.out, "w") as f:
            f.write(f"# Screened Poisson: ours against {' and '.join(names_of[t] for t in peers)}\n\nDepth {args.depth}, alpha {args.alpha}, our degree {args.degree}"
                    f"{' (Open3D: 2)' if 'open3d' in peers else ''}, {args.points} surface points or the GTCP points of a {args.grid}^3 grid; "
                    f"2 cores. Made by `/usr/bin/python3 bench/poisson_compare.py "
                    f"{' '.join(sys.argv[1:])}`.\n\n{header}\n" + "\n".join(rows) + f"\n\n{summary}\n")


if __name__ == "__main__":
    main()

"""The callable sampler's cost against the network's own (issue 37): marching cubes of the neural
SDF fixture (bench/data/neural_bunny.npz, a 4x64 MLP evaluated with numpy) passed as a callable,
at N = 128, 256, 512. Reports the wall time, the time spent inside the network, marching cubes'
time on a dense N^3 grid of the same size (the marching a dense path would add), the evaluated
fraction, and the peak RSS above the process's baseline (network loaded) against the mesh's own
size. Each N runs in its own process, so each peak is its own.

    /usr/bin/python3 bench/callable_sampler.py [--res 128,256,512] [--out docs/results/callable_sampler.md]
"""
import argparse
import json
import os
import resource
import subprocess
import sys
import time

import numpy as np

from common import report

HERE = os.path.dirname(os.path.abspath(__file__))


def one(n):
    import sdfcontour
    from neural_sdf import load
    net = load(os.path.join(HERE, "data", "neural_bunny.npz"))
    spent = [0.0]

    def timed_net(points):
        start = time.perf_counter()
        out = net(points)
        spent[0] += time.perf_counter() - start
        return out

    net(np.zeros((1000, 3)))  # warm
    baseline = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    start = time.perf_counter()
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sdfcontour.LipschitzWarning)  # reported in the table
        mesh = sdfcontour.contour(timed_net, resolution=n, method="mc")
    wall = time.perf_counter() - start
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    mesh_mb = (mesh.V.nbytes + mesh.F.nbytes) / 2**20
    # Marching cubes alone on a dense grid of this size (a sphere: the cost is the grid's scan).
    axis = np.linspace(-1, 1, n, dtype=np.float32)
    X, Y, Z = np.meshgrid(axis, axis, axis, indexing="ij")
    grid = np.sqrt(X * X + Y * Y + Z * Z) - np.float32(0.5)
    del X, Y, Z
    start = time.perf_counter()
    sdfcontour.contour(grid, method="mc")
    marching = time.perf_counter() - start
    return {"n": n, "wall": wall, "network": spent[0], "marching": marching,
            "fraction": mesh.stats["evaluated_fraction"], "peak_above_mb": peak - baseline,
            "mesh_mb": mesh_mb, "triangles": len(mesh.F), "bricks": mesh.stats["bricks"],
            "lipschitz": mesh.stats["lipschitz"]}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--res", default="128,256,512")
    ap.add_argument("--out", default="")
    ap.add_argument("--one", type=int)
    a = ap.parse_args()
    if a.one:
        print(json.dumps(one(a.one)))
        return
    rows = ["| N | wall (s) | network (s) | dense MC alone (s) | wall / (network + MC) | "
            "evaluated | lipschitz used | peak RSS above start (MB) | mesh (MB) | triangles |",
            "|---|---|---|---|---|---|---|---|---|---|"]
    for n in map(int, a.res.split(",")):
        r = subprocess.run([sys.executable, __file__, "--one", str(n)], capture_output=True,
                           text=True, cwd=HERE)
        if r.returncode:
            raise SystemExit(r.stderr[-2000:])
        x = json.loads(r.stdout.strip().splitlines()[-1])
        rows.append(f"| {n} | {x['wall']:.1f} | {x['network']:.1f} | {x['marching']:.2f} | "
                    f"{x['wall'] / (x['network'] + x['marching']):.2f} | {100 * x['fraction']:.1f}% | "
                    f"{x['lipschitz']:g} | "
                    f"{x['peak_above_mb']:.0f} | {x['mesh_mb']:.0f} | {x['triangles']:,} |")
        print(rows[-1], flush=True)
    text = ("# The callable sampler against the network\n\nMarching cubes of the neural SDF "
            "fixture passed as a callable (`/usr/bin/python3 bench/callable_sampler.py`), on this "
            "2-core machine: bricks of 32 cells that may hold the surface (found on a coarse grid "
            "every 8 samples) sampled coarse to fine and contoured one by one, no N³ array.\n\n"
            + "\n".join(rows) + "\n")
    report(text, a.out)


if __name__ == "__main__":
    main()

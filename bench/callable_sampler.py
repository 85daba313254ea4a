"""The callable sampler's cost against the network's own (issue 37): marching cubes of the neural
SDF fixture (bench/data/neural_bunny.npz, a 4x64 MLP evaluated with numpy) passed as a callable,
at N = 128, 256, 512. Reports the wall time, the time spent inside the network, marching cubes'
time on a dense N^3 grid of the same size (the marching a dense path would add), the evaluated
fraction, and the peak RSS above the process's baseline (network loaded) against the mesh's own
size. Each N runs in its own process, so each peak is its own.

With --method gcp: GCP's local reconstruction of the same callable (brick by brick from bricks
sampled near the surface): wall time split into network, reconstruction and the rest, and the
peak RSS above start against the N^3 float64 grid that a dense sampler would hold.

With --method poisson: GCP with the Poisson reconstruction (reconstruction="poisson"), whose
core reads the sampled bricks as a sparse grid: the same split, and whether GCP fell back to
marching cubes (the fixture is no exact distance).

    /usr/bin/python3 bench/callable_sampler.py [--res 128,256,512] [--method mc|gcp|poisson] [--out docs/results/callable_sampler.md]
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


def one(n, method="mc"):
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
        warnings.simplefilter("ignore", sdfcontour.RescaleWarning)
        if method == "poisson":
            mesh = sdfcontour.contour(timed_net, resolution=n, method="gcp",
                                      reconstruction="poisson")
        else:
            mesh = sdfcontour.contour(timed_net, resolution=n, method=method)
    wall = time.perf_counter() - start
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    mesh_mb = (mesh.V.nbytes + mesh.F.nbytes) / 2**20
    if method == "poisson":
        seconds = mesh.stats["seconds"]
        return {"n": n, "wall": wall, "network": spent[0],
                "core": sum(t for k, t in seconds.items() if k != "sampling"),
                "fallback": bool(mesh.stats.get("fallback")),
                "bricks": mesh.stats["sampled_bricks"], "fraction": mesh.stats["evaluated_fraction"],
                "peak_above_mb": peak - baseline, "dense_mb": n ** 3 * 8 / 2**20,
                "triangles": len(mesh.F)}
    if method == "gcp":
        return {"n": n, "wall": wall, "network": spent[0],
                "local": mesh.stats["seconds"]["local"], "bricks": mesh.stats["local_bricks"],
                "fraction": mesh.stats["evaluated_fraction"], "peak_above_mb": peak - baseline,
                "dense_mb": n ** 3 * 8 / 2**20, "mesh_mb": mesh_mb, "triangles": len(mesh.F),
                "value_scale": mesh.stats["value_scale"], "lipschitz": mesh.stats["lipschitz"]}
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
    ap.add_argument("--method", default="mc", choices=["mc", "gcp", "poisson"])
    a = ap.parse_args()
    if a.one:
        print(json.dumps(one(a.one, a.method)))
        return
    table(a, TABLES[a.method])


def each_in_its_process(resolutions, method):
    """(N, one(N, method)) for each N of the comma-separated list, each run in its own process
    so that each peak RSS is its own."""
    for n in map(int, resolutions.split(",")):
        r = subprocess.run([sys.executable, __file__, "--one", str(n), "--method", method],
                           capture_output=True, text=True, cwd=HERE)
        if r.returncode:
            raise SystemExit(r.stderr[-2000:])
        yield n, json.loads(r.stdout.strip().splitlines()[-1])


def table(a, spec):
    """The markdown table of `spec` (title, introduction, column names, the cells of a run) over
    a.res, each N in its own process, into a.out."""
    title, intro, columns, cells = spec
    rows = ["| " + " | ".join(["N"] + columns) + " |", "|---" * (len(columns) + 1) + "|"]
    for n, x in each_in_its_process(a.res, a.method):
        rows.append("| " + " | ".join([str(n)] + cells(x)) + " |")
        print(rows[-1], flush=True)
    report(f"# {title}\n\n{intro}\n\n" + "\n".join(rows) + "\n", a.out)


TABLES = {
    "mc": (
        "The callable sampler against the network",
        "Marching cubes of the neural SDF fixture passed as a callable (`/usr/bin/python3 "
        "bench/callable_sampler.py`), on this 2-core machine: bricks of 32 cells that may hold the "
        "surface (found on a coarse grid every 8 samples) sampled coarse to fine and contoured one "
        "by one, no N³ array.",
        ["wall (s)", "network (s)", "dense MC alone (s)", "wall / (network + MC)", "evaluated",
         "lipschitz used", "peak RSS above start (MB)", "mesh (MB)", "triangles"],
        lambda x: [f"{x['wall']:.1f}", f"{x['network']:.1f}", f"{x['marching']:.2f}",
                   f"{x['wall'] / (x['network'] + x['marching']):.2f}",
                   f"{100 * x['fraction']:.1f}%", f"{x['lipschitz']:g}",
                   f"{x['peak_above_mb']:.0f}", f"{x['mesh_mb']:.0f}", f"{x['triangles']:,}"]),
    "gcp": (
        "GCP of a callable, brick by brick",
        "GCP's local reconstruction of the neural SDF fixture passed as a callable "
        "(`/usr/bin/python3 bench/callable_sampler.py --method gcp`), on this 2-core machine, "
        "refined on the callable (the default): bricks of 32 cells that may hold the surface "
        "sampled once each, exact within the reach of the reconstruction's reads, then bricks of "
        "256 cells reconstructed from blocks assembled out of them. 'rest': sampling "
        "bookkeeping, assembly, joining and refining.",
        ["wall (s)", "network (s)", "local reconstruction (s)", "rest (s)", "evaluated", "bricks",
         "peak RSS above start (MB)", "dense N³ float64 grid (MB)", "triangles"],
        lambda x: [f"{x['wall']:.1f}", f"{x['network']:.1f}", f"{x['local']:.1f}",
                   f"{x['wall'] - x['network'] - x['local']:.1f}",
                   f"{100 * x['fraction']:.1f}%", str(x["bricks"]),
                   f"{x['peak_above_mb']:.0f}", f"{x['dense_mb']:.0f}", f"{x['triangles']:,}"]),
    "poisson": (
        "GCP-Poisson of a callable, from a sparse grid",
        "GCP with the Poisson reconstruction of the neural SDF fixture passed as a callable "
        "(`/usr/bin/python3 bench/callable_sampler.py --method poisson`), on this 2-core machine: "
        "bricks of 32 cells that may hold the surface sampled once each, exact within the band "
        "and the carving band, handed to the core as a sparse grid (no N³ array). 'core's "
        "stages': band, contact points, Poisson, projection, carving, checks (and marching cubes "
        "where GCP fell back); 'rest': sampling bookkeeping.",
        ["wall (s)", "network (s)", "core's stages (s)", "rest (s)", "evaluated",
         "sampled bricks", "fell back to MC", "peak RSS above start (MB)",
         "dense N³ float64 grid (MB)", "triangles"],
        lambda x: [f"{x['wall']:.1f}", f"{x['network']:.1f}", f"{x['core']:.1f}",
                   f"{x['wall'] - x['network'] - x['core']:.1f}",
                   f"{100 * x['fraction']:.1f}%", str(x["bricks"]),
                   "yes" if x["fallback"] else "no", f"{x['peak_above_mb']:.0f}",
                   f"{x['dense_mb']:.0f}", f"{x['triangles']:,}"]),
}


if __name__ == "__main__":
    main()

"""Grids larger than one process on Dask (issue 38): one command, results in
docs/results/distributed.md.

1. A 1024^3 truncated grid stored as zarr (128^3 chunks; chunks that hold only the outside value
   are not stored), contoured by marching cubes in one process (the whole grid read into memory)
   and by sdfcontour.dask on a local cluster of 2 single-threaded workers limited to 2 GB each.
   Wall time, peak RSS of the single process and of each worker, and whether the joined mesh is
   the single-process mesh bit for bit.
2. A 2048^3 sparse level set, generated chunk by chunk (never dense in memory), contoured on 2
   workers limited to 3 GB each and streamed into a PLY: time, memory, triangles.

Each measurement runs in its own process so that its peak RSS is its own.

    /usr/bin/python3 bench/dask_bricks.py [--n 1024] [--big 2048] [--work /tmp/sdfcontour-dask]
    /usr/bin/python3 bench/dask_bricks.py --gcp 512   # GCP's rows: docs/results/distributed_gcp.md
"""
import argparse
import concurrent.futures
import json
import os
import resource
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
CHUNK = 128


def shape_sdf(p, kind):
    """Distances to a union of simple solids (kind "scene": a torus, a box, three spheres; kind
    "sphere": one sphere of radius 0.7): exact near each part, cheap for 10^9 points."""
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    if kind == "sphere":
        return np.sqrt(x * x + y * y + z * z) - 0.7
    torus = np.sqrt((np.sqrt(x * x + z * z) - 0.5) ** 2 + (y - 0.35) ** 2) - 0.18
    q = np.abs(p - np.array([0.1, -0.3, 0.05])) - np.array([0.45, 0.2, 0.3])
    box = np.linalg.norm(np.maximum(q, 0), axis=-1) + np.minimum(q.max(axis=-1), 0)
    d = np.minimum(torus, box)
    for c, r in (((-0.6, 0.5, -0.5), 0.25), ((0.6, 0.55, 0.55), 0.2), ((-0.55, -0.6, 0.6), 0.3)):
        d = np.minimum(d, np.linalg.norm(p - np.array(c), axis=-1) - r)
    return d


def _fill_chunk(path, n, kind, truncation, index):
    import zarr
    z = zarr.open(path, mode="r+")
    h = 2.0 / (n - 1)
    first = [i * CHUNK for i in index]
    last = [min(f + CHUNK, n) for f in first]
    centre = np.array([-1 + (f + l - 1) / 2 * h for f, l in zip(first, last)])
    half_diagonal = np.sqrt(3) * CHUNK * h / 2
    d = float(shape_sdf(centre[None, :], kind)[0])
    if d > half_diagonal + truncation:
        return 0  # all outside: the fill value, not stored
    sl = tuple(slice(f, l) for f, l in zip(first, last))
    if d < -half_diagonal - truncation:
        z[sl] = -truncation
        return 1
    axes = [-1 + np.arange(f, l) * h for f, l in zip(first, last)]
    P = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)
    z[sl] = np.clip(shape_sdf(P, kind), -truncation, truncation).astype(np.float32)
    return 1


def make_zarr(path, n, kind):
    """A truncated (4 spacings) float32 grid over [-1, 1]^3 as zarr, chunk by chunk on 2
    processes; chunks wholly outside are left to the fill value."""
    import zarr
    truncation = 4 * 2.0 / (n - 1)
    made = os.path.join(path, ".bench.json")  # how it was made, for a rerun that reuses it
    if os.path.exists(made):
        with open(made) as f:
            return json.load(f)
    started = time.perf_counter()
    zarr.open(path, mode="w", shape=(n, n, n), chunks=(CHUNK,) * 3, dtype="f4",
              fill_value=truncation, write_empty_chunks=False)
    count = -(-n // CHUNK)
    indices = [(i, j, k) for i in range(count) for j in range(count) for k in range(count)]
    with concurrent.futures.ProcessPoolExecutor(2) as pool:
        stored = sum(pool.map(_fill_chunk, [path] * len(indices), [n] * len(indices),
                              [kind] * len(indices), [truncation] * len(indices), indices,
                              chunksize=8))
    info = {"seconds": time.perf_counter() - started, "stored": stored, "chunks": len(indices)}
    with open(made, "w") as f:
        json.dump(info, f)
    return info


def peak_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def phase_single(path, mesh_out, method="mc"):
    import zarr
    import sdfcontour
    started = time.perf_counter()
    grid = zarr.open(path, mode="r")[...]
    read = time.perf_counter() - started
    V, F = sdfcontour.contour(grid, method=method,
                              **({"reconstruction": "local"} if method == "gcp" else {}))
    wall = time.perf_counter() - started
    np.savez(mesh_out, V=V, F=F)
    return {"wall": wall, "read": read, "peak_mb": peak_mb(), "triangles": len(F)}


def phase_dask(path, memory_limit, brick, mesh_out, ply_out, method="mc"):
    import distributed
    import sdfcontour.dask
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       memory_limit=memory_limit, dashboard_address=None,
                                       silence_logs=40)
    with distributed.Client(cluster) as client:
        started = time.perf_counter()
        if ply_out:
            stats = sdfcontour.dask.contour(path, method=method, brick=brick, client=client,
                                            out=ply_out)
        else:
            V, F, stats = sdfcontour.dask.contour(path, method=method, brick=brick,
                                                  client=client, return_stats=True)
        wall = time.perf_counter() - started
        workers = client.run(lambda: resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
    cluster.close()
    if mesh_out:
        np.savez(mesh_out, V=V, F=F)
    return {"wall": wall, "worker_peak_mb": sorted(workers.values()), "client_peak_mb": peak_mb(),
            "triangles": stats["triangles"], "vertices": stats["vertices"],
            "bricks": stats["bricks"], "empty_bricks": stats["empty_bricks"]}


def run_phase(*args):
    r = subprocess.run([sys.executable, __file__, "--phase", json.dumps(args)],
                       capture_output=True, text=True)
    if r.returncode:
        raise SystemExit(f"phase {args[0]} failed:\n{r.stderr[-3000:]}")
    return json.loads(r.stdout.strip().splitlines()[-1])


def same_mesh(a, b):
    from sdfcontour.dask import canonical_mesh
    A, B = np.load(a), np.load(b)
    ca, cb = canonical_mesh(A["V"], A["F"]), canonical_mesh(B["V"], B["F"])
    return bool(np.array_equal(ca[0], cb[0]) and np.array_equal(ca[1], cb[1]))


def figure(path, n=97, brick=32):
    """The scene at n^3, each brick's piece in its own colour: the pieces meet at the seams
    without cracks (computed with the brick API directly, no cluster)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection
    import sdfcontour.dask as sd
    h = 2.0 / (n - 1)
    axis = -1 + np.arange(n) * h
    grid = shape_sdf(np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1), "scene")
    lo, hi = (-1.0,) * 3, (1.0,) * 3
    pieces, colours = [], []
    cmap = plt.get_cmap("tab20")
    for number, (index, first, dims) in enumerate(sd.bricks(grid.shape, brick)):
        sl = tuple(slice(f, f + d) for f, d in zip(first, dims))
        keys, V, F = sd.brick_piece(grid[sl], index, first, grid.shape, lo, hi)
        if len(F):
            pieces.append((keys, V, F))
            colours += [cmap(number % 20)] * len(F)
    tris = np.concatenate([V[F] for _, V, F in pieces])
    normal = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    light = np.array([0.4, 0.8, 0.5]) / np.linalg.norm([0.4, 0.8, 0.5])
    shade = 0.35 + 0.65 * np.clip(normal @ light, 0, 1)
    face = np.array(colours)[:, :3] * shade[:, None]
    fig = plt.figure(figsize=(7, 6.5), dpi=110)
    ax = fig.add_subplot(projection="3d")
    # Swap y and z so that y is up.
    ax.add_collection3d(Poly3DCollection(tris[:, :, [0, 2, 1]], facecolors=face, linewidths=0))
    ax.set_xlim(-1, 1), ax.set_ylim(-1, 1), ax.set_zlim(-1, 1)
    ax.set_box_aspect(None, zoom=1.6)
    ax.view_init(elev=22, azim=-58)
    ax.set_axis_off()
    ax.set_title(f"marching cubes at {n}³ in bricks of {brick} cells: one colour per brick",
                 fontsize=10)
    fig.tight_layout()
    fig.savefig(path)


def gcp_rows(a):
    """GCP's local reconstruction on an N^3 zarr scene: one process against 2 workers."""
    os.makedirs(a.work, exist_ok=True)
    grid = os.path.join(a.work, f"scene{a.gcp}.zarr")
    made = make_zarr(grid, a.gcp, "scene")
    single = run_phase("single", grid, os.path.join(a.work, "gcp_single.npz"), "gcp")
    dask_run = run_phase("dask", grid, "3GB", a.brick, os.path.join(a.work, "gcp_dask.npz"), None,
                         "gcp")
    equal = same_mesh(os.path.join(a.work, "gcp_single.npz"), os.path.join(a.work, "gcp_dask.npz"))
    text = "\n".join([
        "# GCP (local reconstruction) on Dask: bricks on 2 workers against one process", "",
        f"`/usr/bin/python3 bench/dask_bricks.py --gcp {a.gcp}` on this 2-core machine: a {a.gcp}³ "
        f"zarr scene (float32, {CHUNK}³ chunks, truncated at 4 spacings, {made['stored']} of "
        f"{made['chunks']} chunks stored), GCP with `reconstruction=\"local\"` in one process "
        f"against `sdfcontour.dask.contour(method=\"gcp\", brick={a.brick})` on 2 single-threaded "
        f"workers of 3 GB (a first pass over the bricks finds the truncation).", "",
        "| run | wall (s) | client / single process peak (MB) | worker peaks (MB) | triangles | mesh |",
        "|---|---|---|---|---|---|",
        f"| one process (of which {single['read']:.1f} s reading the grid) | {single['wall']:.1f} | "
        f"{single['peak_mb']:.0f} | – | {single['triangles']:,} | reference |",
        f"| 2 workers × 3 GB, bricks {a.brick} | {dask_run['wall']:.1f} | "
        f"{dask_run['client_peak_mb']:.0f} | "
        + " / ".join(f"{m:.0f}" for m in dask_run["worker_peak_mb"]) +
        f" | {dask_run['triangles']:,} | {'bit for bit' if equal else 'DIFFERENT'} |", ""])
    with open(os.path.join(os.path.dirname(a.out), "distributed_gcp.md"), "w") as f:
        f.write(text)
    print(text)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=1024)
    ap.add_argument("--big", type=int, default=2048)
    ap.add_argument("--brick", type=int, default=256)
    ap.add_argument("--work", default="/tmp/sdfcontour-dask")
    ap.add_argument("--out", default=os.path.join(HERE, "..", "docs", "results", "distributed.md"))
    ap.add_argument("--phase")
    ap.add_argument("--figure", help="only draw the bricks' figure into this PNG")
    ap.add_argument("--gcp", type=int, default=0,
                    help="only GCP (local reconstruction) on an N^3 scene: one process against 2 "
                         "workers x 3 GB, into docs/results/distributed_gcp.md")
    a = ap.parse_args()
    if a.phase:
        args = json.loads(a.phase)
        result = {"single": phase_single, "dask": phase_dask}[args[0]](*args[1:])
        print(json.dumps(result))
        return
    if a.figure:
        figure(a.figure)
        return
    if a.gcp:
        return gcp_rows(a)
    os.makedirs(a.work, exist_ok=True)
    rows = []
    grid = os.path.join(a.work, f"scene{a.n}.zarr")
    scene = make_zarr(grid, a.n, "scene")
    single = run_phase("single", grid, os.path.join(a.work, "single.npz"))
    dask_run = run_phase("dask", grid, "2GB", a.brick, os.path.join(a.work, "dask.npz"), None)
    equal = same_mesh(os.path.join(a.work, "single.npz"), os.path.join(a.work, "dask.npz"))
    rows.append((f"{a.n}³ scene, one process (of which {single['read']:.1f} s reading the whole "
                 f"grid)", single["wall"],
                 f"{single['peak_mb']:.0f}", "–", single["triangles"], "reference"))
    rows.append((f"{a.n}³ scene, 2 workers × 2 GB, bricks {a.brick}", dask_run["wall"],
                 f"{dask_run['client_peak_mb']:.0f}",
                 " / ".join(f"{m:.0f}" for m in dask_run["worker_peak_mb"]),
                 dask_run["triangles"], "bit for bit" if equal else "DIFFERENT"))
    big = os.path.join(a.work, f"sphere{a.big}.zarr")
    made = make_zarr(big, a.big, "sphere")
    ply = os.path.join(a.work, f"sphere{a.big}.ply")
    big_run = run_phase("dask", big, "3GB", a.brick, None, ply)
    rows.append((f"{a.big}³ sphere level set, 2 workers × 3 GB, streamed to PLY", big_run["wall"],
                 f"{big_run['client_peak_mb']:.0f}",
                 " / ".join(f"{m:.0f}" for m in big_run["worker_peak_mb"]), big_run["triangles"],
                 f"{os.path.getsize(ply) / 2**20:.0f} MB PLY"))
    lines = [
        "# Contouring on Dask: bricks on 2 workers against one process",
        "",
        f"`/usr/bin/python3 bench/dask_bricks.py` on this 2-core machine, marching cubes, bricks of "
        f"{a.brick} cells. Zarr grids of float32 in {CHUNK}³ chunks, truncated at 4 spacings, "
        f"chunks wholly outside not stored. Peak RSS per process (`ru_maxrss`); the client joins "
        f"the pieces.",
        "",
        "| run | wall (s) | client / single process peak (MB) | worker peaks (MB) | triangles | mesh |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(f"| {r[0]} | {r[1]:.1f} | {r[2]} | {r[3]} | {r[4]:,} | {r[5]} |")
    lines += ["", f"The {a.n}³ grid was generated chunk by chunk in {scene['seconds']:.0f} s "
              f"({scene['stored']} of {scene['chunks']} chunks stored), the {a.big}³ grid in "
              f"{made['seconds']:.0f} s ({made['stored']} of {made['chunks']} chunks stored; "
              f"{big_run['bricks']} bricks, {big_run['empty_bricks']} of them without surface)."]
    text = "\n".join(lines) + "\n"
    with open(a.out, "w") as f:
        f.write(text)
    print(text)


if __name__ == "__main__":
    main()

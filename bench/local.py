"""GCP's local reconstruction against its Poisson reconstruction, marching cubes and marching
tetrahedra (regular triangulation) on the shared meshes: L1 and L-infinity to the mesh, the mean
distance from points along the mesh's sharp edges (dihedral > 30 degrees) to each method's mesh in
spacings, closedness, triangles, wall time and peak memory. One JSON line per mesh, grid and
method on stdout; with --markdown, the tables (geometric means of the ratios to MC) there too.

    /usr/bin/python3 bench/local.py --res 32,64 --markdown docs/results/local.md

A constant's sweep: each --variant LABEL:OPTIONS adds a method, GCP's local reconstruction with
those options, e.g.

    /usr/bin/python3 bench/local.py --res 128 --methods mc --variant band4:"--band 4" \
        --variant band8:"--band 8"
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import CLI, MESHES, evaluate, geomean, timed  # noqa: E402

METHODS = {
    "mc": ["--method", "mc"],
    "mt-rt": ["--method", "mt-rt"],
    "gcp-poisson": ["--method", "gcp", "--reconstruction", "poisson"],
    "gcp-local": ["--method", "gcp", "--reconstruction", "local"],
    "gcp-local-thin": ["--method", "gcp", "--reconstruction", "local", "--thin-parts", "on"],
    # The same grid as an OpenVDB level set (half width 3 spacings): local reads it box by box,
    # Poisson sparse.
    "gcp-local-vdb": ["--method", "gcp", "--reconstruction", "local"],
    "gcp-poisson-vdb": ["--method", "gcp", "--reconstruction", "poisson"],
}


def read_ply(path):
    """Vertices (n x 3) and triangles (f x 3, none for a point file) of a binary little-endian PLY
    as sdfcontour writes."""
    with open(path, "rb") as f:
        header = []
        while True:
            line = f.readline().decode().strip()
            header.append(line)
            if line == "end_header":
                break
        data = f.read()
    nv = nf = 0
    vprops, in_vertex, face_list = [], False, None
    for line in header:
        w = line.split()
        if w[:2] == ["element", "vertex"]:
            nv, in_vertex = int(w[2]), True
        elif w[:2] == ["element", "face"]:
            nf, in_vertex = int(w[2]), False
        elif w[:1] == ["property"] and in_vertex:
            vprops.append(w[1])
        elif w[:2] == ["property", "list"]:
            face_list = w[2:4]
    kinds = {"double": "<f8", "float64": "<f8", "float": "<f4", "float32": "<f4",
             "uchar": "u1", "uint8": "u1", "int": "<i4", "int32": "<i4", "uint": "<u4",
             "uint32": "<u4"}
    vt = np.dtype([(f"p{i}", kinds[t]) for i, t in enumerate(vprops)])
    v = np.frombuffer(data[:nv * vt.itemsize], dtype=vt)
    V = np.stack([v["p0"], v["p1"], v["p2"]], axis=1).astype(float)
    if face_list is None:  # a point file (contour --points): no triangles
        return V, np.zeros((0, 3), dtype=np.int64)
    ft = np.dtype([("n", kinds[face_list[0]]), ("i", kinds[face_list[1]], 3)])
    F = np.frombuffer(data[nv * vt.itemsize:nv * vt.itemsize + nf * ft.itemsize], dtype=ft)["i"]
    return V, F.astype(np.int64)


def area_samples(V, F, count=200000, seed=1):
    """`count` points spread uniformly over the triangles' area."""
    rng = np.random.default_rng(seed)
    A = V[F]
    area = 0.5 * np.linalg.norm(np.cross(A[:, 1] - A[:, 0], A[:, 2] - A[:, 0]), axis=1)
    t = rng.choice(len(F), count, p=area / area.sum())
    u = rng.random((count, 2))
    flip = u.sum(axis=1) > 1
    u[flip] = 1 - u[flip]
    return A[t, 0] + u[:, :1] * (A[t, 1] - A[t, 0]) + u[:, 1:] * (A[t, 2] - A[t, 0])


def sharp_edges(V, F, angle=30.0):
    """The mesh's edges whose two faces meet at more than `angle` degrees: (a, b, face0, face1)
    per edge, and the faces' unit normals."""
    n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    edges = {}
    for t, tri in enumerate(F):
        for k in range(3):
            a, b = int(tri[k]), int(tri[(k + 1) % 3])
            edges.setdefault((min(a, b), max(a, b)), []).append(t)
    cos = np.cos(np.radians(angle))
    return [(a, b, *faces) for (a, b), faces in edges.items()
            if len(faces) == 2 and n[faces[0]] @ n[faces[1]] < cos], n


def sharp_edge_points(V, F, step, angle=30.0, edges=None):
    """Points every `step` along the mesh's edges whose faces meet at more than `angle` degrees
    (`edges`: sharp_edges(V, F, angle)[0], if already made)."""
    pts = []
    for a, b, _, _ in sharp_edges(V, F, angle)[0] if edges is None else edges:
        length = np.linalg.norm(V[b] - V[a])
        m = max(1, int(np.ceil(length / step)))
        for s in (np.arange(m) + 0.5) / m:
            pts.append(V[a] + s * (V[b] - V[a]))
    return np.array(pts).reshape(-1, 3)


def mean_distance(points, mesh):
    """Mean unsigned distance from `points` to the closed mesh at `mesh` (sdfcontour eval-points)."""
    with tempfile.NamedTemporaryFile(suffix=".ply", delete=False) as f:
        header = (f"ply\nformat ascii 1.0\nelement vertex {len(points)}\n" +
                  "".join(f"property double {c}\n" for c in ("x", "y", "z", "nx", "ny", "nz")) +
                  "end_header\n")
        f.write(header.encode())
        for p in points:
            f.write(f"{p[0]!r} {p[1]!r} {p[2]!r} 0 0 1\n".encode())
    try:
        r = subprocess.run([CLI, "eval-points", f.name, mesh], capture_output=True, text=True)
        return json.loads(r.stdout)["abs_value"]["mean"] if r.returncode == 0 else None
    finally:
        os.unlink(f.name)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", default="32,64")
    ap.add_argument("--meshes", default="", help="comma-separated names (default: all shared)")
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--work", default=os.path.join(tempfile.gettempdir(), "sdfcontour-local"))
    ap.add_argument("--markdown", default="")
    ap.add_argument("--truncate", type=float, default=0,
                    help="sample the grids truncated at this many spacings (fast at 256^3); 0: exact")
    ap.add_argument("--variant", action="append", default=[], metavar="LABEL:OPTIONS",
                    help="one more method: gcp-local with these contour options (repeatable)")
    args = ap.parse_args()
    for v in args.variant:
        label, _, options = v.partition(":")
        if not label or label in METHODS:
            ap.error(f"--variant {v!r}: give a new label, then ':' and the options")
        METHODS[label] = METHODS["gcp-local"] + options.split()
    names = [m for m in args.meshes.split(",") if m] or sorted(
        f[:-4] for f in os.listdir(MESHES) if f.endswith(".obj"))
    methods = [m for m in args.methods.split(",") if m]  # --methods "": the variants alone
    methods += [v.partition(":")[0] for v in args.variant]
    os.makedirs(args.work, exist_ok=True)
    rows = []
    for res in [int(r) for r in args.res.split(",")]:
        h = 2.0 / (res - 1)
        for name in names:
            prefix = os.path.join(args.work, f"{name}{res}")
            if not os.path.exists(prefix + ".npy"):
                truncate = ["--truncate", str(args.truncate)] if args.truncate > 0 else []
                r = subprocess.run([CLI, "sample", os.path.join(MESHES, name + ".obj"), "--res",
                                    str(res), "-o", prefix, "--quiet", *truncate],
                                   capture_output=True, text=True)
                if r.returncode != 0:  # e.g. thinner than a spacing at this grid
                    print(json.dumps({"mesh": name, "res": res, "skipped": r.stderr.strip()}),
                          flush=True)
                    continue
            gt = prefix + "_mesh.ply"
            edge_points = sharp_edge_points(*read_ply(gt), step=h / 4)
            for method in methods:
                out = prefix + f"_{method}.ply"
                source = prefix + ".npy"
                if method.endswith("-vdb"):
                    source = prefix + ".vdb"
                    if not os.path.exists(source):
                        subprocess.run([CLI, "sample", os.path.join(MESHES, name + ".obj"),
                                        "--res", str(res), "-o", source, "--quiet"], check=True,
                                       capture_output=True)
                seconds, peak, _, err = timed([CLI, "contour", source, "-o", out, "--quiet",
                                               *METHODS[method]])
                row = {"mesh": name, "res": res, "method": method, "seconds": seconds,
                       "peak_mb": peak}
                if err is not None:
                    row["error"] = " ".join(err)
                elif (e := evaluate(CLI, out, gt)) is None:
                    row["error"] = "eval failed"
                else:
                    topo = e["recon_mesh"]
                    row.update(L1=e["L1"], Linf=e["L_inf"], triangles=topo["triangles"],
                               closed=topo["closed"], manifold=topo["manifold"],
                               self_intersections=topo["self_intersections"])
                    if len(edge_points):
                        d = mean_distance(edge_points, out)
                        row["edge_distance_h"] = d / h if d is not None else None
                rows.append(row)
                print(json.dumps(row), flush=True)
    if args.markdown:
        write_markdown(rows, methods, args.markdown)


def write_markdown(rows, methods, path):
    lines = ["# Local reconstruction: accuracy against MC, MT-RT and GCP-Poisson", "",
             "`/usr/bin/python3 bench/local.py` (bench/local.py). Ratios are to marching cubes' L1 "
             "on the same grid; geometric means over the meshes. Edge distance: the mean distance "
             "from points along the ground truth's sharp edges (dihedral > 30 degrees) to the "
             "method's mesh, in spacings.", ""]
    for res in sorted({r["res"] for r in rows}):
        at = [r for r in rows if r["res"] == res]
        mc = {r["mesh"]: r.get("L1") for r in at if r["method"] == "mc"}
        lines += [f"## {res}^3", "",
                  "| mesh | " + " | ".join(f"{m} L1 / MC" for m in methods) + " | " +
                  " | ".join(f"{m} edge (h)" for m in methods) + " |",
                  "|---" * (2 * len(methods) + 1) + "|"]
        ratios = {m: [] for m in methods}
        for name in sorted(mc):
            cells, edges = [], []
            for m in methods:
                r = next((x for x in at if x["mesh"] == name and x["method"] == m), {})
                ratio = r["L1"] / mc[name] if r.get("L1") and mc[name] else None
                if ratio:
                    ratios[m].append(ratio)
                flag = "" if r.get("closed", True) and r.get("manifold", True) else " (open)"
                if r.get("self_intersections"):
                    flag += f" ({r['self_intersections']} crossing)"
                cells.append(f"{ratio:.3f}{flag}" if ratio else "–")
                e = r.get("edge_distance_h")
                edges.append(f"{e:.3f}" if e is not None else "–")
            lines.append(f"| {name} | " + " | ".join(cells) + " | " + " | ".join(edges) + " |")
        lines.append("| **geometric mean** | " +
                     " | ".join(f"**{geomean(ratios[m]):.3f}**" for m in methods) + " |" +
                     " |" * len(methods))
        secs = {m: [r["seconds"] for r in at if r["method"] == m and r["seconds"]]
                for m in methods}
        lines += ["", "Median seconds: " + ", ".join(
            f"{m} {np.median(secs[m]):.2f}" for m in methods if secs[m]), ""]
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()

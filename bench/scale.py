"""GCP at scale: wall time, peak RSS and L1 of GCP, MT-RT, our MC and the peers' marching cubes
(scikit-image, OpenVDB's volume-to-mesh, VTK's flying edges) on the same grids, 64^3 to 512^3,
plus GCP on an OpenVDB level set against OpenVDB's own mesher on the same .vdb.

Every method runs in its own process (peak RSS is that process's); the peers' time is what they
spend loading the grid and contouring it (np.load + marching cubes, as a user would), ours is the
whole CLI run (reading, contouring and writing the PLY). Grids come from `sdfcontour sample`:
exact at <= 128^3, truncated at 8 spacings above (sampled block by block; marching cubes is
unaffected, GCP detects the truncation), all float32. L1 against the normalised mesh from
`sdfcontour eval`.

Methods: gcp (the default reconstruction: the local one on grids since session 20), gcp-local
(--reconstruction local, the same on grids), mt-rt, mc, and the peers skimage, openvdb, vtk; and
each --variant LABEL:OPTIONS, GCP with those contour options (e.g. fans:"--edge-fans on
--gradient lattice --band 2").

Usage: /usr/bin/python3 bench/scale.py [--res 64,128,256,512] [--meshes bunny,spot,armadillo]
       [--repeats 1] [--out docs/results/scale.md] [--work /tmp/sdfcontour_scale]
(docs/scale.md reads these tables against the issue's targets and keeps every session's
measurements; --out overwrites its file with this run's tables alone.)
With --repeats N every method runs N times per grid and the median time is reported (peak RSS:
the largest).
Needs Debian's python3-skimage, python3-openvdb and python3-vtk9.
"""
import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

from common import CLI, MESHES, evaluate, geomean, l1, over_peer, scale_grid, timed


def write_ply(path, v, f):
    v = np.ascontiguousarray(v, dtype="<f8")
    f = np.ascontiguousarray(f, dtype="<i4")
    with open(path, "wb") as out:
        out.write((f"ply\nformat binary_little_endian 1.0\nelement vertex {len(v)}\nproperty double x\n"
                   f"property double y\nproperty double z\nelement face {len(f)}\n"
                   "property list uchar int vertex_indices\nend_header\n").encode())
        rows = np.empty(len(f), dtype=[("n", "u1"), ("i", "<i4", 3)])
        rows["n"] = 3
        rows["i"] = f
        out.write(v.tobytes())
        out.write(rows.tobytes())


def peer(name, grid_path, out_path):
    """Runs one peer in this process; prints its seconds (load + contour, after the imports) as JSON."""
    if name.startswith("openvdb"):
        import pyopenvdb as vdb
    elif name == "skimage":
        from skimage.measure import marching_cubes
    elif name == "vtk":
        import vtk
        from vtk.util import numpy_support
    t = time.perf_counter()
    if name == "openvdb-vdb":
        grid = vdb.read(grid_path, vdb.readAllGridMetadata(grid_path)[0].name)
        points, tris, quads = grid.convertToPolygons(isovalue=0.0, adaptivity=0.0)
        seconds = time.perf_counter() - t
        faces = np.vstack([tris.reshape(-1, 3)[:, ::-1], quads[:, [2, 1, 0]], quads[:, [3, 2, 0]]])
        write_ply(out_path, points, faces)
        print(json.dumps({"seconds": seconds}))
        return
    a = np.load(grid_path)
    n = a.shape[0]
    h = 2 / (n - 1)
    if name == "skimage":
        v, f, _, _ = marching_cubes(a, 0.0, spacing=(h, h, h))
        seconds = time.perf_counter() - t
        write_ply(out_path, v - 1, f)
    elif name == "openvdb":
        grid = vdb.FloatGrid(background=float(np.abs(a).max()))
        grid.copyFromArray(a.astype(np.float32, copy=False))
        grid.transform = vdb.createLinearTransform([[h, 0, 0, 0], [0, h, 0, 0], [0, 0, h, 0], [-1, -1, -1, 1]])
        points, tris, quads = grid.convertToPolygons(isovalue=0.0, adaptivity=0.0)
        seconds = time.perf_counter() - t
        faces = np.vstack([tris.reshape(-1, 3), quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
        write_ply(out_path, points, faces)
    elif name == "vtk":
        image = vtk.vtkImageData()
        image.SetDimensions(*a.shape)
        image.SetSpacing(h, h, h)
        image.SetOrigin(-1, -1, -1)
        image.GetPointData().SetScalars(numpy_support.numpy_to_vtk(a.ravel(order="F"), deep=False))
        fe = vtk.vtkFlyingEdges3D()
        fe.SetInputData(image)
        fe.SetValue(0, 0.0)
        fe.ComputeNormalsOff()
        fe.ComputeGradientsOff()
        fe.Update()
        seconds = time.perf_counter() - t
        poly = fe.GetOutput()
        v = numpy_support.vtk_to_numpy(poly.GetPoints().GetData())
        f = numpy_support.vtk_to_numpy(poly.GetPolys().GetConnectivityArray()).reshape(-1, 3)
        write_ply(out_path, v, f)
    print(json.dumps({"seconds": seconds}))








def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", default=CLI)
    ap.add_argument("--res", default="64,128,256,512")
    ap.add_argument("--meshes", default="bunny,spot,armadillo")
    ap.add_argument("--methods", default="gcp,mt-rt,mc,skimage,openvdb,vtk")
    ap.add_argument("--mtrt-max", type=int, default=256, help="largest grid for MT-RT (global triangulation)")
    ap.add_argument("--vdb-res", default="128,256", help="resolutions of the .vdb comparison")
    ap.add_argument("--work", default="/tmp/sdfcontour_scale")
    ap.add_argument("--out", default=None)
    ap.add_argument("--repeats", type=int, default=1, help="runs per method and grid; the median time is kept")
    ap.add_argument("--variant", action="append", default=[], metavar="LABEL:OPTIONS",
                    help="one more method: GCP with these contour options (repeatable)")
    ap.add_argument("--peer", nargs=3, help=argparse.SUPPRESS)
    args = ap.parse_args()
    variants = dict(v.split(":", 1) for v in args.variant)
    args.methods = ",".join([args.methods, *variants]) if variants else args.methods
    if args.repeats < 1:
        ap.error("--repeats must be at least 1")
    if args.peer:
        return peer(*args.peer)
    os.makedirs(args.work, exist_ok=True)
    rows = []
    self_cmd = [sys.executable, os.path.abspath(__file__), "--peer"]
    for res in map(int, args.res.split(",")):
        for name in args.meshes.split(","):
            prefix = scale_grid(args.cli, args.work, name, res)
            gt = prefix + "_mesh.ply"
            for method in args.methods.split(","):
                if method == "mt-rt" and res > args.mtrt_max:
                    continue
                out = os.path.join(args.work, f"out_{method}.ply")
                times, rss, err = [], None, None
                for _ in range(args.repeats):
                    if method in ("gcp", "mt-rt", "mc", "gcp-local") or method in variants:
                        extra = variants.get(method, "--reconstruction local" if method == "gcp-local" else "")
                        cli_method = "gcp" if method in variants else method.split("-local")[0]
                        seconds, r, _, err = timed([args.cli, "contour", prefix + ".npy", "-o", out, "--method",
                                                    cli_method, "-q", *extra.split()])
                    else:
                        wall, r, stdout, err = timed([*self_cmd, method, prefix + ".npy", out])
                        seconds = json.loads(stdout)["seconds"] if wall is not None else None
                    if seconds is None:
                        break
                    times.append(seconds)
                    rss = max(rss or 0, r)
                # The median of the runs: one run's time moves by 10-30% with the machine's load.
                seconds = float(np.median(times)) if times and err is None else None
                e = evaluate(args.cli, out, gt) if seconds is not None else None
                topo = e["recon_mesh"] if e else {}
                row = {"mesh": name, "res": res, "method": method, "seconds": seconds, "runs": times, "rss_mb": rss,
                       "L1": e["L1"] if e else None, "L_inf": e["L_inf"] if e else None,
                       "triangles": topo.get("triangles"),
                       "closed": bool(topo.get("closed") and topo.get("manifold")
                                      and topo.get("self_intersections") == 0) if e else None, "error": err}
                rows.append(row)
                print(json.dumps(row), flush=True)
    vdb_rows = []
    for res in map(int, args.vdb_res.split(",")) if args.vdb_res else []:
        for name in args.meshes.split(","):
            path = os.path.join(args.work, f"{name}_{res}_ls.vdb")
            if not os.path.exists(path):
                subprocess.run([args.cli, "sample", os.path.join(MESHES, name + ".obj"), "--res", str(res), "-o", path,
                                "--half-width", "3", "-q"], check=True, stdout=subprocess.DEVNULL)
            gt = path[:-4] + "_mesh.ply"
            out = os.path.join(args.work, "out_vdb_gcp.ply")
            s, m, _, _ = timed([args.cli, "contour", path, "-o", out, "-q"])
            ours = l1(args.cli, out, gt)
            out = os.path.join(args.work, "out_vdb_openvdb.ply")
            wall, m2, stdout, _ = timed([*self_cmd, "openvdb-vdb", path, out])
            theirs = l1(args.cli, out, gt)
            vdb_rows.append({"mesh": name, "res": res, "gcp_seconds": s, "gcp_rss": m, "gcp_L1": ours,
                             "openvdb_seconds": json.loads(stdout)["seconds"], "openvdb_rss": m2,
                             "openvdb_L1": theirs})
            print(json.dumps(vdb_rows[-1]), flush=True)
    report(args, rows, vdb_rows)


def report(args, rows, vdb_rows):
    methods = args.methods.split(",")
    lines = ["| grid | method | time (s, mean) | time / scikit-image | peak RSS (MB, max) | L1 / MC's | "
             "L∞ / MC's | triangles / MC's |",
             "|---|---|---|---|---|---|---|---|"]
    for res in sorted({r["res"] for r in rows}):
        for method in methods:
            sel = [r for r in rows if r["res"] == res and r["method"] == method and r["seconds"] is not None]
            if not sel:
                failed = [r for r in rows if r["res"] == res and r["method"] == method]
                if failed:
                    lines.append(f"| {res}³ | {method} | failed: {failed[0]['error']} | | | | | |")
                continue
            t = np.mean([r["seconds"] for r in sel])
            tr = over_peer(rows, res, method, "seconds", "skimage")
            l1r, linfr, trir = (over_peer(rows, res, method, key, "mc") for key in ("L1", "L_inf", "triangles"))
            lines.append(f"| {res}³ | {method} | {t:.2f} | {tr:.2f} | {max(r['rss_mb'] for r in sel):.0f} | "
                         f"{l1r:.3f} | {linfr:.3f} | {trir:.2f} |")
    text = "\n".join(lines)
    if vdb_rows:
        text += ("\n\n| .vdb level set (half width 3) | GCP s | GCP MB | GCP L1 | OpenVDB s | OpenVDB MB | OpenVDB L1 | "
                 "L1 GCP / OpenVDB |\n|---|---|---|---|---|---|---|---|\n")
        for r in vdb_rows:
            text += (f"| {r['mesh']} {r['res']}³ | {r['gcp_seconds']:.2f} | {r['gcp_rss']:.0f} | {r['gcp_L1']:.3e} | "
                     f"{r['openvdb_seconds']:.2f} | {r['openvdb_rss']:.0f} | {r['openvdb_L1']:.3e} | "
                     f"{r['gcp_L1'] / r['openvdb_L1']:.3f} |\n")
        text += f"\nGeometric mean of L1 GCP / OpenVDB: {geomean([r['gcp_L1'] / r['openvdb_L1'] for r in vdb_rows]):.3f}\n"
    print(text)
    if args.out:
        with open(args.out, "w") as f:
            f.write("# GCP at scale: one run of the bench\n\n`/usr/bin/python3 bench/scale.py " + " ".join(sys.argv[1:]).replace(
                "--out " + args.out, "").strip() + "` on 2 cores; see the script's docstring for what is timed. "
                "Ratios are geometric means over the meshes; `docs/scale.md` reads them against the targets.\n\n" + text + "\n\n## Rows\n\n")
            f.write("| mesh | grid | method | s | MB | L1 | L∞ | triangles | closed |\n"
                    "|---|---|---|---|---|---|---|---|---|\n")
            for r in rows:
                def cell(key, spec):
                    return "-" if r.get(key) is None else format(r[key], spec)
                f.write(f"| {r['mesh']} | {r['res']}³ | {r['method']} | {cell('seconds', '.3f')} | "
                        f"{cell('rss_mb', '.0f')} | {cell('L1', '.3e')} | {cell('L_inf', '.3e')} | "
                        f"{cell('triangles', ',')} | {'-' if r.get('closed') is None else r['closed']} |\n")


if __name__ == "__main__":
    main()

"""Adaptivity (issue 39): GCP's local reconstruction merged with --adaptivity TOL, against the
same TOL-0 mesh decimated by CGAL's edge collapse with Garland-Heckbert plane quadrics (the
`decimate` bench program) to the same triangle count, and against OpenVDB's adaptive mesher (the
`vdb_mesher` bench program: tools::volumeToMesh of the same grid) with its adaptivity chosen by
bisection to give the nearest triangle count. Per mesh, grid and TOL: triangles, L1 to
the ground truth, the mean distance from points along its sharp edges (dihedral > 30 degrees),
in spacings, closedness and self-intersections. JSON lines on stdout; --markdown writes the
table.

    /usr/bin/python3 bench/adaptivity.py --res 128 --tol 0,0.05,0.1,0.25,0.5 --markdown docs/results/adaptivity.md
"""
import argparse
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import CLI, MESHES, evaluate, geomean, keep, timed  # noqa: E402
from local import mean_distance, read_ply, sharp_edge_points  # noqa: E402

DECIMATE = os.path.join(os.path.dirname(CLI), "bench", "decimate")
VDB_MESHER = os.path.join(os.path.dirname(CLI), "bench", "vdb_mesher")


def vdb_at_count(grid, out, triangles):
    """OpenVDB's mesh of `grid` into `out` with the adaptivity (bisected over [0, 1], 10 steps)
    whose triangle count is nearest `triangles`; returns (adaptivity, seconds of the last run)."""
    def run(adaptivity):
        seconds, _, stdout, err = timed([VDB_MESHER, grid, out, repr(adaptivity)])
        if err:
            raise SystemExit(" ".join(err))
        return int(stdout.strip()), seconds
    lo, hi, best = 0.0, 1.0, None
    for _ in range(10):
        mid = (lo + hi) / 2
        count, seconds = run(mid)
        if best is None or abs(count - triangles) < abs(best[1] - triangles):
            best = (mid, count)
        lo, hi = (mid, hi) if count > triangles else (lo, mid)
    count, seconds = run(best[0])
    return best[0], seconds



def sampled_mesh(work, name, res):
    """The grid of shared mesh `name` at res^3 in `work` (sampled if missing): (file prefix,
    ground-truth mesh, points along its sharp edges, spacing)."""
    h = 2.0 / (res - 1)
    prefix = os.path.join(work, f"{name}{res}")
    if not os.path.exists(prefix + ".npy"):
        subprocess.run([CLI, "sample", os.path.join(MESHES, name + ".obj"), "--res", str(res),
                        "-o", prefix, "--quiet"], check=True)
    gt = prefix + "_mesh.ply"
    return prefix, gt, sharp_edge_points(*read_ply(gt), step=h / 4), h


def add_case_arguments(ap, tol, meshes):
    """The grids (--res), tolerances (--tol), meshes, work folder and markdown file."""
    ap.add_argument("--res", default="128")
    ap.add_argument("--tol", default=tol)
    ap.add_argument("--meshes", default=meshes)
    ap.add_argument("--work", default=os.path.join(tempfile.gettempdir(), "sdfcontour-local"))
    ap.add_argument("--markdown", default="")


def cases(a):
    """(res, mesh name, TOL, file prefix, ground truth, sharp-edge points, spacing) for every
    grid, mesh and TOL the arguments name, each grid sampled once."""
    os.makedirs(a.work, exist_ok=True)
    for res in map(int, a.res.split(",")):
        for name in a.meshes.split(","):
            prefix, gt, edges, h = sampled_mesh(a.work, name, res)
            for tol in map(float, a.tol.split(",")):
                yield res, name, tol, prefix, gt, edges, h


def measure(out, gt, edge_points, h):
    e = evaluate(CLI, out, gt)
    if e is None:
        raise SystemExit(f"sdfcontour eval failed on {out}")
    topo = e["recon_mesh"]
    row = dict(L1=e["L1"], triangles=topo["triangles"], closed=topo["closed"],
               manifold=topo["manifold"], self_intersections=topo["self_intersections"])
    if len(edge_points):
        d = mean_distance(edge_points, out)
        row["edge_h"] = d / h if d is not None else None
    return row


def main():
    ap = argparse.ArgumentParser()
    add_case_arguments(ap, "0,0.05,0.1,0.25,0.5", "bunny,spot,wingnut,hammer,cube,armadillo")
    ap.add_argument("--no-openvdb", action="store_true")
    a = ap.parse_args()
    rows = []
    for res, name, tol, prefix, gt, edges, h in cases(a):
        out = f"{prefix}_adapt{tol:g}.ply"
        seconds, peak, _, err = timed([CLI, "contour", prefix + ".npy", "-o", out,
                                       "--quiet", "--reconstruction", "local",
                                       "--adaptivity", str(tol)])
        if err:
            raise SystemExit(" ".join(err))
        row = dict(mesh=name, res=res, tol=tol, method="adaptivity", seconds=seconds,
                   **measure(out, gt, edges, h))
        keep(rows, row)
        if tol == 0:
            full = out
            continue
        peer = f"{prefix}_decimated{tol:g}.ply"
        seconds, _, _, err = timed([DECIMATE, full, peer, str(row["triangles"])])
        if err:
            raise SystemExit(" ".join(err))
        row = dict(mesh=name, res=res, tol=tol, method="cgal-gh", seconds=seconds,
                   **measure(peer, gt, edges, h))
        keep(rows, row)
        if a.no_openvdb:
            continue
        vdb = f"{prefix}_vdb{tol:g}.ply"
        adaptivity, seconds = vdb_at_count(prefix + ".npy", vdb, row["triangles"])
        row = dict(mesh=name, res=res, tol=tol, method="openvdb", seconds=seconds,
                   vdb_adaptivity=adaptivity, **measure(vdb, gt, edges, h))
        keep(rows, row)
    if a.markdown:
        write_markdown(rows, a.markdown)


def write_markdown(rows, path):
    lines = ["# Adaptivity against decimation and OpenVDB's adaptive mesher", "",
             "`/usr/bin/python3 bench/adaptivity.py` (bench/adaptivity.py): GCP's local "
             "reconstruction with `--adaptivity TOL`; the TOL-0 mesh decimated by CGAL's "
             "edge collapse with Garland-Heckbert plane quadrics to the same triangle count (GH); "
             "OpenVDB's volumeToMesh of the same grid with the adaptivity that gives the nearest "
             "triangle count (VDB, its triangles in brackets). L1 to the ground truth as a ratio "
             "to TOL 0's; edge: mean distance from points along the ground truth's sharp edges, "
             "in spacings; crossings: self-intersecting triangle pairs.", ""]
    for res in sorted({r["res"] for r in rows}):
        lines += [f"## {res}^3", "",
                  "| mesh | TOL | triangles | / TOL 0 | L1 / TOL 0 | GH L1 / TOL 0 | "
                  "VDB L1 / TOL 0 | edge (h) | GH edge (h) | VDB edge (h) | crossings (ours / GH) "
                  "| seconds |",
                  "|---|---|---|---|---|---|---|---|---|---|---|---|"]
        at = [r for r in rows if r["res"] == res]
        ratios = {}
        for r in at:
            if r["method"] != "adaptivity":
                continue
            base = next(x for x in at if x["mesh"] == r["mesh"] and x["tol"] == 0)

            def peer_of(method):
                return next((x for x in at if x["mesh"] == r["mesh"] and x["tol"] == r["tol"] and
                             x["method"] == method), None)
            gh, vdb = peer_of("cgal-gh"), peer_of("openvdb")

            def edge(x):
                return f"{x['edge_h']:.3f}" if x and x.get("edge_h") is not None else "–"

            def l1(x):
                return x["L1"] / base["L1"] if x else None

            def text(v):
                return "–" if v is None else f"{v:.3f}"
            ratios.setdefault(r["tol"], []).append(
                (base["triangles"] / r["triangles"], l1(r), l1(gh), l1(vdb)))
            vdb_text = text(l1(vdb)) + (f" ({vdb['triangles']:,})" if vdb else "")
            lines.append(
                f"| {r['mesh']} | {r['tol']:g} | {r['triangles']:,} | "
                f"{base['triangles'] / r['triangles']:.1f}x fewer | {text(l1(r))} | "
                f"{text(l1(gh))} | {vdb_text} | {edge(r)} | {edge(gh)} | {edge(vdb)} | "
                f"{r['self_intersections']} / {gh['self_intersections'] if gh else '–'} | "
                f"{r['seconds']:.1f} |")
        lines += ["", "| TOL | geometric mean: fewer triangles | L1 / TOL 0 | GH L1 / TOL 0 | "
                  "VDB L1 / TOL 0 |", "|---|---|---|---|---|"]
        for tol, v in sorted(ratios.items()):
            def mean(k):
                got = [x[k] for x in v if x[k] is not None]
                return f"{geomean(got):.3f}" if got else "–"
            lines.append(f"| {tol:g} | {geomean([x[0] for x in v]):.1f}x | {mean(1)} | "
                         f"{mean(2)} | {mean(3)} |")
        lines.append("")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()

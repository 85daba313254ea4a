"""Adaptivity (issue 39): GCP's local reconstruction merged with --adaptivity TOL, against the
same TOL-0 mesh decimated by CGAL's edge collapse with Garland-Heckbert plane quadrics (the
`decimate` bench program) to the same triangle count. Per mesh, grid and TOL: triangles, L1 to
the ground truth, the mean distance from points along its sharp edges (dihedral > 30 degrees),
in spacings, closedness and self-intersections. JSON lines on stdout; --markdown writes the
table.

    /usr/bin/python3 bench/adaptivity.py --res 128 --tol 0,0.05,0.1,0.25,0.5 --markdown docs/results/adaptivity.md
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import CLI, MESHES, geomean, timed  # noqa: E402
from local import mean_distance, read_ply, sharp_edge_points  # noqa: E402

DECIMATE = os.path.join(os.path.dirname(CLI), "bench", "decimate")


def evaluate(out, gt, edge_points, h):
    e = json.loads(subprocess.run([CLI, "eval", out, gt], capture_output=True, text=True).stdout)
    topo = e["recon_mesh"]
    row = dict(L1=e["L1"], triangles=topo["triangles"], closed=topo["closed"],
               manifold=topo["manifold"], self_intersections=topo["self_intersections"])
    if len(edge_points):
        d = mean_distance(edge_points, out)
        row["edge_h"] = d / h if d is not None else None
    return row


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--res", default="128")
    ap.add_argument("--tol", default="0,0.05,0.1,0.25,0.5")
    ap.add_argument("--meshes", default="bunny,spot,wingnut,hammer,cube,armadillo")
    ap.add_argument("--work", default=os.path.join(tempfile.gettempdir(), "sdfcontour-local"))
    ap.add_argument("--markdown", default="")
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    rows = []
    for res in map(int, a.res.split(",")):
        h = 2.0 / (res - 1)
        for name in a.meshes.split(","):
            prefix = os.path.join(a.work, f"{name}{res}")
            if not os.path.exists(prefix + ".npy"):
                subprocess.run([CLI, "sample", os.path.join(MESHES, name + ".obj"), "--res",
                                str(res), "-o", prefix, "--quiet"], check=True)
            gt = prefix + "_mesh.ply"
            edges = sharp_edge_points(*read_ply(gt), step=h / 4)
            for tol in map(float, a.tol.split(",")):
                out = f"{prefix}_adapt{tol:g}.ply"
                seconds, peak, _, err = timed([CLI, "contour", prefix + ".npy", "-o", out,
                                               "--quiet", "--reconstruction", "local",
                                               "--adaptivity", str(tol)])
                if err:
                    raise SystemExit(" ".join(err))
                row = dict(mesh=name, res=res, tol=tol, method="adaptivity", seconds=seconds,
                           **evaluate(out, gt, edges, h))
                rows.append(row)
                print(json.dumps(row), flush=True)
                if tol == 0:
                    full = out
                    continue
                peer = f"{prefix}_decimated{tol:g}.ply"
                seconds, _, _, err = timed([DECIMATE, full, peer, str(row["triangles"])])
                if err:
                    raise SystemExit(" ".join(err))
                row = dict(mesh=name, res=res, tol=tol, method="cgal-gh", seconds=seconds,
                           **evaluate(peer, gt, edges, h))
                rows.append(row)
                print(json.dumps(row), flush=True)
    if a.markdown:
        write_markdown(rows, a.markdown)


def write_markdown(rows, path):
    lines = ["# Adaptivity against decimation", "",
             "`/usr/bin/python3 bench/adaptivity.py` (bench/adaptivity.py): GCP's local "
             "reconstruction with `--adaptivity TOL`, and the TOL-0 mesh decimated by CGAL's "
             "edge collapse with Garland-Heckbert plane quadrics to the same triangle count. "
             "L1 to the ground truth as a ratio to TOL 0's; edge: mean distance from points "
             "along the ground truth's sharp edges, in spacings.", ""]
    for res in sorted({r["res"] for r in rows}):
        lines += [f"## {res}^3", "",
                  "| mesh | TOL | triangles | / TOL 0 | L1 / TOL 0 | CGAL GH L1 / TOL 0 | "
                  "edge (h) | CGAL GH edge (h) | crossings | seconds |",
                  "|---|---|---|---|---|---|---|---|---|---|"]
        at = [r for r in rows if r["res"] == res]
        ratios = {}
        for r in at:
            if r["method"] != "adaptivity":
                continue
            base = next(x for x in at if x["mesh"] == r["mesh"] and x["tol"] == 0)
            peer = next((x for x in at if x["mesh"] == r["mesh"] and x["tol"] == r["tol"] and
                         x["method"] == "cgal-gh"), None)

            def edge(x):
                return f"{x['edge_h']:.3f}" if x and x.get("edge_h") is not None else "–"
            ratio = r["L1"] / base["L1"]
            peer_ratio = peer["L1"] / base["L1"] if peer else None
            ratios.setdefault(r["tol"], []).append(
                (base["triangles"] / r["triangles"], ratio, peer_ratio))
            lines.append(
                f"| {r['mesh']} | {r['tol']:g} | {r['triangles']:,} | "
                f"{base['triangles'] / r['triangles']:.1f}x fewer | {ratio:.3f} | "
                f"{'–' if peer_ratio is None else f'{peer_ratio:.3f}'} | {edge(r)} | "
                f"{edge(peer)} | {r['self_intersections']} | {r['seconds']:.1f} |")
        lines += ["", "| TOL | geometric mean: fewer triangles | L1 / TOL 0 | CGAL GH L1 / TOL 0 |",
                  "|---|---|---|---|"]
        for tol, v in sorted(ratios.items()):
            peers = [p for _, _, p in v if p is not None]
            peer = f"{geomean(peers):.3f}" if peers else "–"
            lines.append(f"| {tol:g} | {geomean([x for x, _, _ in v]):.1f}x | "
                         f"{geomean([y for _, y, _ in v]):.3f} | {peer} |")
        lines.append("")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()

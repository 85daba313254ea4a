"""Contact points from the grid's lattice against the regular triangulation's, on the shared
meshes: the points' distance to the true surface (median, 95th percentile, in spacings), how many
are kept, the local reconstruction's L1 and its time, for `--gradient regular` and
`--gradient lattice`, measured in the same run.

    /usr/bin/python3 bench/lattice_points.py --res 32,64,128 --out docs/results/lattice_points.md

Each gradient runs with its own defaults: the lattice's tie tolerance is 1e-3 and, from 128
samples per axis, its band 6 spacings. `--lattice-options` adds options to the lattice's runs
alone: `--lattice-options "--tie-tolerance 1e-6 --band 8"` gives it the triangulation's.
"""
import argparse
import json
import subprocess
import tempfile

from common import CLI, geomean, keep, l1, mesh_names, report, sample_shared_mesh, timed

GRADIENTS = ("regular", "lattice")


def eval_points(points, gt):
    r = subprocess.run([CLI, "eval-points", points, gt], capture_output=True, text=True, check=True)
    return json.loads(r.stdout)


def run_one(prefix, gradient, h, extra=()):
    out = f"{prefix}_{gradient}"
    wall, rss, _, err = timed([CLI, "contour", prefix + ".npy", "-o", out + ".ply", "--points",
                               out + "_cp.ply", "--gradient", gradient, "--stats", out + ".json",
                               "-q", *extra])
    if err:
        return {"error": " ".join(err)}
    stats = json.load(open(out + ".json"))
    e = eval_points(out + "_cp.ply", prefix + "_mesh.ply")
    local = stats.get("local_seconds", {})
    return {"seconds": wall, "rss_mb": rss, "points": e["count"],
            "median_h": e["abs_value"]["median"] / h, "p95_h": e["abs_value"]["p95"] / h,
            "L1": l1(CLI, out + ".ply", prefix + "_mesh.ply"),
            "contact_seconds": local.get("contact points")}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", default="32,64,128")
    ap.add_argument("--meshes", default="")
    ap.add_argument("--out", default="")
    ap.add_argument("--lattice-options", default="", help="more options for the lattice's runs")
    a = ap.parse_args()
    extra = {"regular": (), "lattice": tuple(a.lattice_options.split())}
    names = mesh_names(a.meshes)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for res in [int(r) for r in a.res.split(",")]:
            h = 2.0 / (res - 1)
            for name in names:
                try:
                    prefix = sample_shared_mesh(name, res, tmp)
                except subprocess.CalledProcessError:  # thinner than a spacing: no grid
                    continue
                row = {"mesh": name, "res": res}
                for g in GRADIENTS:
                    row[g] = run_one(prefix, g, h, extra[g])
                keep(rows, row)
    lines = ["# Contact points: the grid's lattice against the regular triangulation", "",
             "`" + " ".join(["/usr/bin/python3 bench/lattice_points.py", "--res", a.res] +
                            (["--meshes", a.meshes] if a.meshes else []) +
                            ([f'--lattice-options "{a.lattice_options}"']
                             if a.lattice_options else [])) + "` (2 cores).", "",
             "Distances of the contact points to the true surface in spacings h (median, p95), "
             "points kept, the local reconstruction's L1 and wall time; ratios lattice / regular, "
             "geometric means over the meshes.", "",
             "| grid | meshes | median ratio | p95 ratio | points ratio | L1 ratio | time ratio | "
             "contact-point time ratio |", "|---|---|---|---|---|---|---|---|"]
    for res in sorted({r["res"] for r in rows}):
        ok = [r for r in rows if r["res"] == res and all("error" not in r[g] for g in GRADIENTS)]

        def ratio(key):
            return geomean([r["lattice"][key] / r["regular"][key] for r in ok
                            if r["lattice"][key] and r["regular"][key]])
        lines.append(f"| {res}³ | {len(ok)} | {ratio('median_h'):.3f} | {ratio('p95_h'):.3f} | "
                     f"{ratio('points'):.3f} | {ratio('L1'):.3f} | {ratio('seconds'):.3f} | "
                     f"{ratio('contact_seconds'):.3f} |")
    lines += ["", "| mesh | grid | regular median / p95 (h) | lattice median / p95 (h) | points "
              "regular / lattice | L1 regular / lattice | s regular / lattice |",
              "|---|---|---|---|---|---|---|"]
    for r in rows:
        g, t = r["regular"], r["lattice"]
        if "error" in g or "error" in t:
            lines.append(f"| {r['mesh']} | {r['res']}³ | {g.get('error', '')} | "
                         f"{t.get('error', '')} | | | |")
            continue
        lines.append(f"| {r['mesh']} | {r['res']}³ | {g['median_h']:.4f} / {g['p95_h']:.4f} | "
                     f"{t['median_h']:.4f} / {t['p95_h']:.4f} | {g['points']} / {t['points']} | "
                     f"{g['L1']:.3e} / {t['L1']:.3e} | {g['seconds']:.2f} / {t['seconds']:.2f} |")
    report("\n".join(lines) + "\n", a.out)


if __name__ == "__main__":
    main()

"""What the narrow band costs and changes: GCP with --band K against --band all (the paper's,
every sample triangulated), measured in the same run on grids of the shared meshes.

For each mesh and resolution: samples kept, wall time, peak RSS and L1 against the normalised
mesh, and the ratios to --band all. Writes a Markdown table (and the raw rows as JSON).

Usage: /usr/bin/python3 bench/band.py [--cli build/sdfcontour] [--meshes bunny,spot,...]
       [--res 64,128] [--bands 2,3,4,6,all] [--out docs/band.md]
"""
import argparse
import json
import os
import subprocess
import tempfile

from common import CLI, MESHES, geomean, l1, timed








def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", default=CLI)
    ap.add_argument("--meshes", default="bunny,spot,armadillo,koala_lowres,wingnut,hammer")
    ap.add_argument("--res", default="64,128")
    ap.add_argument("--bands", default="2,3,4,6,all")
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    bands = args.bands.split(",")
    if "all" not in bands:
        bands.append("all")
    rows = []
    with tempfile.TemporaryDirectory() as d:
        for res in map(int, args.res.split(",")):
            for name in args.meshes.split(","):
                prefix = os.path.join(d, f"{name}_{res}")
                subprocess.run([args.cli, "sample", os.path.join(MESHES, name + ".obj"), "--res", str(res),
                                "-o", prefix, "-q"], check=True, stdout=subprocess.DEVNULL)
                for band in bands:
                    out = os.path.join(d, "m.ply")
                    stats = os.path.join(d, "s.json")
                    t, rss, _, err = timed([args.cli, "contour", prefix + ".npy", "-o", out, "--band", band, "-q",
                                       "--stats", stats])
                    if t is None:
                        raise RuntimeError(f"{name} {res} band {band} failed: {err}")
                    s = json.load(open(stats))
                    if "fallback" in s:  # GCP fell back to marching cubes: no band to compare
                        print(f"{name} {res} band {band}: {s['fallback']['reason']}", flush=True)
                        continue
                    rows.append({"mesh": name, "res": res, "band": band, "seconds": t, "rss_mb": rss,
                                 "samples": s["band"]["samples"], "kept": s["contact_points"]["kept"],
                                 "L1": l1(args.cli, out, prefix + "_mesh.ply")})
                    print(json.dumps(rows[-1]), flush=True)
    lines = ["| grid | band | samples triangulated (%) | L1 / all (geomean) | worst L1 / all | time / all | "
             "peak RSS / all |", "|---|---|---|---|---|---|---|"]
    for res in sorted({r["res"] for r in rows}):
        ref = {r["mesh"]: r for r in rows if r["res"] == res and r["band"] == "all"}
        for band in bands:
            sel = [r for r in rows if r["res"] == res and r["band"] == band and r["mesh"] in ref]
            ratio = lambda key: [r[key] / ref[r["mesh"]][key] for r in sel]
            if not sel:
                continue
            frac = 100 * sum(r["samples"] for r in sel) / (len(sel) * res**3)
            lines.append(f"| {res}³ | {band} | {frac:.1f} | {geomean(ratio('L1')):.3f} | {max(ratio('L1')):.3f} | "
                         f"{geomean(ratio('seconds')):.2f} | {geomean(ratio('rss_mb')):.2f} |")
    table = "\n".join(lines)
    print(table)
    if args.out:
        with open(args.out, "w") as f:
            f.write("# The narrow band: GCP with `--band K` against `--band all`\n\n")
            f.write(f"`/usr/bin/python3 bench/band.py --meshes {args.meshes} --res {args.res} --bands {args.bands}`; "
                    "2 cores, default Poisson (depth 8, α = 10); ratios are geometric means over the meshes, "
                    "each against `--band all` on the same grid in the same run.\n\n")
            f.write(table + "\n\n## Rows\n\n| mesh | grid | band | samples | contact points | s | MB | L1 |\n"
                    "|---|---|---|---|---|---|---|---|\n")
            for r in rows:
                f.write(f"| {r['mesh']} | {r['res']}³ | {r['band']} | {r['samples']} | {r['kept']} | "
                        f"{r['seconds']:.2f} | {r['rss_mb']:.0f} | {r['L1']:.3e} |\n")


if __name__ == "__main__":
    main()

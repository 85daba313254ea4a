"""Grid samples on the wrong side of GCP's mesh (issue: GCP accuracy): for each shared mesh at
N^3, contour its SDF grid with GCP, sample the mesh's own signed distance at the same grid
points, and count the samples whose sign differs (and how deep the deepest lies, in spacings).

Needs the Python module (python3 -m venv --system-site-packages env && env/bin/pip install
--no-build-isolation .); run with that interpreter:
    env/bin/python bench/wrong_side.py [--res 32,64] [--meshes bunny,spot]
        [--variants=';--sign-trigger 0;--no-sign-constraints']

With --variants (extra `contour` options per variant, separated by ';'), each grid is contoured once per variant (extra `contour` options) and the table
gives, per variant, the wrong-side count and L1 to the mesh (`sdfcontour eval`), then per grid
size the total wrong-side samples and the geometric mean of L1 against the first variant
(fallbacks to marching cubes, `FB`, left out).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

import sdfcontour

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import CLI, MESHES, geomean, l1  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", default="32,64")
    ap.add_argument("--meshes", default="")
    ap.add_argument("--variants", default=None)
    args = ap.parse_args()
    names = args.meshes.split(",") if args.meshes else sorted(
        f[:-4] for f in os.listdir(MESHES) if f.endswith(".obj"))
    variants = args.variants.split(";") if args.variants is not None else None
    if variants is None:
        print("| mesh | grid | samples on the wrong side | deepest (h) |\n|---|---|---|---|")
    else:
        print("| mesh | grid | " + " | ".join(f"`{v}` wrong, L1" for v in variants) + " |")
        print("|---|---|" + "---|" * len(variants))
    with tempfile.TemporaryDirectory() as tmp:
        for n in (int(r) for r in args.res.split(",")):
            totals = {v: 0 for v in variants or []}
            ratios = {v: [] for v in variants or []}
            for name in names:
                prefix = os.path.join(tmp, name)
                r = subprocess.run([CLI, "sample", os.path.join(MESHES, name + ".obj"), "--res",
                                    str(n), "-o", prefix, "--quiet"], capture_output=True, text=True)
                if r.returncode != 0:  # e.g. a shape thinner than a spacing
                    print(f"| {name} | {n}³ | no grid: {r.stderr.strip()} |", flush=True)
                    continue
                grid = np.load(prefix + ".npy")
                h = 2.0 / (n - 1)
                cells = []
                first = None
                for v in variants if variants is not None else [""]:
                    out = prefix + "_gcp.ply"
                    stats = prefix + "_stats.json"
                    subprocess.run([CLI, "contour", prefix + ".npy", "-o", out, "--quiet",
                                    "--stats", stats] + v.split(), check=True, capture_output=True)
                    with open(stats) as f:
                        fell_back = bool(json.load(f).get("fallback"))
                    V, F = sdfcontour.read_mesh(out)
                    own = sdfcontour.sample(V, F, resolution=n, scale=None)
                    wrong = (np.sign(own) != np.sign(grid)) & (grid != 0)
                    deepest = np.abs(grid[wrong]).max() / h if wrong.any() else 0.0
                    if variants is None:
                        print("| %s | %d³ | %d | %.3f |" % (name, n, wrong.sum(), deepest),
                              flush=True)
                        continue
                    if fell_back:
                        cells.append("FB")
                        continue
                    dist = l1(CLI, out, prefix + "_mesh.ply")
                    totals[v] += int(wrong.sum())
                    first = dist if first is None else first
                    if v != variants[0] and first and dist:
                        ratios[v].append(dist / first)
                    cells.append("%d, %.3e" % (wrong.sum(), dist))
                if variants is not None:
                    print("| %s | %d³ | %s |" % (name, n, " | ".join(cells)), flush=True)
            for v in variants or []:
                print(f"\n{n}³ `{v}`: {totals[v]} wrong-side samples; L1 / first "
                      f"{geomean(ratios[v]) if ratios[v] else 1.0:.4f}")

if __name__ == "__main__":
    main()

"""Grid samples on the wrong side of GCP's mesh (issue: GCP accuracy): for each shared mesh at
N^3, contour its SDF grid with GCP, sample the mesh's own signed distance at the same grid
points, and count the samples whose sign differs (and how deep the deepest lies, in spacings).

Needs the Python module (python3 -m venv --system-site-packages env && env/bin/pip install
--no-build-isolation .); run with that interpreter:
    env/bin/python bench/wrong_side.py [--res 32,64] [--meshes bunny,spot]
"""
import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np

import sdfcontour

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import CLI, MESHES  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", default="32,64")
    ap.add_argument("--meshes", default="")
    args = ap.parse_args()
    names = args.meshes.split(",") if args.meshes else sorted(
        f[:-4] for f in os.listdir(MESHES) if f.endswith(".obj"))
    print("| mesh | grid | samples on the wrong side | deepest (h) |\n|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for n in (int(r) for r in args.res.split(",")):
            for name in names:
                prefix = os.path.join(tmp, name)
                subprocess.run([CLI, "sample", os.path.join(MESHES, name + ".obj"), "--res",
                                str(n), "-o", prefix, "--quiet"], check=True, capture_output=True)
                grid = np.load(prefix + ".npy")
                out = prefix + "_gcp.ply"
                subprocess.run([CLI, "contour", prefix + ".npy", "-o", out, "--quiet"],
                               check=True, capture_output=True)
                V, F = sdfcontour.read_mesh(out)
                own = sdfcontour.sample(V, F, resolution=n)
                wrong = (np.sign(own) != np.sign(grid)) & (grid != 0)
                h = 2.0 / (n - 1)
                deepest = np.abs(grid[wrong]).max() / h if wrong.any() else 0.0
                print("| %s | %d³ | %d | %.3f |" % (name, n, wrong.sum(), deepest), flush=True)


if __name__ == "__main__":
    main()

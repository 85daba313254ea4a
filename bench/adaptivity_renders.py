"""Renders for docs/adaptivity.md: GCP's local reconstruction of one organic and one CAD mesh
at TOL 0 and with --adaptivity, and the TOL-0 mesh decimated by CGAL's Garland-Heckbert edge
collapse to the same triangle count, edges drawn, each titled with its triangles and L1 to the
ground truth (VTK, bench/vtk_render.py; runs itself under xvfb-run where there is no display).

    /usr/bin/python3 bench/adaptivity_renders.py [--meshes bunny,wingnut] [--res 32] [--tol 0.25]
        [--out docs/img/adaptivity_renders.png]

(with the sdfcontour package importable: installed, or on PYTHONPATH)
"""
import argparse
import os
import subprocess
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from common import CLI, sample_shared_mesh  # noqa: E402
from vtk_render import ensure_display, render  # noqa: E402

import sdfcontour  # noqa: E402

DECIMATE = os.path.join(os.path.dirname(CLI), "bench", "decimate")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", default="bunny,wingnut")
    ap.add_argument("--res", type=int, default=32)
    ap.add_argument("--tol", type=float, default=0.25)
    ap.add_argument("--out", default=os.path.join(HERE, "..", "docs", "img",
                                                  "adaptivity_renders.png"))
    args = ap.parse_args()
    ensure_display()
    names = args.meshes.split(",")
    fig = plt.figure(figsize=(12, 4.1 * len(names)), dpi=100)
    for row, name in enumerate(names):
        with tempfile.TemporaryDirectory() as d:
            prefix = sample_shared_mesh(name, args.res, d)
            gt = sdfcontour.read_mesh(prefix + "_mesh.ply")
            meshes = []
            for tol in (0.0, args.tol):
                out = f"{prefix}_{tol:g}.ply"
                subprocess.run([CLI, "contour", prefix + ".npy", "-o", out, "-q",
                                "--reconstruction", "local", "--adaptivity", str(tol)],
                               check=True)
                meshes.append((f"TOL {tol:g}", sdfcontour.read_mesh(out)))
            peer = prefix + "_decimated.ply"
            subprocess.run([DECIMATE, f"{prefix}_0.ply", peer, str(len(meshes[1][1][1]))],
                           check=True)
            meshes.append(("CGAL GH decimation", sdfcontour.read_mesh(peer)))
        for col, (label, (V, F)) in enumerate(meshes):
            l1 = sdfcontour.distances(V, F, *gt, samples=100000)["L1"]
            ax = fig.add_subplot(len(names), len(meshes), row * len(meshes) + col + 1)
            ax.imshow(render(V, F, azimuth=-35.0, elevation=25.0, zoom=1.25, edges=True))
            ax.set_axis_off()
            ax.set_title(f"{name} {args.res}³, {label}: {len(F):,} triangles, L1 {l1:.1e}",
                         fontsize=9)
            print(name, label, len(F), l1, flush=True)
    fig.tight_layout()
    fig.savefig(args.out)


if __name__ == "__main__":
    main()

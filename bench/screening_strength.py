"""How strongly each implementation's screening holds the surface to the points, at the same alpha.

Points on a sphere of radius 0.6 carry the normals of a 1.3 : 1 : 1/1.3 ellipsoid, so the normal
field asks for an ellipsoid while the positions ask for the sphere. Plain Poisson follows the
normals; the stronger the screening, the rounder the result. We report the residual anisotropy
(RMS x minus RMS z of the surface, area-weighted, in thousandths of the radius) for ours at several
alpha, MeshLab (Kazhdan's code, degree 2) at alpha 2 and 8, and Open3D (degree 1, alpha fixed at 2).

Usage: /usr/bin/python3 bench/screening_strength.py [--cli build/sdfcontour] [--depths 6,7,8]
       [--degree 1|2] [--alphas 1,2,3,4,6,8]
"""
import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np
import open3d as o3d

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import poisson_compare  # noqa: E402  (its MeshLab filter script)


def anisotropy(path):
    m = o3d.io.read_triangle_mesh(path)
    v, f = np.asarray(m.vertices), np.asarray(m.triangles)
    c = (v[f[:, 0]] + v[f[:, 1]] + v[f[:, 2]]) / 3
    a = np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1)
    rms = lambda x: np.sqrt((a * x * x).sum() / a.sum())  # noqa: E731
    return 1e3 * (rms(c[:, 0]) - rms(c[:, 2])) / 0.6


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cli", default=os.path.join(HERE, "..", "build", "sdfcontour"))
    ap.add_argument("--depths", default="6,7,8")
    ap.add_argument("--degree", default="1", help="our elements' degree (MeshLab's are 2)")
    ap.add_argument("--alphas", default="1,2,3,4,6,8", help="our screening weights")
    args = ap.parse_args()
    n = 60000
    i = np.arange(n)
    z = 1 - (2 * i + 1) / n
    r = np.sqrt(1 - z * z)
    phi = i * np.pi * (3 - np.sqrt(5))
    u = np.stack([r * np.cos(phi), r * np.sin(phi), z], 1)
    normals = u * np.array([1 / 1.3**2, 1.0, 1.3**2])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    with tempfile.TemporaryDirectory() as d:
        pts = os.path.join(d, "points.ply")
        cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(0.6 * u))
        cloud.normals = o3d.utility.Vector3dVector(normals)
        o3d.io.write_point_cloud(pts, cloud)
        out = os.path.join(d, "out.ply")
        alphas = [float(a) for a in args.alphas.split(",")]
        print("| depth | Open3D (alpha 2) | MeshLab alpha 2 | MeshLab alpha 8 | ours (degree %s) alpha %s |"
              % (args.degree, " / ".join(args.alphas.split(","))))
        print("|---|---|---|---|---|")
        for depth in map(int, args.depths.split(",")):
            subprocess.run([sys.executable, os.path.join(HERE, "open3d_poisson.py"), pts, out, str(depth)],
                           check=True, capture_output=True)
            row = [f"{anisotropy(out):.3f}"]
            for alpha in (2, 8):
                mlx = os.path.join(d, "poisson.mlx")
                open(mlx, "w").write(poisson_compare.MLX.format(depth=depth, alpha=alpha))
                subprocess.run(["xvfb-run", "-a", "meshlabserver", "-i", pts, "-o", out, "-s", mlx],
                               check=True, capture_output=True, cwd=d)
                row.append(f"{anisotropy(out):.3f}")
            ours = []
            for alpha in alphas:
                subprocess.run([args.cli, "poisson", pts, "-o", out, "--depth", str(depth), "--alpha", str(alpha),
                                "--degree", args.degree, "-q"],
                               check=True, capture_output=True)
                ours.append(f"{anisotropy(out):.3f}")
            print(f"| {depth} | " + " | ".join(row) + " | " + " / ".join(ours) + " |", flush=True)


if __name__ == "__main__":
    main()

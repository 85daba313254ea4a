"""Open3D's screened Poisson (Kazhdan's code; point weight fixed at 2, Neumann, degree 1) as a
separate process, so that its wall time and peak memory compare with ours.

Usage: /usr/bin/python3 bench/open3d_poisson.py POINTS.ply OUT.ply DEPTH [SCALE]
"""
import sys

import open3d as o3d

points = o3d.io.read_point_cloud(sys.argv[1])
depth, scale = int(sys.argv[3]), float(sys.argv[4]) if len(sys.argv) > 4 else 1.1
mesh, _ = o3d.geometry.TriangleMesh.create_from_point_cloud_poisson(points, depth=depth, scale=scale, linear_fit=False)
o3d.io.write_triangle_mesh(sys.argv[2], mesh)

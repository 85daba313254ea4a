"""Marching cubes by scikit-image, the reference for our own: grid.npy -> verts.npy, faces.npy.

Usage: skimage_mc.py GRID.npy SPACING MIN VERTS_OUT.npy FACES_OUT.npy
"""
import sys

import numpy as np
from skimage.measure import marching_cubes

grid = np.load(sys.argv[1])
spacing, origin = float(sys.argv[2]), float(sys.argv[3])
verts, faces, _, _ = marching_cubes(grid, level=0.0, spacing=(spacing,) * 3, method="lewiner")
np.save(sys.argv[4], (verts + origin).astype(np.float64))
np.save(sys.argv[5], faces.astype(np.float64))

"""Where a mesh's distance to the ground truth lies: points spread over each mesh's area, their
exact distance to the ground truth (`sdfcontour eval-points`), binned by their distance from the
ground truth's sharp edges (dihedral > 30 degrees) and, away from those, by how far the ground
truth's facets turn within two spacings (a polyhedron's facets at the spacing's scale).

    /usr/bin/python3 bench/where_error.py GT_mesh.ply 256 default.ply variant.ply

Per mesh and bin: the share of the area, the mean distance in spacings, and the bin's share of
the mesh's summed distance (the one-sided L1 from the mesh to the ground truth)."""
import os
import sys

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from local import (area_samples, mean_distance, read_ply, sharp_edge_points,  # noqa: E402
                   sharp_edges)

EDGE_BINS = [(0, 0.5), (0.5, 1), (1, 2), (2, 4)]  # spacings from the nearest sharp edge
TURN_BINS = [(0, 3), (3, 10), (10, 30), (30, 180)]  # degrees, beyond 4 spacings from any edge
SAMPLES = 100000


def facet_turn(points, V, F, n, h):
    """Per point: the largest turn (degrees) between the ground truth's facet nearest it and the
    facets among its 16 nearest (by centroid) within two spacings; `n`: the facets' unit normals."""
    dist, idx = cKDTree(V[F].mean(axis=1)).query(points, k=min(16, len(F)))
    cos = np.einsum("ij,ikj->ik", n[idx[:, 0]], n[idx])
    cos[dist > 2 * h] = 1
    return np.degrees(np.arccos(np.clip(cos.min(axis=1), -1, 1)))


def main():
    gt, res, meshes = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
    if not meshes:
        sys.exit(__doc__)
    h = 2.0 / (res - 1)
    GV, GF = read_ply(gt)
    sharp, normals = sharp_edges(GV, GF)
    edges = sharp_edge_points(GV, GF, step=h / 8, edges=sharp)
    tree = cKDTree(edges) if len(edges) else None
    for path in meshes:
        P = area_samples(*read_ply(path), count=SAMPLES)
        to_edge = tree.query(P)[0] / h if tree else np.full(len(P), np.inf)
        turn = facet_turn(P, GV, GF, normals, h)
        bins = [(f"edge {lo}-{hi} h", (to_edge >= lo) & (to_edge < hi)) for lo, hi in EDGE_BINS]
        bins += [(f"far, turn {lo}-{hi} deg", (to_edge >= 4) & (turn >= lo) & (turn < hi))
                 for lo, hi in TURN_BINS]
        rows, total = [], 0.0
        for name, mask in bins:
            mean = mean_distance(P[mask], gt) / h if mask.any() else 0.0
            rows.append((name, mask.mean(), mean))
            total += mask.mean() * mean
        print(f"{os.path.basename(path)}: {total:.5f} h from the ground truth on average")
        print("| bin | area | mean (h) | share of the distance |\n|---|---|---|---|")
        for name, area, mean in rows:
            print(f"| {name} | {area:.3f} | {mean:.4f} | {area * mean / total:.3f} |")


if __name__ == "__main__":
    main()

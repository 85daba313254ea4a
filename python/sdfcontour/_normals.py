"""Vertex normals from the field: the gradient of the samples (central differences at the 8
corners of the cell holding the vertex, interpolated trilinearly, as scikit-image does), or of a
callable (central differences at the vertex). Unit length, pointing outward (along grad f)."""
import numpy as np


def _unit(G):
    length = np.linalg.norm(G, axis=1, keepdims=True)
    return np.divide(G, length, out=np.zeros_like(G), where=length > 0)


def grid_normals(grid, lo, h, V, chunk=1 << 18):
    """Normals at V (n, 3) of the grid (nx, ny, nz) whose sample [i, j, k] lies at lo + (i, j, k) h.
    Reads only the cells that hold vertices (memory bounded by the mesh, not the grid)."""
    dims = np.array(grid.shape)
    out = np.empty_like(V)
    for start in range(0, len(V), chunk):
        P = V[start:start + chunk]
        t = (P - lo) / h
        cell = np.clip(np.floor(t).astype(np.int64), 0, dims - 2)
        w = np.clip(t - cell, 0.0, 1.0)
        G = np.zeros_like(P)
        for corner in range(8):
            offset = np.array([corner & 1, corner >> 1 & 1, corner >> 2 & 1])
            c = cell + offset
            weight = np.prod(np.where(offset == 1, w, 1 - w), axis=1)
            for a in range(3):
                up, down = c.copy(), c.copy()
                up[:, a] = np.minimum(c[:, a] + 1, dims[a] - 1)
                down[:, a] = np.maximum(c[:, a] - 1, 0)
                diff = (grid[up[:, 0], up[:, 1], up[:, 2]].astype(np.float64) -
                        grid[down[:, 0], down[:, 1], down[:, 2]])
                G[:, a] += weight * diff / ((up[:, a] - down[:, a]) * h[a])
        out[start:start + chunk] = _unit(G)
    return out


def callable_normals(f, V, h, batch_size):
    """Normals at V of the callable f by central differences of step h / 2 (6 evaluations per
    vertex, in batches); returns (normals, evaluations)."""
    out = np.empty_like(V)
    step = 0.5 * h
    per = max(1, batch_size // 6)
    for start in range(0, len(V), per):
        P = V[start:start + per]
        probes = np.concatenate([P + s * step * np.eye(3)[a] for a in range(3) for s in (1, -1)])
        values = np.asarray(f(probes), dtype=np.float64).reshape(6, len(P))
        G = np.stack([(values[2 * a] - values[2 * a + 1]) / (2 * step) for a in range(3)], axis=1)
        out[start:start + per] = _unit(G)
    return out, 6 * len(V)

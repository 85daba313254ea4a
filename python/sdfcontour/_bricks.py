"""Bricks of a grid and the mesh piece each owns (marching cubes), for any scheduler: the
Dask module, the bricked callable path, or a user's own (a Slurm array)."""
import numpy as np

from . import _sdfcontour


class BrickError(ValueError):
    """A brick's data could not be contoured (NaN, wrong dtype or shape): names the brick."""


def bricks(shape, brick):
    """The bricks of a grid of `shape` samples, `brick` cells a side (the last ones shorter):
    a list of (index (3 ints), first sample (3 ints), samples (3 ints)), in C order. A brick holds
    the samples of the cells it owns: its cells and one more sample on each high side."""
    ranges = []
    for n in shape:
        starts = range(0, n - 1, brick)
        ranges.append([(s, min(brick, n - 1 - s) + 1) for s in starts])
    out = []
    for a, (fa, da) in enumerate(ranges[0]):
        for b, (fb, db) in enumerate(ranges[1]):
            for c, (fc, dc) in enumerate(ranges[2]):
                out.append(((a, b, c), (fa, fb, fc), (da, db, dc)))
    return out


def brick_piece(block, index, first, shape, lo, hi):
    """The piece of the marching cubes mesh that one brick owns, from its block of samples (the
    samples [first, first + block.shape) of a grid of `shape` samples over [lo, hi]).

    Returns (keys (v,) uint64 ascending, V (v, 3) float64, F (f, 3) int32 into V). A grid edge's
    vertex has the same key and bit for bit the same position in every brick that meets it, so
    pieces from any scheduler join into the single-process mesh (`join_pieces`)."""
    try:
        block = np.asarray(block)
        if block.dtype.kind not in "fiu":
            raise ValueError(f"the grid must hold real numbers, not {block.dtype}")
        # The core checks the values (finite, named by global [i, j, k]) and returns an empty
        # piece for a block of one sign, in one pass.
        return _sdfcontour.marching_cubes_brick(block, tuple(int(f) for f in first),
                                                tuple(int(n) for n in shape),
                                                tuple(float(x) for x in lo),
                                                tuple(float(x) for x in hi))
    except ValueError as e:
        end = [int(f) + int(d) for f, d in zip(first, np.shape(block))]
        raise BrickError(f"brick {tuple(int(x) for x in index)} (samples "
                         f"[{first[0]}:{end[0]}, {first[1]}:{end[1]}, {first[2]}:{end[2]}]): "
                         f"{e}") from None


def canonical_mesh(V, F):
    """The mesh (V (n, 3), F (m, 3)) in a canonical order: vertices sorted by position, each
    triangle renumbered and rotated to start at its smallest index, triangles sorted. Two meshes
    have equal canonical forms iff they hold the same vertex positions (bit for bit) and the same
    oriented triangles, in whatever order: how to check that bricked runs agree."""
    V, F = np.asarray(V), np.asarray(F)
    order = np.lexsort(V.T[::-1])
    rank = np.empty(len(V), np.int64)
    rank[order] = np.arange(len(V))
    T = rank[F]
    shift = np.argmin(T, axis=1)
    T = np.stack([T[np.arange(len(T)), (shift + s) % 3] for s in range(3)], axis=1)
    return V[order], T[np.lexsort(T.T[::-1])]

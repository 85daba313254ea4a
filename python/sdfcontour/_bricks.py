"""Bricks of a grid and the mesh piece each owns (marching cubes, or GCP's local reconstruction),
for any scheduler: the Dask module, the bricked callable path, or a user's own (a Slurm array)."""
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


def bricks_among(shape, brick, indices=None):
    """The bricks of ``bricks(shape, brick)`` whose index is in `indices` (a set of 3-tuples), in
    C order, without listing the others (a level set's leaves far apart span bricks by the
    billion); all of them where `indices` is None."""
    if indices is None:
        return bricks(shape, brick)
    out = []
    for index in sorted(indices):
        first = tuple(int(i) * brick for i in index)
        if any(f >= n - 1 for f, n in zip(first, shape)):
            continue  # past the grid's last cell
        out.append((tuple(index), first, tuple(min(brick, n - 1 - f) + 1 for f, n in zip(first, shape))))
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
        raise _brick_error(index, first, end, e) from None


def _brick_error(index, first, end, error):
    return BrickError(f"brick {tuple(int(x) for x in index)} (samples "
                      f"[{first[0]}:{end[0]}, {first[1]}:{end[1]}, {first[2]}:{end[2]}]): "
                      f"{error}")


def gcp_brick_piece(read, index, first, dims, shape, lo, hi, options, truncation, value_scale=1.0,
                    with_stats=False, store=None):
    """The piece of GCP's local reconstruction (its mesh in bricks, local_brick.h) that one brick
    owns: the grid edges from the brick's samples [first, first + dims - 1) (its cells' low
    corners), read with a halo around them by ``read(first, dims)`` (a block of the grid; the
    core's brick driver widens the halo until the contact points' stars fit in it). ``options``:
    contour()'s options dict; ``truncation``: (inside, outside) found on the whole grid (inf:
    none); ``value_scale``: the factor that makes the values distances (found on the whole
    grid); ``store``: a ``_sdfcontour.LatticeStore`` shared by the grid's bricks when they run
    one at a time in C order (each sample's contact point then made once), or None.

    Returns (keys (v, 2) uint64 ascending, V (v, 3) float64, F (f, 3) int32 into V, the
    triangles' names (f,) uint64 ascending), with ``with_stats`` the piece's whole stats dict in
    the names' place: joined with the other bricks' pieces (``_sdfcontour.join_local_pieces``,
    the core's join), the whole grid's local mesh, bit for bit."""
    own_first = [int(f) for f in first]
    # Its cells' low samples; the brick at the grid's end also owns the last sample (whose
    # contact point adaptivity reads), as the core's bricks do.
    own_end = [int(n) if int(f) + int(d) >= int(n) else int(f) + int(d) - 1
               for f, d, n in zip(first, dims, shape)]
    last = [own_first, own_end]  # the samples of the last block read, for an error's message

    def checked(at, size):
        last[:] = [list(at), [a + s for a, s in zip(at, size)]]
        block = np.asarray(read(list(at), list(size)))
        if block.dtype.kind not in "fiu":
            raise ValueError(f"the grid must hold real numbers, not {block.dtype}")
        return block

    try:
        piece = _sdfcontour.local_brick(checked, tuple(int(n) for n in shape),
                                        tuple(float(x) for x in lo), tuple(float(x) for x in hi),
                                        tuple(own_first), tuple(own_end), options,
                                        tuple(float(t) for t in truncation), float(value_scale),
                                        store)
    except ValueError as e:
        raise _brick_error(index, last[0], last[1], e) from None
    return piece if with_stats else (*piece[:3], piece[3]["triangle_names"])


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

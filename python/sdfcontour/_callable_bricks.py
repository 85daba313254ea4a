"""Marching cubes of a callable SDF brick by brick, in one process: memory follows the surface,
not the n^3 grid.

A coarse grid (every BRICK // 4 samples) bounds |f| / lipschitz from below in each coarse cell
(a corner's distance less the cell's diagonal). A brick of BRICK cells none of whose coarse cells
can come within `threshold` of the surface holds no sign change: it is skipped unread. Each other
brick is sampled near the surface only (the coarse-to-fine sampler, on the brick) and contoured
by marching_cubes_brick; the pieces join by their edge keys into exactly the mesh of the full
grid (brick_marching.h)."""
import sys

import numpy as np

from ._bricks import brick_piece
from ._callable import _axis_indices, _evaluate, sample_blocks, steepest_slope
from ._io_join import join_pieces

BRICK = 32  # cells a side: small bricks walk few points far from the surface
GROUP = 32  # bricks sampled together (their temporaries ~3 MB each), so f gets large batches


def active_bricks(f, lo, h, n, threshold, batch_size, report, lipschitz):
    """The bricks (index, first sample, samples) that may hold the surface, in C order."""
    step = BRICK // 4
    axis = _axis_indices(n, step)
    P = np.stack(np.meshgrid(*[lo[a] + axis * h[a] for a in range(3)], indexing="ij"), axis=-1)
    counter = [0]
    C = _evaluate(f, P.reshape(-1, 3), batch_size, counter).reshape((len(axis),) * 3)
    report.evaluations += counter[0]
    report.steepest = max(report.steepest, steepest_slope(C, [axis * h[a] for a in range(3)]))
    d = [np.diff(axis) * h[a] for a in range(3)]
    diagonal = np.sqrt(d[0][:, None, None] ** 2 + d[1][None, :, None] ** 2 +
                       d[2][None, None, :] ** 2)
    distance = np.abs(C) / lipschitz
    m = len(axis) - 1
    bound = np.full((m, m, m), -np.inf)
    for corner in range(8):
        o = (corner & 1, corner >> 1 & 1, corner >> 2 & 1)
        bound = np.maximum(bound, distance[o[0]:o[0] + m, o[1]:o[1] + m, o[2]:o[2] + m] - diagonal)
    cells = np.argwhere(bound <= threshold)
    index = np.unique(axis[cells] // BRICK, axis=0)
    out = []
    for b in index:
        first = tuple(int(x) * BRICK for x in b)
        dims = tuple(min(BRICK, n - 1 - f0) + 1 for f0 in first)
        out.append((tuple(int(x) for x in b), first, dims))
    return out


def contour_callable_mc(f, lo, hi, n, batch_size, report, lipschitz=1.0, progress=False):
    """(V, F, stats) of marching cubes on the n^3 grid of f over [lo, hi], from the bricks that
    may hold the surface (F empty if none has a sign change); evaluations and slopes go to
    `report`."""
    h = (hi - lo) / (n - 1)
    threshold = float(h.max())  # marching cubes reads values only on edges that change sign
    bricks = active_bricks(f, lo, h, n, threshold, batch_size, report, lipschitz)
    pieces = []
    for start in range(0, len(bricks), GROUP):  # sampled together: large calls to f
        group = bricks[start:start + GROUP]
        blocks = sample_blocks(f, lo, h, [(first, dims) for _, first, dims in group], threshold,
                               batch_size, report, lipschitz=lipschitz)
        for number, ((index, first, _), block) in enumerate(zip(group, blocks), start):
            pieces.append((number, brick_piece(block, index, first, (n, n, n), lo, hi)))
        if callable(progress):
            progress("bricks", start + len(group), len(bricks))
        elif progress:
            print(f"[sdfcontour] bricks {start + len(group)}/{len(bricks)}, "
                  f"{report.evaluations} evaluations", file=sys.stderr, end="\r", flush=True)
    if progress is True:
        print(file=sys.stderr, flush=True)
    if pieces:
        V, F, stats = join_pieces(pieces, len(pieces))
    else:  # the caller decides: a steeper field sampled again, or no surface
        V, F, stats = np.zeros((0, 3)), np.zeros((0, 3), np.int32), {}
    stats["bricks"] = len(bricks)
    return V, F, stats

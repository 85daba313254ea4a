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

from . import _sdfcontour
from ._bricks import brick_piece, bricks, gcp_brick_piece
from ._callable import _axis_indices, _evaluate, sample_blocks, steepest_slope
from ._io_join import join_pieces

BRICK = 32  # cells a side: small bricks walk few points far from the surface
GROUP = 32  # bricks sampled together (their temporaries ~3 MB each), so f gets large batches


def active_bricks(f, lo, h, n, threshold, batch_size, report, lipschitz, fill=False):
    """The bricks (index, first sample, samples) that may hold the surface, in C order. With
    `fill`, also an array (one per brick a side) of a value for each brick left out: its sign, and
    a size under the smallest |f| in it (its coarse cells' bound, over `threshold`)."""
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
    if not fill:
        return out
    # Each brick's smallest bound over its coarse cells (BRICK // step of them a side), signed as
    # its first coarse sample: a brick left out has no sign change.
    starts = np.flatnonzero(np.diff(np.concatenate([[-1], axis[:-1] // BRICK])))
    for a in range(3):
        bound = np.minimum.reduceat(bound, starts, axis=a)
    corner = C[np.ix_(starts, starts, starts)]
    return out, np.where(corner < 0, -1.0, 1.0) * np.maximum(bound, threshold) * lipschitz


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
        _report_bricks(progress, "bricks", start + len(group), len(bricks), report)
    if progress is True:
        print(file=sys.stderr, flush=True)
    if pieces:
        V, F, stats = join_pieces(pieces, len(pieces))
    else:  # the caller decides: a steeper field sampled again, or no surface
        V, F, stats = np.zeros((0, 3)), np.zeros((0, 3), np.int32), {}
    stats["bricks"] = len(bricks)
    return V, F, stats


class NearSurfaceGrid:
    """The n^3 grid of a callable f over [lo, hi], held as its bricks that may hold the surface,
    sampled once each (exact where |f| / lipschitz <= threshold, as sample_block) and a signed
    bound for each other brick: memory follows the surface. `read(first, dims)` assembles any
    block of it, for a reconstruction that goes brick by brick."""

    def __init__(self, f, lo, hi, n, threshold, batch_size, report, lipschitz=1.0,
                 progress=False, earlier=None):
        """`earlier`: a NearSurfaceGrid of the same f and grid sampled to a smaller threshold,
        whose evaluations are reused (its bricks are moved out of it)."""
        self.lo, self.hi, self.shape = lo, hi, (n, n, n)
        h = (hi - lo) / (n - 1)
        bricks, self.fill = active_bricks(f, lo, h, n, threshold, batch_size, report, lipschitz,
                                          fill=True)
        self.arrays, self.exact = {}, {}
        before = earlier.arrays if earlier is not None else {}
        for start in range(0, len(bricks), GROUP):  # sampled together: large calls to f
            group = bricks[start:start + GROUP]
            # (Taken out of the earlier grid: each brick held once.)
            known = [(before.pop(index), earlier.exact.pop(index)) if index in before else None
                     for index, _, _ in group]
            blocks = sample_blocks(f, lo, h, [(first, dims) for _, first, dims in group],
                                   threshold, batch_size, report, lipschitz=lipschitz,
                                   known=known, with_exact=True)
            for (index, _, _), (block, exact) in zip(group, blocks):
                self.arrays[index], self.exact[index] = block, exact
            _report_bricks(progress, "sampling", start + len(group), len(bricks), report)

    def owns_surface(self, first, end):
        """Whether any sampled brick meets the cells [first, end) (the others have no sign
        change)."""
        ranges = [range(a // BRICK, (b - 1) // BRICK + 1) for a, b in zip(first, end)]
        return any((i, j, k) in self.arrays for i in ranges[0] for j in ranges[1]
                   for k in ranges[2])

    def read(self, first, dims):
        """The samples [first, first + dims) as a float64 array."""
        return assemble(self.arrays, self.fill, first, dims)

    def value_scale(self):
        """(value_scale, median gradient norm) as the core measures them on the whole grid
        (band.h, gradient_norm_summary), from the sampled bricks alone: a sample next to a sign
        change lies in one."""
        n = self.shape[0]
        norms = []
        for b in self.arrays:
            own_first = [x * BRICK for x in b]
            own_end = [min(x + BRICK, n) for x in own_first]
            first = [max(0, x - 2) for x in own_first]
            end = [min(n, x + 2) for x in own_end]
            block = self.read(first, [e - f0 for f0, e in zip(first, end)])
            norms.append(_sdfcontour.crossing_gradient_norms(
                block, tuple(first), self.shape, tuple(self.lo), tuple(self.hi),
                tuple(own_first), tuple(own_end)))
        if not norms:
            return _sdfcontour.distance_value_scale(np.zeros(0), np.zeros(0))
        every, kinkless = zip(*norms)
        return _sdfcontour.distance_value_scale(np.concatenate(every), np.concatenate(kinkless))


def assemble(arrays, fill, first, dims):
    """The samples [first, first + dims) of a grid held as sampled bricks (`arrays`: index ->
    block of BRICK + 1 samples a side, or fewer at the grid's end) and a `fill` value for each
    other brick, as a float64 array. Where two bricks share a face, the higher index's values
    are taken: a pure function of the bricks, so every block read of one grid agrees."""
    count = fill.shape
    index = [np.minimum((first[a] + np.arange(dims[a])) // BRICK, count[a] - 1) for a in range(3)]
    block = fill[np.ix_(*index)]
    ranges = [range(max(0, (first[a] - 1) // BRICK), (first[a] + dims[a] - 1) // BRICK + 1)
              for a in range(3)]
    for b in ((i, j, k) for i in ranges[0] for j in ranges[1] for k in ranges[2]):
        array = arrays.get(b)
        if array is None:
            continue
        at = [x * BRICK for x in b]
        lo = [max(at[a], first[a]) for a in range(3)]
        hi = [min(at[a] + array.shape[a], first[a] + dims[a]) for a in range(3)]
        if any(l >= u for l, u in zip(lo, hi)):
            continue
        block[tuple(slice(l - f0, u - f0) for l, u, f0 in zip(lo, hi, first))] = \
            array[tuple(slice(l - a0, u - a0) for l, u, a0 in zip(lo, hi, at))]
    return block


def _report_bricks(progress, stage, done, total, report):
    if callable(progress):
        progress(stage, done, total)
    elif progress:
        print(f"[sdfcontour] {stage} {done}/{total} bricks, {report.evaluations} evaluations",
              file=sys.stderr, end="\r", flush=True)


def sample_near_surface(f, lo, hi, n, reach, batch_size, report, lipschitz=1.0, progress=False,
                        earlier=None):
    """(NearSurfaceGrid, (value_scale, median gradient norm)) exact wherever a reconstruction
    reads a value: `reach` spacings of distance (local_values_reach, contour_values_reach), and 4
    for the gradient norms. The sampler is exact where |f| / lipschitz <= its threshold; the
    values read are those with |f| * value_scale <= reach, so a field steeper than `lipschitz`
    says (value_scale * lipschitz < 1) is sampled again over the reach it needs, its values
    evaluated once. `earlier`: a NearSurfaceGrid of f sampled before (with a smaller bound),
    whose evaluations are reused."""
    h = float(((hi - lo) / (n - 1)).max())
    reach = max(reach, 4.0) * h
    # A little beyond the reach, so that a value scale of 1 / lipschitz, rounded, needs no more.
    grid = NearSurfaceGrid(f, lo, hi, n, reach * (1 + 1e-6), batch_size, report, lipschitz,
                           progress, earlier)
    scale = grid.value_scale()
    if scale[0] * lipschitz * (1 + 1e-6) < 1:
        grid = NearSurfaceGrid(f, lo, hi, n, reach / (scale[0] * lipschitz), batch_size, report,
                               lipschitz, progress, earlier=grid)
    return grid, scale


def contour_sparse(grid, scale, options, want_mesh, want_points, callback=None):
    """contour() of a NearSurfaceGrid as the core's sparse grid (input/sparse_grid.h): its
    sampled bricks and the fill of the others, never an n^3 array. The dict of
    _sdfcontour.contour, for any method but the local reconstruction (which goes brick by brick:
    contour_callable_gcp)."""
    blocks = sorted(grid.arrays.items())
    return _sdfcontour.contour_sparse(blocks, grid.fill, BRICK, grid.shape, tuple(grid.lo),
                                      tuple(grid.hi), float(scale[0]), float(scale[1]),
                                      dict(options, truncation="none"), want_mesh, want_points,
                                      callback)


def contour_callable_gcp(grid, scale, options, progress=False):
    """(V, F, stats) of GCP's local reconstruction of a NearSurfaceGrid, brick by brick
    (local_brick.h): bricks of LOCAL_BRICK cells, each read with its halo, the pieces joined by
    their keys. Bricks whose cells hold no sampled brick are skipped. `scale`: (value_scale,
    median gradient norm), as the core rescales a grid's values to distances."""
    n = grid.shape[0]
    value_scale, norm = scale
    size = options["brick_size"] if options["brick_size"] > 0 else _sdfcontour.LOCAL_BRICK
    todo = [(index, first, dims) for index, first, dims in bricks(grid.shape, size)
            if grid.owns_surface(first, [f0 + d - 1 for f0, d in zip(first, dims)])]
    pieces, contact_points, owned = [], 0, []
    # (The bricks in C order, one at a time: each sample's lattice point made once.)
    store = _sdfcontour.LatticeStore()
    for number, (index, first, dims) in enumerate(todo):
        keys, V, F, stats = gcp_brick_piece(grid.read, index, first, dims, grid.shape, grid.lo,
                                            grid.hi, options, (np.inf, np.inf), value_scale,
                                            with_stats=True, store=store)
        contact_points += stats["contact_points"]
        pieces.append((keys, V, F, stats["triangle_names"]))
        if "owned_samples" in stats:
            owned.append((stats["owned_samples"], stats["owned_points"], stats["owned_normals"]))
        if callable(progress):
            progress("bricks", number + 1, len(todo))
    if progress is True:
        print(file=sys.stderr, flush=True)
    # The core's join (named pieces): vertices by key, triangles by name, the same arrays for
    # any bricks (what adaptivity's merges depend on).
    V, F, stats = join_pieces(enumerate(pieces), len(pieces))
    del pieces
    if len(F) == 0:
        raise ValueError("the local reconstruction found no surface inside the grid")
    stats.update(local_bricks=len(todo), contact_points=contact_points, value_scale=value_scale,
                 gradient_norm=norm, samples=n ** 3,
                 local_edge_fans=_sdfcontour.edge_fans_chosen(options, tuple(grid.shape)))
    if options.get("adaptivity", 0.0) > 0:
        # Merged over the bricks' own contact points, in their samples' order (as the core's
        # join_owned_contact_points), once the mesh is whole.
        samples = np.concatenate([o[0] for o in owned])
        order = np.argsort(samples, kind="stable")
        P = np.concatenate([o[1] for o in owned])[order]
        N = np.concatenate([o[2] for o in owned])[order]
        h = float(((grid.hi - grid.lo) / (n - 1)).max())
        V, F, stats["adaptivity"] = _sdfcontour.adapt_mesh(V, F, P, N, h, options["adaptivity"])
    return V, F, stats

"""Sampling a callable signed distance only where the contouring needs it.

Coarse to fine: level L holds the grid points whose indices are multiples of 2^L (and the last
index), down to level 0, the full grid. The coarsest level is evaluated everywhere. At each finer
level, a new point p gets a lower bound of |f(p)| from its (up to 8) parents on the coarser level:
max over parents q of |f(q)| - |p - q| (a distance moves by at most the distance moved; a parent
that was itself only bounded passes its bound on). p is evaluated when that bound is at most
tau_l = threshold + sqrt(3) h (2^l - 1): then a point left out at level l has every descendant left
out too, and at level 0 every point with |f| <= threshold is evaluated. A point left out keeps its
signed bound (its sign is its parent's: f cannot change sign within the bound), so the grid handed
on has the true value wherever the contouring reads one, and the right sign everywhere else.
"""
import sys

import numpy as np

from ._checks import ArgumentTypeError


def _axis_indices(n, step):
    idx = np.arange(0, n, step)
    if idx[-1] != n - 1:
        idx = np.append(idx, n - 1)
    return idx


def _evaluate(f, points, batch_size, counter):
    out = np.empty(len(points))
    for start in range(0, len(points), batch_size):
        chunk = points[start:start + batch_size]
        try:
            raw = np.asarray(f(chunk))
        except Exception as error:
            # Marked as the callable's own, so that a Dask client raises it as it is (its
            # attributes travel with it from the worker).
            try:
                error.sdfcontour_from_callable = True
            except AttributeError:
                pass
            raise
        if raw.dtype.kind not in "fiu":
            raise ArgumentTypeError(f"the SDF must return real numbers, got an array of dtype {raw.dtype}")
        values = raw.astype(float).reshape(-1)
        if values.shape != (len(chunk),):
            raise ValueError(f"the SDF returned {values.size} values for {len(chunk)} points")
        if not np.all(np.isfinite(values)):
            raise ValueError("the SDF returned NaN or infinite values")
        out[start:start + len(chunk)] = values
        counter[0] += len(chunk)
    return out


class SamplingReport:
    """What sampling a callable found: its evaluations, the steepest slope between neighbouring
    coarse samples (|f(p) - f(q)| / |p - q|), and the largest amount by which an evaluated value
    undercut the bound that its coarser neighbours gave (both 0 for a field within its
    Lipschitz bound)."""

    def __init__(self):
        self.evaluations = 0
        self.steepest = 0.0
        self.undercut = 0.0

    def breaks(self, lipschitz, spacing):
        """Whether the field broke the assumed bound: a slope past 1.5 lipschitz (the neural SDF
        fixture's coarse slopes reach 1.22: near the surface it is a distance, and the undercut
        test watches there), or a value a quarter spacing under its bound."""
        return self.steepest > 1.5 * lipschitz or self.undercut > 0.25 * spacing


def steepest_slope(values, positions):
    """The largest |difference| / distance between neighbours along the axes of a block of
    samples at the coordinates `positions` (3 increasing 1D arrays)."""
    slope = 0.0
    for a in range(3):
        if values.shape[a] > 1:
            step = np.diff(positions[a]).reshape([-1 if b == a else 1 for b in range(3)])
            slope = max(slope, float((np.abs(np.diff(values, axis=a)) / step).max()))
    return slope


def sample_block(f, lo, h, first, dims, threshold, batch_size, report, progress=False,
                 lipschitz=1.0):
    """The samples [first, first + dims) of the grid lo + index * h (float64 arrays of 3) of f:
    exact where |f| / lipschitz <= threshold (a length), signed lower bounds elsewhere (see the
    module's docstring). A point's position depends on its global index only, so blocks of one grid
    agree where they overlap. Adds to `report` (a SamplingReport)."""
    return sample_blocks(f, lo, h, [(first, dims)], threshold, batch_size, report, progress,
                         lipschitz)[0]


def sample_blocks(f, lo, h, blocks, threshold, batch_size, report, progress=False,
                  lipschitz=1.0, known=None, with_exact=False):
    """sample_block for each (first, dims) of `blocks`, level by level together, so that the
    callable sees batches of all the blocks' points (few large calls, not many small ones).
    `known`: for each block, None or (values, exact) of an earlier sampling of it, whose exact
    values are taken instead of evaluated again. With `with_exact`, each block comes as (values,
    exact), exact flagging the values evaluated."""
    known = known or [None] * len(blocks)
    steppers = [_block_steps(lo, h, first, dims, threshold, report, progress and len(blocks) == 1,
                             lipschitz, earlier)
                for (first, dims), earlier in zip(blocks, known)]
    grids = [None] * len(steppers)
    requests = {}
    for b, stepper in enumerate(steppers):  # (one with every value known asks for none)
        try:
            requests[b] = next(stepper)
        except StopIteration as done:
            grids[b] = done.value
    counter = [0]
    while requests:
        points = np.concatenate([requests[b] for b in requests])
        values = _evaluate(f, points, batch_size, counter)
        at, answered = 0, {}
        for b in requests:
            answered[b] = values[at:at + len(requests[b])]
            at += len(requests[b])
        requests = {}
        for b, v in answered.items():
            try:
                requests[b] = steppers[b].send(v)
            except StopIteration as done:
                grids[b] = done.value
    report.evaluations += counter[0]
    return grids if with_exact else [values for values, _ in grids]


def _block_steps(lo, h, first, dims, threshold, report, progress, lipschitz, earlier=None):
    """The coarse-to-fine sampling of one block as a generator: yields the positions it needs
    evaluated (possibly none), receives their values, returns the block and its flags of the
    values evaluated. `earlier`: None or (values, exact) of this block, exact values reused."""
    first = np.asarray(first, dtype=np.int64)
    dims = tuple(int(d) for d in dims)
    levels = 0
    while levels < 6 and (min(dims) - 1) >> (levels + 1) >= 4:
        levels += 1
    grid = np.full(dims, np.nan)
    exact = np.zeros(dims, bool)

    def position(i, j, k):
        return np.column_stack([lo[0] + (first[0] + i) * h[0], lo[1] + (first[1] + j) * h[1],
                                lo[2] + (first[2] + k) * h[2]])

    def evaluated(i, j, k):
        # f at samples (i, j, k): what an earlier sampling evaluated, the rest asked for.
        values = np.empty(len(i))
        todo = np.ones(len(i), bool)
        if earlier is not None:
            todo = ~earlier[1][i, j, k]
            values[~todo] = earlier[0][i[~todo], j[~todo], k[~todo]]
        if todo.any():
            values[todo] = yield position(i[todo], j[todo], k[todo])
        exact[i, j, k] = True
        return values

    # The coarsest level, everywhere.
    coarse = [_axis_indices(d, 1 << levels) for d in dims]
    ci, cj, ck = (a.ravel() for a in np.meshgrid(*coarse, indexing="ij"))
    grid[ci, cj, ck] = yield from evaluated(ci, cj, ck)
    report.steepest = max(report.steepest, steepest_slope(
        grid[np.ix_(*coarse)], [coarse[a] * h[a] for a in range(3)]))
    for level in range(levels - 1, -1, -1):
        axes, is_parent, above, below = [], [], [], []
        for d in dims:
            parent_axis = _axis_indices(d, 1 << (level + 1))
            axis = _axis_indices(d, 1 << level)
            axes.append(axis)
            is_parent.append(np.isin(axis, parent_axis))
            # Each index's parents below and above on the coarser level (equal when it is one).
            above.append(parent_axis[np.minimum(np.searchsorted(parent_axis, axis),
                                                len(parent_axis) - 1)])
            below.append(parent_axis[np.maximum(np.searchsorted(parent_axis, axis, side="right")
                                                - 1, 0)])
        tau = threshold + np.sqrt(3.0) * float(h.max()) * ((1 << level) - 1)
        if progress:
            print(f"[sdfcontour] sampling level {level}", file=sys.stderr, flush=True)
        # A slab of i at a time bounds the temporary arrays.
        slab = max(1, (1 << 22) // (len(axes[1]) * len(axes[2])))
        for start in range(0, len(axes[0]), slab):
            ii = np.arange(start, min(start + slab, len(axes[0])))
            a, b, c = np.meshgrid(ii, np.arange(len(axes[1])), np.arange(len(axes[2])),
                                  indexing="ij")
            a, b, c = a.ravel(), b.ravel(), c.ravel()
            new = ~(is_parent[0][a] & is_parent[1][b] & is_parent[2][c])
            a, b, c = a[new], b[new], c[new]
            i, j, k = axes[0][a], axes[1][b], axes[2][c]
            bound = np.full(len(i), -np.inf)  # a lower bound of the distance |f| / lipschitz
            sign = np.ones(len(i))
            for corner in range(8):
                qi = np.where(corner & 1, above[0][a], below[0][a])
                qj = np.where(corner & 2, above[1][b], below[1][b])
                qk = np.where(corner & 4, above[2][c], below[2][c])
                value = grid[qi, qj, qk]
                reach = np.sqrt(((i - qi) * h[0]) ** 2 + ((j - qj) * h[1]) ** 2 +
                                ((k - qk) * h[2]) ** 2)
                candidate = np.abs(value) / lipschitz - reach
                better = candidate > bound
                bound[better] = candidate[better]
                sign[better] = np.sign(value[better])
            evaluate = bound <= tau
            grid[i[~evaluate], j[~evaluate], k[~evaluate]] = \
                (sign * bound * lipschitz)[~evaluate]
            ie, je, ke = i[evaluate], j[evaluate], k[evaluate]
            if len(ie):
                values = yield from evaluated(ie, je, ke)
                grid[ie, je, ke] = values
                # A value under its bound near the band: the field is steeper than assumed
                # where it matters (far from the surface a neural SDF's values wander).
                near = np.abs(values) / lipschitz <= tau
                if near.any():
                    under = bound[evaluate][near] - np.abs(values[near]) / lipschitz
                    report.undercut = max(report.undercut, float(under.max()))
    return grid, exact


def vertex_normals(V, F):
    """Area-weighted unit vertex normals of the mesh (V, F)."""
    n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    out = np.zeros_like(V)
    for k in range(3):
        np.add.at(out, F[:, k], n)
    length = np.linalg.norm(out, axis=1, keepdims=True)
    return np.divide(out, length, out=np.zeros_like(out), where=length > 0)


def refine_on_zero_set(f, V, F, h, batch_size, iterations=2):
    """Moves each vertex along its normal onto f's zero set: secant steps on f along the normal
    (the normal is the outward direction, so f must increase along it), each move at most h / 2;
    a vertex where f does not increase along its normal, or whose |f| would grow, stays. Returns
    the new vertices, how many moved, and the evaluations spent."""
    V = np.array(V, dtype=np.float64)
    normals = vertex_normals(V, F)
    step = 1e-3 * h
    counter = [0]
    moved = np.zeros(len(V), dtype=bool)
    value = _evaluate(f, V, batch_size, counter)
    for _ in range(iterations):
        ahead = _evaluate(f, V + step * normals, batch_size, counter)
        slope = (ahead - value) / step
        usable = slope > 0.1  # a distance grows by ~1 per unit length along the outward normal
        move = np.zeros(len(V))
        move[usable] = np.clip(-value[usable] / slope[usable], -0.5 * h, 0.5 * h)
        trial = V + move[:, None] * normals
        trial_value = _evaluate(f, trial, batch_size, counter)
        better = usable & (np.abs(trial_value) < np.abs(value))
        V[better] = trial[better]
        value[better] = trial_value[better]
        moved |= better
    return V, int(moved.sum()), counter[0]

"""sdfcontour: contour samples of a signed distance function into a triangle mesh.

Numpy in, numpy out. The default method is GCP ("Contouring Signed Distance Fields by
Approximating Gradients"): contact points from the regular triangulation of the samples near the
surface, then screened Poisson reconstruction. Marching cubes (``method="mc"``), marching
tetrahedra (``"mt-rt"``, ``"mt-dt"``) are there too.

Conventions: a grid ``a`` of shape (nx, ny, nz) has ``a[i, j, k]`` at ``lo + (i*hx, j*hy, k*hz)``
over ``bounds=(lo, hi)`` (default ``(-1, 1)``, samples at both ends); values are negative inside;
normals point outward. Bad input raises ``ValueError`` (with the command-line tool's message;
an argument of the wrong type raises ``ArgumentTypeError``, both a ``TypeError`` and a
``ValueError``), files ``OSError``; Ctrl-C raises ``KeyboardInterrupt``.

Examples
--------
>>> import numpy as np, sdfcontour
>>> x = _np.linspace(-1, 1, 64)
>>> grid = _np.linalg.norm(_np.stack(_np.meshgrid(x, x, x, indexing="ij")), axis=0) - 0.6
>>> V, F = sdfcontour.contour(grid)                    # GCP
>>> V, F = sdfcontour.contour(grid, method="mc")       # marching cubes
>>> V, F = sdfcontour.contour(lambda p: _np.linalg.norm(p, axis=1) - 0.6, resolution=128)
"""
import warnings as _warnings

import numpy as _np

from . import _checks, _sdfcontour
from ._checks import ArgumentTypeError

__all__ = ["Mesh", "contour", "contact_points", "poisson", "sample", "distances", "read_mesh", "write_mesh",
           "ArgumentTypeError", "DroppedSamplesWarning", "FallbackWarning", "LipschitzWarning",
           "RescaleWarning"]

METHODS = ("gcp", "gtcp", "mc", "mt-rt", "mt-dt")


class FallbackWarning(UserWarning):
    """GCP could not trust the values as distances and returned marching cubes' mesh
    (``stats["fallback"]`` says why; ``strict=True`` makes it an error)."""


class RescaleWarning(UserWarning):
    """The values changed by m per unit length near the surface, not 1, and were divided by m
    (``stats["value_scale"]``)."""


class LipschitzWarning(UserWarning):
    """A callable SDF changed faster than its ``lipschitz`` bound said: it was sampled again with
    a larger bound (without it, small parts could be skipped)."""


class DroppedSamplesWarning(UserWarning):
    """Scattered samples were dropped as isolated strays (``stats["isolated_samples"]``)."""


def _bounds(bounds):
    """(lo, hi) as two float arrays of 3, from scalars or 3-sequences."""
    if bounds is None:
        bounds = (-1.0, 1.0)
    try:
        lo, hi = bounds
        lo = _np.broadcast_to(_checks.numbers_array("bounds", lo).astype(float), (3,)).copy()
        hi = _np.broadcast_to(_checks.numbers_array("bounds", hi).astype(float), (3,)).copy()
    except ValueError:
        raise ValueError("bounds must be (lo, hi), each a number or 3 numbers") from None
    limit = _checks.LARGEST_COORDINATE
    if not (_np.all(_np.abs(lo) <= limit) and _np.all(_np.abs(hi) <= limit) and _np.all(lo < hi)):
        raise ValueError(f"bounds: lo must be less than hi on every axis, all finite and at most "
                         f"{limit:g} in size")
    return lo, hi


def _brick_size(brick_size):
    if isinstance(brick_size, str):
        if brick_size != "auto":
            raise ValueError(f"brick_size must be a whole number or 'auto', got {brick_size!r}")
        return -1  # the core chooses
    if isinstance(brick_size, (int, _np.integer)) and brick_size == 0:
        return 0  # one triangulation
    try:
        return _checks.in_range("brick_size", brick_size, whole=True)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{error} (or 0 for no bricks, or 'auto')") from None


def _degree(degree):
    """The Poisson elements' degree, checked: 1 or 2."""
    if isinstance(degree, bool) or degree not in (1, 2):
        raise ValueError(f"degree must be 1 or 2, got {degree!r}")
    return int(degree)


def _poisson_options(full_depth, alpha, samples_per_node, scale, boundary, solver_tolerance,
                     finest_solver_tolerance):
    """The screened Poisson options that contour() and poisson() share, checked."""
    return dict(full_depth=_checks.in_range("full_depth", full_depth, whole=True),
                alpha=_checks.in_range("alpha", alpha),
                samples_per_node=_checks.in_range("samples_per_node", samples_per_node),
                scale=_checks.in_range("scale", scale),
                boundary=_checks.choice("boundary", boundary, ("neumann", "dirichlet", "free")),
                solver_tolerance=_checks.in_range("solver_tolerance", solver_tolerance),
                finest_solver_tolerance=_checks.in_range("finest_solver_tolerance",
                                                         finest_solver_tolerance))


def _progress(value):
    """True, False, or a callable progress(stage, done, total)."""
    if callable(value):
        return value
    if isinstance(value, (bool, _np.bool_)):
        return bool(value)
    raise _checks.ArgumentTypeError(f"progress must be True, False or a callable "
                                    f"progress(stage, done, total), got {value!r}")


def _full_depth_within(options):
    if options["full_depth"] > options["depth"]:
        raise ValueError("full_depth must be at most depth")


def _options(method, band, margin, truncation, gradient, weights, knn, fn, tie_tolerance,
             brick_size, brick_halo, depth, full_depth, alpha, samples_per_node, scale, boundary,
             solver_tolerance, progress, finest_solver_tolerance=1e-3):
    if method not in METHODS:
        raise ValueError(f"unknown method '{method}' (known: {', '.join(METHODS)})")
    auto_band = isinstance(band, str) and band == "auto"
    if isinstance(band, str) and band == "all":
        band = float("inf")
    elif auto_band:
        band = 0.0  # the core picks it from the resolution
    elif not (_checks.number("band", band) > 0 and band == band):
        raise ValueError(f"band must be a positive number of spacings (or 'all' or 'auto'), "
                         f"got {band!r}")
    if not isinstance(truncation, str):
        raise _checks.ArgumentTypeError(f"truncation must be 'auto', 'none' or a number as text, got "
                        f"{truncation!r}")
    if truncation not in ("auto", "none"):
        try:
            given = float(truncation)
        except ValueError:
            given = float("nan")
        if not 0 < given < float("inf"):
            raise ValueError(f"truncation must be 'auto', 'none' or a positive number as text, "
                             f"got {truncation!r}")
    o = dict(method=method, band=float(band), margin=_checks.in_range("margin", margin),
             truncation=truncation,
             gradient=_checks.choice("gradient", gradient, ("regular", "delaunay", "knn")),
             weights=_checks.choice("weights", weights, ("james", "volume", "uniform")),
             knn=_checks.in_range("knn", knn, whole=True), fn=_checks.flag("fn", fn),
             tie_tolerance=_checks.in_range("tie_tolerance", tie_tolerance),
             brick_size=_brick_size(brick_size),
             brick_halo=_checks.in_range("brick_halo", brick_halo),
             progress=_progress(progress) is True,  # a callable is passed on apart
             **_poisson_options(full_depth, alpha, samples_per_node, scale, boundary,
                                solver_tolerance, finest_solver_tolerance))
    if callable(progress):
        o["progress_callback"] = progress  # taken out before the options reach the core
    if isinstance(depth, str) and depth == "auto":
        o["depth_text"] = "auto"
    else:
        try:
            o["depth"] = _checks.in_range("depth", depth, whole=True)
        except (TypeError, ValueError) as error:
            raise ValueError(f"{error}, or 'auto'") from None
        _full_depth_within(o)
    return o


def _input_array(sdf):
    """The samples as an array the core reads: a grid, an (n, 4) array, or (points, values)."""
    if isinstance(sdf, tuple) and len(sdf) == 2:
        points = _checks.numbers_array("points", sdf[0]).astype(float)
        values = _checks.numbers_array("values", sdf[1]).astype(float)
        if points.ndim != 2 or points.shape[1] != 3 or values.shape != (points.shape[0],):
            raise ValueError("(points, values) must have shapes (n, 3) and (n,)")
        return _np.column_stack([points, values])
    array = _checks.numbers_array("the samples", sdf)
    if array.ndim == 3 and max(array.shape) > 2**31 - 1:
        raise ValueError(f"the grid has shape {array.shape}: at most 2147483647 samples per axis")
    return array


def _from_path(sdf, grid_name):
    """A path as the samples: a .npy memory-mapped (a grid or (n, 4) samples), a .vdb level set
    read sparse as the CLI reads it (its voxel size the spacing, its background the truncation
    unless one is given). Returns (samples, spacing of scattered samples or 0, truncation or
    None)."""
    import os
    if not isinstance(sdf, (str, os.PathLike)):
        if grid_name is not None:
            raise ValueError("grid_name is for a .vdb file")
        return sdf, 0.0, None
    path = os.fspath(sdf)
    if path.lower().endswith(".npy"):
        if grid_name is not None:
            raise ValueError("grid_name is for a .vdb file")
        if not os.path.isfile(path):
            raise OSError(f"cannot read '{path}': no such file")
        try:
            return _np.load(path, mmap_mode="r", allow_pickle=False), 0.0, None
        except ValueError as error:
            raise ValueError(f"cannot read '{path}' as .npy: {error}") from None
    if path.lower().endswith(".vdb"):
        points, values, voxel, background = _sdfcontour.read_vdb(path, grid_name or "")
        return _np.column_stack([points, values.reshape(-1)]), float(voxel), float(background)
    raise ValueError(f"cannot read '{path}': give a .npy or .vdb path, an array or a callable")


def _run_callable(f, lo, hi, resolution, batch_size, options, want_mesh, want_points, lipschitz):
    """A callable sampled near the surface and contoured; memory follows the surface. Marching
    cubes and GCP's local reconstruction go brick by brick; the other methods, and contact points
    alone, get the sampled bricks as the core's sparse grid. A field found steeper than
    `lipschitz` is sampled again with a larger bound, and said (LipschitzWarning)."""
    import time
    from ._callable import SamplingReport
    from ._callable_bricks import sample_near_surface
    options = dict(options)
    callback = options.pop("progress_callback", None)
    if resolution is None:
        raise ValueError("a callable SDF needs a resolution (samples per axis)")
    n = int(resolution)
    bricked = options["method"] == "mc" and want_mesh and not want_points
    local = (options["method"] == "gcp" and options.get("reconstruction") == "local" and
             options["gradient"] == "regular" and want_mesh and not want_points)
    # (Adaptivity of marching cubes' mesh merges it whole, in the core.)
    bricked = bricked and not options.get("adaptivity", 0.0) > 0
    _check_callable_arguments(resolution, batch_size)
    h = float(((hi - lo) / (n - 1)).max())
    started = time.perf_counter()
    evaluations, grid = 0, None
    for attempt in range(4):
        # (Each attempt's slopes afresh; every attempt's evaluations counted. An attempt with a
        # larger bound reuses the values that the last one evaluated.)
        report = SamplingReport()
        report.evaluations = evaluations
        if bricked:
            from ._callable_bricks import contour_callable_mc
            V, F, piece_stats = contour_callable_mc(f, lo, hi, n, int(batch_size), report,
                                                    lipschitz, callback or options["progress"])
        else:
            reach = (_sdfcontour.local_values_reach if local else
                     _sdfcontour.contour_values_reach)(options, (n, n, n))
            grid, scale = sample_near_surface(f, lo, hi, n, reach, int(batch_size), report,
                                              lipschitz, callback or options["progress"],
                                              earlier=grid)
        evaluations = report.evaluations
        if not report.breaks(lipschitz, h) or attempt == 3:
            break
        steeper = max(2.0 * lipschitz, 1.25 * report.steepest)
        _warnings.warn(f"the SDF changes by up to {report.steepest:.3g} per unit length "
                       f"(lipschitz={lipschitz:.3g} assumed): sampled again assuming "
                       f"lipschitz={steeper:.3g}, so that no small part is skipped; pass "
                       f"lipschitz= to say so up front", LipschitzWarning, stacklevel=4)
        lipschitz = steeper
    sampled = time.perf_counter() - started
    if bricked:
        if len(F) == 0:
            raise ValueError("the SDF has no sign change on the grid: no surface to contour")
        stats = dict(piece_stats, **_sdfcontour.mesh_topology(V, F))
        stats["seconds"] = {"bricks": sampled}
        stats["reconstruction"] = "none"
        out = {"V": V, "F": F, "stats": stats}
    elif local:
        from ._callable_bricks import contour_callable_gcp
        V, F, piece_stats = contour_callable_gcp(grid, scale, options,
                                                 callback or options["progress"])
        stats = dict(piece_stats, **_sdfcontour.mesh_topology(V, F))
        stats["seconds"] = {"sampling": sampled, "local": time.perf_counter() - started - sampled}
        stats["reconstruction"] = "local"
        out = {"V": V, "F": F, "stats": stats}
    else:
        from ._callable_bricks import contour_sparse
        out = contour_sparse(grid, scale, options, want_mesh, want_points, callback)
        out["stats"]["seconds"]["sampling"] = sampled
        out["stats"]["sampled_bricks"] = len(grid.arrays)
    out["stats"].update(evaluations=report.evaluations, lipschitz=lipschitz,
                        evaluated_fraction=report.evaluations / float(n) ** 3,
                        steepest_slope=report.steepest)
    return out


def _run(sdf, bounds, resolution, batch_size, options, want_mesh, want_points, spacing=0.0,
         lipschitz=1.0):
    lo, hi = _bounds(bounds)
    if callable(sdf):
        out = _run_callable(sdf, lo, hi, resolution, batch_size, options, want_mesh, want_points,
                            lipschitz)
    else:
        if resolution is not None:
            raise ValueError("resolution is for a callable SDF; a grid has its own shape")
        array = _input_array(sdf)
        options = dict(options)
        callback = options.pop("progress_callback", None)
        out = _sdfcontour.contour(array, lo, hi, spacing, options, want_mesh, want_points,
                                  callback)
    if out["stats"].get("fallback"):
        _warnings.warn(f"GCP returned marching cubes' mesh: {out['stats']['fallback']}",
                       FallbackWarning, stacklevel=3)
    if out["stats"].get("rescale_dropped"):
        _warnings.warn(f"GCP failed on the values rescaled to distances "
                       f"({out['stats']['rescale_dropped']}): this is GCP's mesh of the values "
                       f"as given", FallbackWarning, stacklevel=3)
    if out["stats"].get("value_scale", 1.0) != 1.0:
        _warnings.warn(f"the values were rescaled by {out['stats']['value_scale']:.4g} to "
                       f"distances (they change by {1 / out['stats']['value_scale']:.4g} per unit "
                       f"length near the surface)", RescaleWarning, stacklevel=3)
    if out["stats"].get("isolated_samples", 0) > 0:
        _warnings.warn(f"dropped {out['stats']['isolated_samples']} isolated samples (fewer than "
                       f"3 others within 4 spacings): strays far from the rest cannot place the "
                       f"surface", DroppedSamplesWarning, stacklevel=3)
    return out


def _check_callable_arguments(resolution, batch_size):
    """Refuses a callable's resolution or batch out of range (no path makes an n^3 array)."""
    if isinstance(resolution, bool) or not isinstance(resolution, (int, _np.integer)) \
            or not 2 <= resolution <= 2048:
        raise ValueError(f"resolution must be a whole number from 2 to 2048, got {resolution!r}")
    if isinstance(batch_size, bool) or not isinstance(batch_size, (int, _np.integer)) \
            or not 1 <= batch_size <= 2**26:
        raise ValueError(f"batch_size must be a whole number from 1 to {2**26}, got "
                         f"{batch_size!r}")


def _count_or_auto(name, value, most):
    """-1 for "auto", else a whole number from 0 to `most`; ValueError otherwise."""
    if isinstance(value, str) and value == "auto":
        return -1
    if isinstance(value, (int, _np.integer)) and not isinstance(value, bool) and 0 <= value <= most:
        return int(value)
    raise ValueError(f"{name} must be a whole number from 0 to {most} or 'auto', got {value!r}")


def _switch(name, value):
    """True, False or "auto" as the library's on/off/auto; anything else is a ValueError."""
    if isinstance(value, str) and value == "auto":
        return "auto"
    if isinstance(value, (bool, _np.bool_)):
        return "on" if value else "off"
    raise ValueError(f"{name} must be True, False or 'auto', got {value!r}")


class Mesh(tuple):
    """A triangle mesh that unpacks as a tuple (``V, F = mesh``; with normals or stats asked for,
    those follow) and names its parts:

    - ``V``: ndarray (n, 3) float64, the vertices;
    - ``F``: ndarray (m, 3) int32, triangles counter-clockwise seen from outside;
    - ``normals``: ndarray (n, 3) unit vertex normals, or None unless asked for;
    - ``stats``: dict, what the run did (always there).
    """

    def __new__(cls, V, F, normals=None, stats=None, unpack=("V", "F")):
        parts = {"V": V, "F": F, "normals": normals, "stats": stats}
        self = super().__new__(cls, tuple(parts[name] for name in unpack))
        self.V, self.F, self.normals, self.stats = V, F, normals, stats if stats is not None else {}
        return self

    def __repr__(self):
        return f"sdfcontour.Mesh({len(self.V)} vertices, {len(self.F)} triangles)"


def _lipschitz(value):
    value = float(_checks.number("lipschitz", value))
    if not 1e-6 <= value <= 1e6:
        raise ValueError(f"lipschitz must be from 1e-06 to 1e+06, got {value!r}")
    return value


def _at_level(sdf, level):
    """The samples less `level`, so that the level set f = level is their zero set."""
    level = float(_checks.number("level", level))
    if not _np.isfinite(level) or abs(level) > _checks.LARGEST_COORDINATE:
        raise ValueError(f"level must be a finite number, got {level!r}")
    if level == 0.0:
        return sdf
    if callable(sdf):
        f = sdf
        return lambda points: _np.asarray(f(points), dtype=float) - level
    if isinstance(sdf, tuple) and len(sdf) == 2:
        return sdf[0], _checks.numbers_array("values", sdf[1]).astype(float) - level
    array = _checks.numbers_array("the samples", sdf)
    if array.ndim == 2 and array.shape[1:] == (4,):
        array = array.astype(float)  # a copy
        array[:, 3] -= level
        return array
    return array - _np.asarray(level, dtype=array.dtype if array.dtype.kind == "f" else float)


def _placement(sdf, bounds, spacing, origin, resolution):
    """`bounds`, or (origin, origin + spacing (n - 1)) from scikit-image's keywords."""
    if spacing is None and origin is None:
        return bounds
    if bounds is not None:
        raise ValueError("give bounds, or spacing and origin, not both")
    if callable(sdf):
        if resolution is None:
            raise ValueError("a callable SDF needs a resolution (samples per axis)")
        shape = (_checks.whole_in("resolution", resolution, 2, 2048),) * 3
    else:
        array = _checks.numbers_array("the samples", sdf[1] if isinstance(sdf, tuple) else sdf)
        if array.ndim != 3:
            raise ValueError("spacing and origin place a grid (nx, ny, nz); scattered samples "
                             "carry their own positions")
        shape = array.shape

    def three(name, value, default):
        value = default if value is None else value
        try:
            v = _np.broadcast_to(_checks.numbers_array(name, value).astype(float), (3,)).copy()
        except ValueError:
            raise ValueError(f"{name} must be a number or 3 numbers") from None
        return v

    step, first = three("spacing", spacing, 1.0), three("origin", origin, 0.0)
    if not (_np.all(_np.isfinite(step)) and _np.all(step > 0) and _np.all(_np.isfinite(first))):
        raise ValueError("spacing must be positive and finite, origin finite")
    return first, first + step * (_np.array(shape) - 1)


def _normals_of(sdf, bounds, resolution, out, batch_size):
    """Unit vertex normals of out["V"] from the field (see contour's Returns)."""
    from . import _normals
    V = out["V"]
    if callable(sdf):
        lo, hi = _bounds(bounds)
        h = float(((hi - lo) / (int(resolution) - 1)).max())
        normals, evaluations = _normals.callable_normals(sdf, V, h, batch_size)
        out["stats"]["normal_evaluations"] = evaluations
        return normals
    array = _input_array(sdf)
    if array.ndim == 3:
        lo, hi = _bounds(bounds)
        return _normals.grid_normals(array, lo, (hi - lo) / (_np.array(array.shape) - 1), V)
    from ._callable import vertex_normals
    return vertex_normals(V, out["F"])


def contour(sdf, bounds=None, method="gcp", *, resolution=None, band="auto", margin=1.0,
            truncation="auto", gradient="regular", weights="james", knn=18, fn=False,
            tie_tolerance=1e-6, brick_size="auto", brick_halo=0.0, depth="auto", full_depth=5,
            alpha=10.0, samples_per_node=1.5, scale=1.1, boundary="neumann",
            solver_tolerance=1e-4, finest_solver_tolerance=1e-3, sign_constraints="auto",
            carve=True, side_passes="auto", projection="auto", refine_dilation="auto",
            degree=1, reconstruction="auto", subdivisions="auto", batch_size=65536,
            refine="auto", strict=False, progress=False, return_stats=False, level=0.0,
            spacing=None, origin=None, return_normals=False, grid_name=None, lipschitz=1.0,
            adaptivity=0.0):
    """Contour signed distance samples into a triangle mesh.

    Parameters
    ----------
    sdf : ndarray (nx, ny, nz), ndarray (n, 4), tuple (points (n, 3), values (n,)), callable, or path
        A grid of signed distances (float32 or float64; read in place when C-contiguous),
        scattered samples (rows x, y, z, value), a function ``f(points (k, 3)) -> (k,)``
        that is sampled on a ``resolution``^3 grid only near the surface (see Notes), or a
        path: a ``.npy`` (memory-mapped) or an OpenVDB ``.vdb`` float level set, read sparse as
        the CLI reads it (its active voxels as samples, its voxel size the spacing, its
        background the truncation).
    bounds : (lo, hi), optional
        The grid's box: positions of the first and last samples, each a number or 3 numbers.
        Default (-1, 1). Ignored for scattered samples.
    method : {"gcp", "gtcp", "mc", "mt-rt", "mt-dt"}
        GCP (default), GTCP (exact contact points: built-in shapes, CLI only), marching cubes
        (grids only), marching tetrahedra on the regular or the Delaunay triangulation.
    resolution : int, optional
        Samples per axis for a callable ``sdf``.
    band : float, "auto" or "all"
        Triangulation methods use the samples with ``|value| <= band`` grid spacings; "auto"
        is 8 below 128 samples per axis, 4 from 128 and 3 from 256 (docs/band.md); "all" keeps
        every sample (the paper's GCP, far slower).
    margin : float
        Samples up to this many spacings beyond the band close the band's stars.
    truncation : "auto", "none" or a number as text
        Values clamped at +-T (a TSDF) carry no distance: detect ("auto"), none, or given.
    gradient : {"regular", "delaunay", "knn"}
        Where GCP's gradients come from.
    weights : {"james", "volume", "uniform"}
        Averaging of the incident tetrahedra's gradients.
    knn : int
        k for ``gradient="knn"``.
    fn : bool
        +FN: retry a discarded contact point with each incident tet's gradient.
    tie_tolerance : float
        Contact point c is discarded only if it is inside another sample's sphere by more than
        this relative tolerance.
    sign_constraints : bool or "auto"
        GCP: correct the reconstruction where samples within 2 spacings of the surface would end
        on the wrong side of the mesh. "auto": below 128 samples per axis, where it is more
        accurate (finer grids are more accurate without); False: the paper's reconstruction
        (CLI ``--sign-constraints`` / ``--no-sign-constraints``).
    carve : bool
        GCP: move the mesh's vertices out of the samples' spheres, which hold no surface (the
        band's samples; below 128 samples per axis with ``band="auto"``, every sample within 16
        spacings). On by default, except on values smoothed for noise; CLI ``--no-carve``.
    side_passes : int or "auto"
        GCP carving: rounds in which each sample within a spacing of the surface that a triangle
        cuts, or that lies on the wrong side of the mesh, moves the nearest triangle, edge or
        vertex behind its sphere. 0: vertices only; "auto": 12 below 128 samples per axis, 0
        above (CLI ``--side-passes``).
    projection : bool or "auto"
        GCP: move each vertex of the reconstruction along its normal onto a quadric fitted to
        the contact points around it, where they fit one to 0.005 spacings ("auto", the
        default: on at every resolution; CLI ``--projection``).
    reconstruction : "auto", "poisson" or "local"
        GCP's mesh from its contact points: "poisson" (the paper's screened Poisson solve, then
        projection and carving), "local" (a vertex per grid cell the surface crosses, from the
        contact points near it; topology from the samples' signs; then subdivision, projection
        and carving vertex by vertex; brick by brick, as :func:`sdfcontour.dask.contour` runs it;
        grids and callables only), or
        "auto": local for a callable (refined on it, 0.12x / 0.16x marching cubes' L1 on a neural
        SDF at 64^3 / 128^3, where Poisson falls back to marching cubes or reaches 0.80x), local
        for grids from 256 samples per axis (more accurate and faster there), poisson for smaller
        grids (whose worst vertex on mirror-symmetric analytic shapes stays within marching
        cubes'; local is more accurate on average there too: docs/local.md) and scattered
        samples. CLI
        ``--reconstruction``.
    subdivisions : int or "auto"
        Local reconstruction: midpoint subdivisions before projection onto the contact points
        (0 to 4; "auto": 2 below 96 samples per axis, else 1).
    adaptivity : float
        Merge the mesh where the surface is flat enough: edges collapse while the merged
        vertex's squared distances to the tangent planes its region gathers (GCP's contact
        points; the mesh's own planes for the other methods), summed, stay under this many
        spacings (0 to 10) squared; creases and corners stay.
        Merges that make the mesh cross itself are made again with their region frozen.
        0 (default): the mesh as reconstructed. ``stats["adaptivity"]`` gives the triangles
        before and after. 0.02-0.05 gives 5-14x fewer triangles at about TOL 0's L1 (128^3,
        docs/adaptivity.md). CLI ``--adaptivity``.
    brick_size : int or "auto"
        GCP triangulates the band in bricks of this many spacings (0: one triangulation; "auto":
        the largest of 256 down to 96 that makes at least 4 bricks per thread, else 64).
    brick_halo : float
        First halo around a brick in spacings (0: automatic).
    depth : int or "auto"
        Poisson octree depth; "auto" follows the grid's resolution.
    full_depth, alpha, samples_per_node, scale, boundary, solver_tolerance, finest_solver_tolerance, degree
        Screened Poisson options, as in :func:`poisson`.
    refine_dilation : int or "auto"
        As in :func:`poisson`; "auto": 2 below 256 samples per axis, 1 from 256 (CLI
        ``--refine-dilation``).
    batch_size : int
        Points per call of a callable ``sdf``.
    strict : bool
        Where GCP cannot trust the values rescaled to distances, it runs again on the values
        as given (``stats["rescale_dropped"]``), and where it cannot trust those either it
        returns marching cubes' mesh (``stats["fallback"]``), each with a ``FallbackWarning``;
        ``strict=True`` raises ValueError instead.
    refine : bool or "auto"
        GCP with a callable ``sdf``: move each vertex along its normal onto the callable's zero
        set (two secant steps, each move at most half a spacing; a vertex whose field does not
        increase outward stays). "auto": on for a callable with GCP. Costs 5 evaluations per
        vertex (``stats["refined_vertices"]``, ``stats["refine_evaluations"]``; the sampler's
        own are ``stats["evaluations"]``).
    progress : bool or callable
        True: stage messages and a bar with a fraction and ETA for the long stages on stderr. A
        callable ``progress(stage, done, total)`` receives the same instead, on the calling
        thread (for example a tqdm bar's update): a stage's start as ``(message, 0, 0)``, then
        its fractions (bricks of contact points or of a callable's marching cubes, the Poisson
        solve's cells).
    level : float
        Contour the level set ``f = level`` instead of the zero set (scikit-image's ``level``):
        the values less ``level`` are contoured.
    spacing, origin : 3 numbers (or one), optional
        scikit-image's placement, instead of ``bounds``: sample ``[i, j, k]`` at
        ``origin + (i, j, k) * spacing`` (defaults: origin 0, spacing 1 when either is given).
        For grids and callables.
    return_normals : bool
        Also return vertex normals (see Returns).
    grid_name : str, optional
        The float grid to read from a ``.vdb`` (default: the first).
    lipschitz : float
        For a callable: how fast it may change, per unit length (1 for a distance). The sampler
        skips the points whose coarser neighbours show them farther than the band from the
        surface, which holds only for fields no steeper than this. It checks: where the
        callable's coarse samples change faster (beyond 1.5x), or a value undercuts the bound
        its neighbours gave, it warns (``LipschitzWarning``) and samples again with a larger
        bound, so small parts are never skipped silently. Give the bound of a field that is not
        a distance (for example 3 for 3x a distance) to skip the first pass.
    return_stats : bool
        Also return a dict of counts (samples, band samples, for a callable the evaluations) and
        ``stats["seconds"]``, the seconds spent in each stage (as the CLI's ``--stats``).

    Returns
    -------
    V : ndarray (n, 3) float64
        Vertices.
    F : ndarray (m, 3) int32
        Triangles, counter-clockwise seen from outside.
    normals : ndarray (n, 3) float64
        Only with ``return_normals=True``: unit vertex normals along the field's gradient
        (outward): central differences of the grid interpolated trilinearly (as scikit-image), of
        a callable at the vertex, or the mesh's area-weighted normals for scattered samples.
    stats : dict
        Only with ``return_stats=True``; among its counts ``closed``, ``manifold`` and
        ``components`` describe the mesh.

    The result is a :class:`Mesh`: it unpacks as above (``V, F = ...``) and also names its
    parts, ``mesh.V``, ``mesh.F``, ``mesh.normals`` (None unless asked for) and ``mesh.stats``.

    Raises
    ------
    ValueError
        NaN or infinite values, a wrong shape, an empty grid, no sign change, bad options.
    KeyboardInterrupt
        Ctrl-C (the computation stops at its next stage, brick or solver iteration).

    Notes
    -----
    A callable is evaluated coarse to fine: on a coarse grid first, then at each finer level only
    at points whose distance to the surface, bounded below from the coarser values (a distance
    changes by at most the distance moved), may be within the band. The result is the mesh of the
    full grid, from a small fraction of its evaluations (``stats["evaluated_fraction"]``).

    Examples
    --------
    >>> V, F = sdfcontour.contour(grid, bounds=(-1, 1), method="mc")
    >>> V, F = sdfcontour.contour(samples)                  # (n, 4) scattered samples
    """
    sdf, sample_spacing, truncation_found = _from_path(sdf, grid_name)
    if truncation_found is not None and truncation == "auto":
        truncation = repr(truncation_found)  # a level set's background is its truncation
    sdf = _at_level(sdf, level)
    bounds = _placement(sdf, bounds, spacing, origin, resolution)
    o = _options(method, band, margin, truncation, gradient, weights, knn, fn, tie_tolerance,
                 brick_size, brick_halo, depth, full_depth, alpha, samples_per_node, scale, boundary,
                 solver_tolerance, progress, finest_solver_tolerance)
    o["degree"] = _degree(degree)
    o["sign_constraints"] = _switch("sign_constraints", sign_constraints)
    if not isinstance(carve, (bool, _np.bool_)):
        raise ValueError(f"carve must be True or False, got {carve!r}")
    o["carve"] = bool(carve)
    o["side_passes"] = _count_or_auto("side_passes", side_passes, 100)
    o["projection"] = _switch("projection", projection)
    if reconstruction not in ("auto", "poisson", "local"):
        raise ValueError(f"reconstruction must be 'auto', 'poisson' or 'local', "
                         f"got {reconstruction!r}")
    # A callable is most often a neural SDF, only roughly a distance: there the local
    # reconstruction, refined on the callable, lies 6-8x closer to its zero set than marching
    # cubes, where Poisson gives up on the whole mesh or gains 20% (bench/neural.py).
    if reconstruction == "auto" and callable(sdf):
        reconstruction = "local"
    o["reconstruction"] = reconstruction
    o["subdivisions"] = _count_or_auto("subdivisions", subdivisions, 4)
    o["adaptivity"] = _checks.in_range("adaptivity", adaptivity)
    if isinstance(refine_dilation, str) and refine_dilation == "auto":
        o["refine_dilation_text"] = "auto"
    else:
        o["refine_dilation"] = _refine_dilation(refine_dilation)
    refine = _switch("refine", refine)
    o["fallback_to_mc"] = not _checks.flag("strict", strict)
    out = _run(sdf, bounds, resolution, batch_size, o, True, False, sample_spacing,
               _lipschitz(lipschitz))
    if callable(sdf) and method == "gcp" and refine != "off":
        from ._callable import refine_on_zero_set
        lo, hi = _bounds(bounds)
        h = float(((hi - lo) / (int(resolution) - 1)).max())
        out["V"], moved, evaluations = refine_on_zero_set(sdf, out["V"], out["F"], h,
                                                          int(batch_size))
        out["stats"]["refined_vertices"] = moved
        out["stats"]["refine_evaluations"] = evaluations
    normals = None
    if _checks.flag("return_normals", return_normals):
        normals = _normals_of(sdf, bounds, resolution, out, int(batch_size))
    unpack = ("V", "F") + (("normals",) if normals is not None else ()) + \
        (("stats",) if _checks.flag("return_stats", return_stats) else ())
    return Mesh(out["V"], out["F"], normals, out["stats"], unpack)


def contact_points(sdf, bounds=None, *, resolution=None, band="auto", margin=1.0, truncation="auto",
                   gradient="regular", weights="james", knn=18, fn=False, tie_tolerance=1e-6,
                   brick_size="auto", brick_halo=0.0, batch_size=65536, progress=False,
                   grid_name=None, lipschitz=1.0, return_stats=False):
    """GCP's contact points with their normals, without the surface reconstruction.

    Parameters are those of :func:`contour`. A callable is sampled near its surface only (the
    band's bricks), never on the full grid.

    Returns
    -------
    P : ndarray (k, 3) float64
        Contact points c = p - value * n.
    N : ndarray (k, 3) float64
        Unit outward normals.
    stats : dict
        Only with ``return_stats=True``: as :func:`contour`'s (for a callable, its evaluations).

    Examples
    --------
    >>> P, N = sdfcontour.contact_points(grid, weights="james")
    """
    sdf, sample_spacing, truncation_found = _from_path(sdf, grid_name)
    if truncation_found is not None and truncation == "auto":
        truncation = repr(truncation_found)
    o = _options("gcp", band, margin, truncation, gradient, weights, knn, fn, tie_tolerance,
                 brick_size, brick_halo, "auto", 5, 10.0, 1.5, 1.1, "neumann", 1e-4, progress)
    out = _run(sdf, bounds, resolution, batch_size, o, False, True, sample_spacing,
               _lipschitz(lipschitz))
    if _checks.flag("return_stats", return_stats):
        return out["P"], out["N"], out["stats"]
    return out["P"], out["N"]


def _refine_dilation(value):
    if isinstance(value, (int, _np.integer)) and not isinstance(value, (bool, _np.bool_)) \
            and 1 <= value <= 4:
        return int(value)
    raise ValueError(f"refine_dilation must be a whole number from 1 to 4 (or 'auto' for contour), "
                     f"got {value!r}")


def poisson(P, N, *, weights=None, depth=8, alpha=10.0, full_depth=5, samples_per_node=1.5,
            scale=1.1, boundary="neumann", solver_tolerance=1e-4, finest_solver_tolerance=1e-3,
            refine_dilation=2, degree=1):
    """Screened Poisson reconstruction of oriented points: a watertight mesh.

    Parameters
    ----------
    P : ndarray (n, 3)
        Points.
    N : ndarray (n, 3)
        Outward normals (any non-zero length).
    weights : ndarray (n,), optional
        Confidence of each point in (0, 1]: its normal and screening terms are scaled by it, so a
        less reliable point pulls the surface less. None: every point weighs 1.
    depth : int
        Finest octree depth (the domain cube split 2^depth times).
    alpha : float
        Screening weight (PoissonRecon's pointWeight); 0 is plain Poisson.
    full_depth : int
        The octree is complete down to this depth.
    samples_per_node : float
        Splat each normal where an octree node holds about this many points.
    scale : float
        The domain cube is the points' bounding cube enlarged by this factor.
    boundary : {"neumann", "dirichlet", "free"}
        Boundary condition on the domain cube.
    solver_tolerance : float
        Conjugate gradients stop at this relative residual at each depth but the finest.
    finest_solver_tolerance : float
        ... and at this one at the finest depth (most of the solve's time).
    refine_dilation : int
        Each depth refines the cells within this many cells (1-4) of the points' cells: 1 is
        cheaper and less accurate where points are sparse (CLI ``--refine-dilation``).
    degree : {1, 2}
        The elements: 1, trilinear; 2, quadratic B-splines (PoissonRecon's default), smoother
        and slower (CLI ``--degree``).

    Returns
    -------
    V : ndarray (n, 3) float64
    F : ndarray (m, 3) int32

    Examples
    --------
    >>> V, F = sdfcontour.poisson(P, N, depth=8, alpha=10)
    """
    o = dict(depth=_checks.in_range("depth", depth, whole=True),
             refine_dilation=_refine_dilation(refine_dilation), degree=_degree(degree),
             **_poisson_options(full_depth, alpha, samples_per_node, scale, boundary,
                                solver_tolerance, finest_solver_tolerance))
    _full_depth_within(o)
    P = _checks.points("P", P)
    N = _checks.points("N", N)
    if len(N) != len(P):
        raise ValueError(f"P and N must have the same number of rows, got {len(P)} and {len(N)}")
    if len(P) == 0:
        raise ValueError("P is empty: no points to reconstruct from")
    W = None
    if weights is not None:
        W = _checks.numbers_array("weights", weights).astype(_np.float64)
        if W.shape != (len(P),):
            raise ValueError(f"weights must have shape ({len(P)},), got {W.shape}")
        if not _np.all((W > 0) & (W <= 1)):
            raise ValueError("weights must lie in (0, 1]")
    return _sdfcontour.poisson(P, N, W, o)


def sample(V, F, resolution=64, bounds=None, scale=0.9, return_mesh=False):
    """Signed distances of a closed mesh on a resolution^3 grid (negative inside), placed as the
    CLI's ``sample`` places it.

    Parameters
    ----------
    V : ndarray (n, 3)
        Vertices.
    F : ndarray (m, 3)
        Triangles of a closed, consistently oriented mesh.
    resolution : int
        Samples per axis (2 to 1024).
    bounds : (lo, hi), optional
        The grid's box, default (-1, 1).
    scale : float or None
        The mesh is first moved and scaled uniformly so that its bounding box is centred at the
        origin and its longest side spans [-scale, scale] (default 0.9, as the CLI). None samples
        the mesh where it lies (parts outside the bounds are then cut off by the box).
    return_mesh : bool
        Also return the vertices as sampled (V moved and scaled), to compare meshes with.

    Returns
    -------
    grid : ndarray (resolution, resolution, resolution) float64
    V_sampled : ndarray (n, 3), with ``return_mesh``

    Examples
    --------
    >>> grid, V_unit = sdfcontour.sample(V, F, resolution=64, return_mesh=True)
    >>> grid = sdfcontour.sample(V, F, resolution=64, bounds=(0, 1), scale=None)
    """
    lo, hi = _bounds(bounds)
    V = _checks.points("V", V)
    F = _checks.faces("F", F, len(V))
    if scale is None:
        half_extent = 0.0
    else:
        half_extent = float(_checks.number("scale", scale))
        if not 1e-6 <= half_extent <= 1e6:
            raise ValueError(f"scale must be from 1e-06 to 1e+06 (or None), got {scale!r}")
    grid, V_sampled = _sdfcontour.sample(
        V, F, _checks.in_range("resolution", resolution, whole=True), lo, hi, half_extent)
    return (grid, V_sampled) if _checks.flag("return_mesh", return_mesh) else grid


def distances(V, F, V_gt, F_gt, samples=200000, seed=1):
    """Distances between a mesh and the ground truth, from area-uniform samples on both.

    Returns
    -------
    dict
        ``L1`` (mean of the two directed mean distances), ``L2``, ``L_inf`` (Hausdorff), the
        directed ``recon_to_gt`` and ``gt_to_recon`` mean/rms/max, ``closed`` and
        ``components`` of the first mesh.

    Examples
    --------
    >>> sdfcontour.distances(V, F, V_gt, F_gt)["L1"]
    """
    V, V_gt = _checks.points("V", V), _checks.points("V_gt", V_gt)
    F, F_gt = _checks.faces("F", F, len(V)), _checks.faces("F_gt", F_gt, len(V_gt))
    _checks.number("samples", samples)
    if not (isinstance(samples, (int, _np.integer)) and 1 <= samples <= 100_000_000):
        raise ValueError(f"samples must be a whole number from 1 to 100000000, got {samples!r}")
    if not (isinstance(seed, (int, _np.integer)) and 0 <= seed < 2**64):
        raise ValueError(f"seed must be a whole number from 0 to 2**64 - 1, got {seed!r}")
    return _sdfcontour.distances(V, F, V_gt, F_gt, int(samples), int(seed))


def read_mesh(path):
    """A triangle mesh from an OBJ, PLY (ASCII or binary) or OFF file; polygons are fan-split.

    Returns
    -------
    V : ndarray (n, 3) float64
    F : ndarray (m, 3) int32

    Raises
    ------
    OSError
        The file cannot be opened or read.
    ValueError
        The file is malformed, or has no faces, or a face indexes a missing vertex.

    Examples
    --------
    >>> V_gt, F_gt = sdfcontour.read_mesh("bunny.obj")
    """
    return _sdfcontour.read_mesh(str(path))


def write_mesh(path, V, F, ascii=False):
    """Writes a mesh as PLY (binary unless ``ascii``), OBJ, OFF or binary STL (float32, no shared
    vertices), by the extension; atomically (a failed write leaves no file).

    Examples
    --------
    >>> sdfcontour.write_mesh("out.ply", V, F)
    """
    V = _checks.points("V", V)
    F = _checks.faces("F", F, len(V))
    if len(F) == 0:
        raise ValueError("the mesh is empty (F has no rows): nothing to write")
    _sdfcontour.write_mesh(str(path), V, F, _checks.flag("ascii", ascii))

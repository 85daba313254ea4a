"""Running the core on an array, a file or a callable, and the warnings about what it did."""
import warnings as _warnings

import numpy as _np

from . import _checks, _sdfcontour
from ._arguments import _bounds, _check_callable_arguments
from ._warning_types import DroppedSamplesWarning, FallbackWarning, LipschitzWarning, RescaleWarning

# The gradients with which GCP's local reconstruction runs brick by brick (the core's
# local_gradients): the regular triangulation's, the lattice's, or the choice between them.
_LOCAL_GRADIENTS = ("auto", "regular", "lattice")


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


# A .npy path larger than this is memory-mapped instead of read (a 1024^3 float32 grid is 4 GiB).
MAPPED_NPY_BYTES = 2 << 30


def _from_path(sdf, grid_name):
    """A path as the samples: a .npy read (a grid or (n, 4) samples; memory-mapped above
    MAPPED_NPY_BYTES), a .vdb level set read sparse as the CLI reads it (its voxel size the
    spacing, its background the truncation unless one is given). Returns (samples, spacing of scattered samples or 0, truncation or
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
            # Read into memory: a mapped file that another process truncates while it is read
            # kills the interpreter (SIGBUS). Only a file larger than that is mapped, as
            # np.load(path, mmap_mode="r") would be, and must then stay as it is.
            mapped = os.path.getsize(path) > MAPPED_NPY_BYTES
            return _np.load(path, mmap_mode="r" if mapped else None, allow_pickle=False), 0.0, None
        except ValueError as error:
            raise ValueError(f"cannot read '{path}' as .npy: {error}") from None
    if path.lower().endswith(".vdb"):
        points, values, voxel, background = _sdfcontour.read_vdb(path, grid_name or "")
        return _np.column_stack([points, values.reshape(-1)]), float(voxel), float(background)
    raise ValueError(f"cannot read '{path}': give a .npy or .vdb path, an array or a callable")


def _vdb_by_boxes(sdf, method, reconstruction, gradient, band, level):
    """The path of a .vdb level set that marching cubes or GCP's local reconstruction read box by
    box (as the CLI does: a mesh, of GCP on a finite band, of the level set's own zero set), or
    None."""
    import os
    if not isinstance(sdf, (str, os.PathLike)) or not os.fspath(sdf).lower().endswith(".vdb"):
        return None
    local = reconstruction == "local" or (
        reconstruction == "auto" and gradient in _LOCAL_GRADIENTS and
        not (isinstance(band, str) and band == "all"))
    boxes = method == "mc" or (method == "gcp" and local)
    return os.fspath(sdf) if boxes and level == 0 else None


def _run_vdb(path, grid_name, options):
    """A .vdb level set read box by box, never whole, for marching cubes or GCP's local
    reconstruction; its background is its truncation unless one is given."""
    options = dict(options)
    callback = options.pop("progress_callback", None)
    return _sdfcontour.contour_vdb(path, grid_name or "", options, callback)


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
             options["gradient"] in _LOCAL_GRADIENTS and want_mesh and not want_points)
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
    if out["stats"].get("value_scale", 1.0) != 1.0:
        _warnings.warn(f"the values were rescaled by {out['stats']['value_scale']:.4g} to "
                       f"distances (they change by {1 / out['stats']['value_scale']:.4g} per unit "
                       f"length near the surface)", RescaleWarning, stacklevel=3)
    if out["stats"].get("isolated_samples", 0) > 0:
        _warnings.warn(f"dropped {out['stats']['isolated_samples']} isolated samples (fewer than "
                       f"3 others within 4 spacings): strays far from the rest cannot place the "
                       f"surface", DroppedSamplesWarning, stacklevel=3)
    return out


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
    if isinstance(sdf, str) and sdf.lower().endswith(".vdb"):  # read box by box: the mesh's own
        from ._callable import vertex_normals
        return vertex_normals(V, out["F"])
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

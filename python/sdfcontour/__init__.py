"""sdfcontour: contour samples of a signed distance function into a triangle mesh.

Numpy in, numpy out. The default method is GCP ("Contouring Signed Distance Fields by
Approximating Gradients"): contact points from the regular triangulation of the samples near the
surface, then screened Poisson reconstruction. Marching cubes (``method="mc"``), marching
tetrahedra (``"mt-rt"``, ``"mt-dt"``) are there too.

Conventions: a grid ``a`` of shape (nx, ny, nz) has ``a[i, j, k]`` at ``lo + (i*hx, j*hy, k*hz)``
over ``bounds=(lo, hi)`` (default ``(-1, 1)``, samples at both ends); values are negative inside;
normals point outward. Bad input raises ``ValueError`` (with the command-line tool's message),
files ``OSError``; Ctrl-C raises ``KeyboardInterrupt``.

Examples
--------
>>> import numpy as np, sdfcontour
>>> x = np.linspace(-1, 1, 64)
>>> grid = np.linalg.norm(np.stack(np.meshgrid(x, x, x, indexing="ij")), axis=0) - 0.6
>>> V, F = sdfcontour.contour(grid)                    # GCP
>>> V, F = sdfcontour.contour(grid, method="mc")       # marching cubes
>>> V, F = sdfcontour.contour(lambda p: np.linalg.norm(p, axis=1) - 0.6, resolution=128)
"""
import numpy as np

from . import _sdfcontour

__all__ = ["contour", "contact_points", "poisson", "sample", "distances", "read_mesh", "write_mesh"]

METHODS = ("gcp", "gtcp", "mc", "mt-rt", "mt-dt")


def _bounds(bounds):
    """(lo, hi) as two float arrays of 3, from scalars or 3-sequences."""
    if bounds is None:
        bounds = (-1.0, 1.0)
    try:
        lo, hi = bounds
        lo = np.broadcast_to(np.asarray(lo, dtype=float), (3,)).copy()
        hi = np.broadcast_to(np.asarray(hi, dtype=float), (3,)).copy()
    except (TypeError, ValueError):
        raise ValueError("bounds must be (lo, hi), each a number or 3 numbers") from None
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)) and np.all(lo < hi)):
        raise ValueError("bounds: lo must be less than hi on every axis, all finite")
    return lo, hi


def _brick_size(brick_size):
    if isinstance(brick_size, str):
        if brick_size != "auto":
            raise ValueError(f"brick_size must be a whole number or 'auto', got {brick_size!r}")
        return -1  # the core chooses
    if int(brick_size) < 0:
        raise ValueError("brick_size must be >= 1, 0 for no bricks, or 'auto'")
    return int(brick_size)


def _degree(degree):
    """The Poisson elements' degree, checked: 1 or 2."""
    if isinstance(degree, bool) or degree not in (1, 2):
        raise ValueError(f"degree must be 1 or 2, got {degree!r}")
    return int(degree)


def _options(method, band, margin, truncation, gradient, weights, knn, fn, tie_tolerance,
             brick_size, brick_halo, depth, full_depth, alpha, samples_per_node, scale, boundary,
             solver_tolerance, progress, finest_solver_tolerance=1e-3):
    if method not in METHODS:
        raise ValueError(f"unknown method '{method}' (known: {', '.join(METHODS)})")
    auto_band = isinstance(band, str) and band == "auto"
    if band == "all":
        band = float("inf")
    elif auto_band:
        band = 0.0  # the core picks it from the resolution
    o = dict(method=method, band=float(band), margin=float(margin), truncation=str(truncation),
             gradient=gradient, weights=weights, knn=int(knn), fn=bool(fn),
             tie_tolerance=float(tie_tolerance), brick_size=_brick_size(brick_size),
             brick_halo=float(brick_halo), full_depth=int(full_depth), alpha=float(alpha),
             samples_per_node=float(samples_per_node), scale=float(scale), boundary=boundary,
             solver_tolerance=float(solver_tolerance),
             finest_solver_tolerance=float(finest_solver_tolerance), progress=bool(progress))
    if depth == "auto":
        o["depth_text"] = "auto"
    else:
        o["depth"] = int(depth)
    for name in ("band", "margin", "alpha", "samples_per_node", "scale", "solver_tolerance",
                 "finest_solver_tolerance"):
        if not o[name] == o[name]:  # NaN
            raise ValueError(f"{name} must be a number, got NaN")
    if not (o["band"] > 0 or auto_band):
        raise ValueError("band must be positive (or 'all' or 'auto')")
    if not (0 <= o["alpha"] <= 1e4):
        raise ValueError("alpha must be between 0 and 10000")
    if depth != "auto" and not (1 <= o["depth"] <= 16):
        raise ValueError("depth must be between 1 and 16, or 'auto'")
    return o


def _input_array(sdf):
    """The samples as an array the core reads: a grid, an (n, 4) array, or (points, values)."""
    if isinstance(sdf, tuple) and len(sdf) == 2:
        points, values = (np.asarray(a, dtype=float) for a in sdf)
        if points.ndim != 2 or points.shape[1] != 3 or values.shape != (points.shape[0],):
            raise ValueError("(points, values) must have shapes (n, 3) and (n,)")
        return np.column_stack([points, values])
    array = np.asarray(sdf)
    if array.dtype.kind not in "fiu":
        raise ValueError(f"the samples must be numbers, got an array of dtype {array.dtype}")
    return array


def _run(sdf, bounds, resolution, batch_size, options, want_mesh, want_points):
    lo, hi = _bounds(bounds)
    stats = {}
    if callable(sdf):
        if resolution is None:
            raise ValueError("a callable SDF needs a resolution (samples per axis)")
        from ._callable import sample_callable
        # The band the core will use (0: auto, from the samples per axis).
        band = options["band"] or _sdfcontour.auto_band(int(resolution))
        threshold = band + options["margin"]
        if options["method"] == "mc":
            threshold = 1.0  # marching cubes needs the signs right and the values at crossings
        array, evaluations = sample_callable(sdf, lo, hi, int(resolution), threshold,
                                             int(batch_size), options["progress"])
        options = dict(options, truncation="none")
        stats["evaluations"] = evaluations
        stats["evaluated_fraction"] = evaluations / float(int(resolution) ** 3)
    else:
        if resolution is not None:
            raise ValueError("resolution is for a callable SDF; a grid has its own shape")
        array = _input_array(sdf)
    out = _sdfcontour.contour(array, lo, hi, 0.0, options, want_mesh, want_points)
    out["stats"].update(stats)
    return out


def _count_or_auto(name, value, most):
    """-1 for "auto", else a whole number from 0 to `most`; ValueError otherwise."""
    if isinstance(value, str) and value == "auto":
        return -1
    if isinstance(value, (int, np.integer)) and not isinstance(value, bool) and 0 <= value <= most:
        return int(value)
    raise ValueError(f"{name} must be a whole number from 0 to {most} or 'auto', got {value!r}")


def _switch(name, value):
    """True, False or "auto" as the library's on/off/auto; anything else is a ValueError."""
    if isinstance(value, str) and value == "auto":
        return "auto"
    if isinstance(value, (bool, np.bool_)):
        return "on" if value else "off"
    raise ValueError(f"{name} must be True, False or 'auto', got {value!r}")


def contour(sdf, bounds=None, method="gcp", *, resolution=None, band="auto", margin=1.0,
            truncation="auto", gradient="regular", weights="james", knn=18, fn=False,
            tie_tolerance=1e-6, brick_size="auto", brick_halo=0.0, depth="auto", full_depth=5,
            alpha=10.0, samples_per_node=1.5, scale=1.1, boundary="neumann",
            solver_tolerance=1e-4, finest_solver_tolerance=1e-3, sign_constraints="auto",
            carve=True, side_passes="auto", projection="auto", refine_dilation="auto",
            degree=1, reconstruction="auto", subdivisions="auto", batch_size=65536,
            progress=False, return_stats=False):
    """Contour signed distance samples into a triangle mesh.

    Parameters
    ----------
    sdf : ndarray (nx, ny, nz), ndarray (n, 4), tuple (points (n, 3), values (n,)), or callable
        A grid of signed distances (float32 or float64; read in place when C-contiguous),
        scattered samples (rows x, y, z, value), or a function ``f(points (k, 3)) -> (k,)``
        that is sampled on a ``resolution``^3 grid only near the surface (see Notes).
    bounds : (lo, hi), optional
        The grid's box: positions of the first and last samples, each a number or 3 numbers.
        Default (-1, 1). Ignored for scattered samples.
    method : {"gcp", "mc", "mt-rt", "mt-dt"}
        GCP (default), marching cubes (grids only), marching tetrahedra on the regular or the
        Delaunay triangulation.
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
        contact points in it; topology from the samples' signs; grids and callables only), or
        "auto" (poisson, measured more accurate so far: docs/local.md). CLI
        ``--reconstruction``.
    subdivisions : int or "auto"
        Local reconstruction: midpoint subdivisions before projection onto the contact points
        (0 to 4; "auto": 2 below 48 samples per axis, 1 below 192, else 0).
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
    progress : bool
        Show the stages on stderr.
    return_stats : bool
        Also return a dict of counts (samples, band samples, for a callable the evaluations) and
        ``stats["seconds"]``, the seconds spent in each stage (as the CLI's ``--stats``).

    Returns
    -------
    V : ndarray (n, 3) float64
        Vertices.
    F : ndarray (m, 3) int32
        Triangles, counter-clockwise seen from outside.
    stats : dict
        Only with ``return_stats=True``.

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
    o = _options(method, band, margin, truncation, gradient, weights, knn, fn, tie_tolerance,
                 brick_size, brick_halo, depth, full_depth, alpha, samples_per_node, scale, boundary,
                 solver_tolerance, progress, finest_solver_tolerance)
    o["degree"] = _degree(degree)
    o["sign_constraints"] = _switch("sign_constraints", sign_constraints)
    if not isinstance(carve, (bool, np.bool_)):
        raise ValueError(f"carve must be True or False, got {carve!r}")
    o["carve"] = bool(carve)
    o["side_passes"] = _count_or_auto("side_passes", side_passes, 100)
    o["projection"] = _switch("projection", projection)
    if reconstruction not in ("auto", "poisson", "local"):
        raise ValueError(f"reconstruction must be 'auto', 'poisson' or 'local', "
                         f"got {reconstruction!r}")
    o["reconstruction"] = reconstruction
    o["subdivisions"] = _count_or_auto("subdivisions", subdivisions, 4)
    if isinstance(refine_dilation, str) and refine_dilation == "auto":
        o["refine_dilation_text"] = "auto"
    else:
        o["refine_dilation"] = _refine_dilation(refine_dilation)
    out = _run(sdf, bounds, resolution, batch_size, o, True, False)
    if return_stats:
        return out["V"], out["F"], out["stats"]
    return out["V"], out["F"]


def contact_points(sdf, bounds=None, *, resolution=None, band="auto", margin=1.0, truncation="auto",
                   gradient="regular", weights="james", knn=18, fn=False, tie_tolerance=1e-6,
                   brick_size="auto", brick_halo=0.0, batch_size=65536, progress=False):
    """GCP's contact points with their normals, without the surface reconstruction.

    Parameters are those of :func:`contour`.

    Returns
    -------
    P : ndarray (k, 3) float64
        Contact points c = p - value * n.
    N : ndarray (k, 3) float64
        Unit outward normals.

    Examples
    --------
    >>> P, N = sdfcontour.contact_points(grid, weights="james")
    """
    o = _options("gcp", band, margin, truncation, gradient, weights, knn, fn, tie_tolerance,
                 brick_size, brick_halo, "auto", 5, 10.0, 1.5, 1.1, "neumann", 1e-4, progress)
    out = _run(sdf, bounds, resolution, batch_size, o, False, True)
    return out["P"], out["N"]


def _refine_dilation(value):
    if isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_)) \
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
    o = dict(depth=int(depth), alpha=float(alpha), full_depth=int(full_depth),
             samples_per_node=float(samples_per_node), scale=float(scale), boundary=boundary,
             solver_tolerance=float(solver_tolerance),
             finest_solver_tolerance=float(finest_solver_tolerance),
             refine_dilation=_refine_dilation(refine_dilation), degree=_degree(degree))
    W = None if weights is None else np.asarray(weights, dtype=np.float64)
    return _sdfcontour.poisson(np.asarray(P), np.asarray(N), W, o)


def sample(V, F, resolution=64, bounds=None):
    """Signed distances of a closed mesh on a resolution^3 grid (negative inside).

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

    Returns
    -------
    grid : ndarray (resolution, resolution, resolution) float64

    Examples
    --------
    >>> grid = sdfcontour.sample(V, F, resolution=64)
    """
    lo, hi = _bounds(bounds)
    return _sdfcontour.sample(np.asarray(V), np.asarray(F), int(resolution), lo, hi)


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
    return _sdfcontour.distances(np.asarray(V), np.asarray(F), np.asarray(V_gt),
                                 np.asarray(F_gt), int(samples), int(seed))


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
    """Writes a mesh as PLY (binary unless ``ascii``) or OBJ, by the extension; atomically (a
    failed write leaves no file).

    Examples
    --------
    >>> sdfcontour.write_mesh("out.ply", V, F)
    """
    _sdfcontour.write_mesh(str(path), np.asarray(V), np.asarray(F), bool(ascii))

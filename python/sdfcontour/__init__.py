"""sdfcontour: contour samples of a signed distance function into a triangle mesh.

Numpy in, numpy out. The default method is GCP ("Contouring Signed Distance Fields by
Approximating Gradients"): contact points from the regular triangulation of the samples near the
surface, then a mesh from them: on grids a local reconstruction (a vertex per surface cell from
the contact points near it), on scattered samples the paper's screened Poisson reconstruction
(``reconstruction=``). Marching cubes (``method="mc"``), marching
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
import inspect as _inspect
import warnings as _warnings

import numpy as _np

from . import _checks, _sdfcontour
from ._arguments import METHODS  # noqa: F401 (the method names, public)
from ._arguments import (_bounds, _count_or_auto, _degree, _full_depth_within, _lipschitz, _options,
                         _poisson_options, _refine_dilation, _split_sag, _switch)
from ._checks import ArgumentTypeError
from ._running import (_at_level, _from_path, _normals_of, _placement, _run, _run_vdb,
                       _vdb_by_boxes)
from ._warning_types import DroppedSamplesWarning, FallbackWarning, LipschitzWarning, RescaleWarning

__all__ = ["Mesh", "contour", "contact_points", "poisson", "sample", "distances", "read_mesh", "write_mesh",
           "ArgumentTypeError", "DroppedSamplesWarning", "FallbackWarning", "LipschitzWarning",
           "RescaleWarning"]


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


def contour(sdf, bounds=None, method="gcp", *, resolution=None, band="auto", margin=1.0,
            truncation="auto", gradient="auto", weights="james", knn=18, fn=False,
            tie_tolerance="auto", brick_size="auto", brick_halo=0.0, depth="auto", full_depth=5,
            alpha=10.0, samples_per_node=1.5, scale=1.1, boundary="neumann",
            solver_tolerance=1e-4, finest_solver_tolerance=1e-3, sign_constraints="auto",
            carve=True, side_passes="auto", projection="auto", refine_dilation="auto",
            degree=1, reconstruction="auto", subdivisions="auto", batch_size=65536,
            refine="auto", strict=False, progress=False, return_stats=False, level=0.0,
            spacing=None, origin=None, return_normals=False, grid_name=None, lipschitz=1.0,
            adaptivity=0.0, zero_set="auto", split_sag="auto", thin_parts="auto",
            edge_fans="auto"):
    """Contour signed distance samples into a triangle mesh.

    Parameters
    ----------
    sdf : ndarray (nx, ny, nz), ndarray (n, 4), tuple (points (n, 3), values (n,)), callable, or path
        A grid of signed distances (float32 or float64; read in place when C-contiguous),
        scattered samples (rows x, y, z, value), a function ``f(points (k, 3)) -> (k,)``
        that is sampled on a ``resolution``^3 grid only near the surface (see Notes), or a
        path: a ``.npy`` (memory-mapped) or an OpenVDB ``.vdb`` float level set, read as the CLI
        reads it (its background the truncation): for GCP's local reconstruction box by box on
        its voxels' grid, never whole; otherwise sparse, its active voxels as scattered samples
        with its voxel size as the spacing.
    bounds : (lo, hi), optional
        The grid's box: positions of the first and last samples, each a number or 3 numbers.
        Default (-1, 1). Ignored for scattered samples.
    method : {"gcp", "gtcp", "mc", "mt-rt", "mt-dt"}
        GCP (default), GTCP (exact contact points: built-in shapes, CLI only), marching cubes
        (grids and .vdb level sets), marching tetrahedra on the regular or the Delaunay triangulation.
    resolution : int, optional
        Samples per axis for a callable ``sdf``.
    band : float, "auto" or "all"
        Triangulation methods use the samples with ``|value| <= band`` grid spacings; "auto"
        is 8 below 128 samples per axis, 4 from 128 and 3 from 256 (docs/band.md), and for GCP's
        local reconstruction (the default on grids and callables) 8 below 384 and 3 from 384
        (docs/notes/local.md); "all" keeps every sample (the paper's GCP, far slower).
    margin : float
        Samples up to this many spacings beyond the band close the band's stars.
    truncation : "auto", "none" or a number (or a number as text)
        Values clamped at +-T (a TSDF) carry no distance: detect ("auto"), none, or given.
    gradient : {"auto", "regular", "delaunay", "knn", "lattice"}
        Where GCP's gradients come from ("lattice": a grid's finite differences, for the local
        reconstruction of grids only; "auto": the lattice's for the local reconstruction of a grid
        with at least 64 samples along its longest axis, the regular triangulation's elsewhere).
    weights : {"james", "volume", "uniform"}
        Averaging of the incident tetrahedra's gradients.
    knn : int
        k for ``gradient="knn"``.
    fn : bool
        +FN: retry a discarded contact point with each incident tet's gradient.
    tie_tolerance : float or "auto"
        Contact point c is discarded only if it is inside another sample's sphere by more than
        this relative tolerance ("auto": 1e-6 for the triangulation's points, 1e-3 for the
        lattice's).
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
        "auto": local for grids and callables (the shared meshes' L1 over marching cubes' at
        32^3 / 64^3: 0.22x / 0.20x, Poisson's 0.31x / 0.34x; a callable refined on it, 0.15x /
        0.17x on a neural SDF at 64^3 / 128^3, Poisson 0.19x / 0.55x; docs/notes/local.md), poisson
        for scattered samples. CLI ``--reconstruction``.
    subdivisions : int or "auto"
        Local reconstruction: midpoint subdivisions before projection onto the contact points
        (0 to 4; "auto": 2 below 64 samples per axis, else 1).
    split_sag : float, "auto" or "off"
        Local reconstruction on grids: after the projection, each edge whose chord sags by more
        than this many spacings (its length times its ends' normals' turn / 8) is split once
        more and its midpoint projected (0 to 1; "auto": 0.002 from 64 to 95 samples per axis,
        else 0.004). CLI ``--split-sag``.
    thin_parts : bool or "auto"
        Local reconstruction on grids: find the parts thinner than a spacing that the samples
        straddle without a sign change (a wing, a blade) from the contact points on their two
        sides, on a grid of twice the resolution with one subdivision fewer ("auto": for arrays
        and files below 192 samples per axis, and from 192 to 256 where at least 0.25% of the edges
        that the surface crosses have a gap beside them, two samples on one side closer together
        than their values allow; off for callables, which may be neural SDFs whose values are no
        distances; the shared meshes' L1 over marching cubes' at 64^3 0.253x -> 0.199x,
        docs/notes/local.md). ``stats["local_thin_points"]`` counts the points put in a thin part.
        With ``edge_fans=True`` only when True. CLI ``--thin-parts``.
    edge_fans : bool or "auto"
        Local reconstruction on grids: fan each grid edge's polygon from a vertex where the
        surface crosses the edge, every vertex kept in its cell, edge or face, so that the mesh
        cannot cross itself or leave a sample on the wrong side with no repair stage (about 3x
        marching cubes' triangles; no subdivision, side rounds or untangling; with ``band=3``,
        bunny, spot and armadillo at 64^3: L1 0.37x marching cubes', the default's 0.23x, in
        0.15x the default's time, docs/choosing.md; with ``thin_parts=True``, on the finer
        grid: 0.22x at 11x its triangles, docs/edge_fans.md). "auto": from 384 samples per axis
        (there about 0.4x the time for 1.4x the L1). ``stats["local_edge_fans"]`` says which
        ran. CLI ``--edge-fans``.
    zero_set : bool or "auto"
        Local reconstruction: move the vertices onto the zero set of the grid's tricubic
        interpolant, uncarved. "auto" (default): where the values are found no exact distances
        (their slope off 1 where the field is smooth, as a neural SDF's grid:
        ``stats["approximate_distances"]``; GCP then takes the local reconstruction and no
        carving: 0.10x / 0.16x marching cubes' L1 to a neural SDF's zero set on its 64^3 / 128^3
        grid, where GCP made 4.4x / 7.3x before); off on exact distances, whose contact points
        are the more accurate. CLI ``--zero-set``.
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
        Where GCP cannot trust the values as distances (clamped within a spacing of the
        surface; on the Poisson path, a mesh off the zero set or from too few contact points),
        it returns marching cubes' mesh (``stats["fallback"]``) with a ``FallbackWarning``, and
        where the local reconstruction keeps no contact point (or, for rescaled values, very
        few) it goes on from the cells' edge crossings; ``strict=True`` raises ValueError
        instead of either.
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
    vdb = _vdb_by_boxes(sdf, method, reconstruction, gradient, band, level)
    if vdb is not None:
        sdf = vdb
        if bounds is not None or spacing is not None or origin is not None:
            raise ValueError("a .vdb level set places itself (its transform): give no bounds, "
                             "spacing or origin")
    else:
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
    # reconstruction, refined on the callable, lies 6-7x closer to its zero set than marching
    # cubes, where Poisson gives up on the whole mesh or gains 20% (bench/neural.py).
    if reconstruction == "auto" and callable(sdf):
        reconstruction = "local"
    o["reconstruction"] = reconstruction
    o["subdivisions"] = _count_or_auto("subdivisions", subdivisions, 4)
    o["split_sag"] = _split_sag(split_sag)
    o["zero_set"] = _switch("zero_set", zero_set)
    o["thin_parts"] = _switch("thin_parts", thin_parts)
    o["edge_fans"] = _switch("edge_fans", edge_fans)
    if o["thin_parts"] == "auto" and callable(sdf):
        # A callable may be a neural SDF, whose values are no exact distances: its contact points
        # then make false thin parts (the fixture at 64^3: 0.15x -> 0.68x marching cubes' L1 to
        # its zero set with them), and no pass measures its values first.
        o["thin_parts"] = "off"
    o["adaptivity"] = _checks.in_range("adaptivity", adaptivity)
    if isinstance(refine_dilation, str) and refine_dilation == "auto":
        o["refine_dilation_text"] = "auto"
    else:
        o["refine_dilation"] = _refine_dilation(refine_dilation)
    refine = _switch("refine", refine)
    o["fallback_to_mc"] = not _checks.flag("strict", strict)
    if vdb is not None:
        if resolution is not None:
            raise ValueError("resolution is for a callable SDF; a grid has its own shape")
        out = _run_vdb(vdb, grid_name, o)
    else:
        out = _run(sdf, bounds, resolution, batch_size, o, True, False, sample_spacing,
                   _lipschitz(lipschitz))
    # Options that the reconstruction which ran does not read are said (the CLI's warning).
    given = locals()
    ran = out["stats"].get("reconstruction")
    if method == "gcp" and ran in ("local", "poisson"):
        other = _POISSON_OPTIONS if ran == "local" else _LOCAL_OPTIONS
        other_given = [name for name in other if _differs(given[name], _CONTOUR_DEFAULTS[name])]
        if other_given and ran == "local":
            _warnings.warn(", ".join(other_given) + " set the Poisson reconstruction, and this "
                           "is the local one (the default on grids): pass "
                           "reconstruction='poisson' for it", stacklevel=2)
        elif other_given:
            _warnings.warn(", ".join(other_given) + " set the local reconstruction, and this is "
                           "the Poisson one (scattered samples take it): pass a grid or a "
                           "callable with reconstruction='local' for it",
                           stacklevel=2)
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


# contour()'s options that only the Poisson path reads, and contour()'s defaults (whether the
# user set them).
_POISSON_OPTIONS = ("depth", "full_depth", "alpha", "samples_per_node", "scale", "boundary",
                    "solver_tolerance", "finest_solver_tolerance", "refine_dilation", "degree",
                    "sign_constraints", "fn")
# ... and those that only the local reconstruction reads.
_LOCAL_OPTIONS = ("subdivisions", "split_sag", "thin_parts", "zero_set", "edge_fans")
_CONTOUR_DEFAULTS = {name: p.default for name, p in _inspect.signature(contour).parameters.items()}


def _differs(value, default):
    return isinstance(value, str) != isinstance(default, str) or value != default


def contact_points(sdf, bounds=None, *, resolution=None, band="auto", margin=1.0, truncation="auto",
                   gradient="regular", weights="james", knn=18, fn=False, tie_tolerance="auto",
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

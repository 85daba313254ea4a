"""sdfcontour.dask: contour a grid larger than one machine, brick by brick, on Dask.

The grid's cells are cut into bricks of ``brick`` cells a side. Each brick is one Dask task: it
reads its samples (marching cubes: plus one more on each high side, the samples of the cells it
owns; GCP: plus a halo wide enough for its contact points' stars) and returns the piece of the
mesh that it owns, its vertices named globally (the grid edge or cell they come from). Pieces are
joined by those names, so the mesh is the single-process mesh bit for bit, whatever ran where.
Dask's scheduler does the rest: placement, retries on a lost worker, a remote cluster.

>>> import sdfcontour.dask
>>> V, F = sdfcontour.dask.contour("big.zarr", method="mc", brick=256)
>>> V, F = sdfcontour.dask.contour("big.zarr", method="gcp")   # the local reconstruction
>>> stats = sdfcontour.dask.contour("big.zarr", out="big.ply", client="tcp://10.0.0.5:8786")
"""
import contextlib
import os
import sys
import time

import numpy as np

from . import _checks, _sdfcontour
from ._arguments import _bounds
from ._bricks import BrickError, brick_piece, bricks, bricks_among, canonical_mesh, gcp_brick_piece
from ._io_join import join_pieces, write_pieces_as_ply

__all__ = ["contour", "bricks", "brick_piece", "gcp_brick_piece", "canonical_mesh", "BrickError"]


# ---------------------------------------------------------------------------------------------
# Sources: picklable readers of one block of samples, opened again on each worker.

class _NpyReader:
    def __init__(self, path):
        self.path = os.fspath(path)
        array = np.load(self.path, mmap_mode="r")  # reads the header only
        self.shape, self.dtype = array.shape, array.dtype

    def read(self, first, dims):
        array = np.load(self.path, mmap_mode="r")
        return np.array(array[tuple(slice(f, f + d) for f, d in zip(first, dims))])


class _ZarrReader:
    def __init__(self, array):
        self.array = array  # a zarr.Array pickles as its store and path, not its data
        self.shape, self.dtype = array.shape, array.dtype

    def read(self, first, dims):
        return self.array[tuple(slice(f, f + d) for f, d in zip(first, dims))]


class _Hdf5Reader:
    def __init__(self, filename, name, shape, dtype):
        self.filename, self.name, self.shape, self.dtype = filename, name, shape, dtype

    def read(self, first, dims):
        import h5py
        with h5py.File(self.filename, "r") as f:
            return f[self.name][tuple(slice(f0, f0 + d) for f0, d in zip(first, dims))]


class _VdbReader:
    """An OpenVDB level set read box by box (never densified whole): the grid is its active
    voxels' bounding box grown by one voxel, in float32; a brick reads its box from the file (only
    the part of the file that the box needs), and bricks that meet no leaf with active voxels are
    not read at all (they hold no surface)."""

    def __init__(self, path, grid_name):
        self.path, self.grid_name = path, grid_name or ""
        layout = _sdfcontour.vdb_layout(self.path, self.grid_name)
        self.grid_name = layout["grid_name"]
        self.first = np.array(layout["min"]) - 1  # the vdb index of grid sample (0, 0, 0)
        self.shape = tuple(int(n) for n in np.array(layout["max"]) - self.first + 2)
        self.dtype = np.dtype(np.float32)
        self.background = float(layout["background"])
        voxel, origin = layout["voxel_size"], np.array(layout["origin"])
        rotation = np.asarray(layout["rotation"], dtype=np.float64)
        # A rotated level set is contoured in its own frame (origin at voxel (0, 0, 0)) and its
        # vertices placed after, as the core's vdb_world_from_grid does.
        self.placement = None
        if not np.array_equal(rotation, np.eye(3)):
            self.placement, origin = (rotation, origin), np.zeros(3)
        self.bounds = (origin + voxel * self.first,
                       origin + voxel * (self.first + np.array(self.shape) - 1))
        self.leaves = np.asarray(layout["leaf_origins"]) - self.first  # in grid indices

    def place(self, arrivals):
        """The pieces of `arrivals` with their vertices in the world (a rotated level set)."""
        rotation, origin = self.placement
        for b, piece in arrivals:
            V = np.asarray(piece[1], np.float64).reshape(-1, 3)
            yield b, (piece[0], V @ rotation + origin, *piece[2:])

    def read(self, first, dims):
        return _sdfcontour.read_vdb_box(self.path, self.grid_name,
                                        tuple(int(f) for f in self.first + np.array(first)),
                                        tuple(int(d) for d in dims))

    def active(self, brick):
        """The indices of the bricks whose samples meet a leaf with active voxels."""
        found = set()
        for lo in self.leaves:
            hi = lo + 7
            ranges = [range(max(0, -(-(int(lo[a]) - brick) // brick)), int(hi[a]) // brick + 1)
                      for a in range(3)]
            found.update((a, b, c) for a in ranges[0] for b in ranges[1] for c in ranges[2])
        return found


class _CallableReader:
    """A callable SDF, to be sampled near the surface only (_callable_tasks): exact where |f| <= `reach`
    (marching cubes needs the signs everywhere and the values at crossings, one spacing; GCP's
    local reconstruction its local_values_reach)."""

    def __init__(self, f, lo, hi, n, batch_size):
        self.f, self.lo, self.batch_size = f, lo, batch_size
        self.h = (hi - lo) / (n - 1)
        self.shape, self.dtype = (n, n, n), np.dtype(np.float64)
        self.reach = float(self.h.max())


# A callable on Dask: each small brick of its grid (_callable_bricks.BRICK cells) that may hold the
# surface is sampled once, by one task; every brick of the reconstruction assembles its block
# from those samples and the other bricks' fill. So a callable that does not repeat itself to
# the last bit (a network on a GPU) still gives every brick the same value for a shared sample.

def _active_task(reader):
    """(the small bricks that may hold the surface, the fill of the others) of a callable."""
    from ._callable import SamplingReport
    from ._callable_bricks import active_bricks
    return active_bricks(reader.f, reader.lo, reader.h, reader.shape[0], reader.reach,
                         reader.batch_size, SamplingReport(), 1.0, fill=True)


def _sample_task(reader, group):
    """{index: samples} of a group of small bricks (index, first, dims)."""
    from ._callable import SamplingReport, sample_blocks
    blocks = sample_blocks(reader.f, reader.lo, reader.h,
                           [(first, dims) for _, first, dims in group], reader.reach,
                           reader.batch_size, SamplingReport())
    return {index: block for (index, _, _), block in zip(group, blocks)}


class _SampledBlocks:
    """Blocks of a callable's grid, assembled from the sampled small bricks of the cells
    [lo, hi) (every one that was sampled there) and the fill of the others."""

    def __init__(self, parts, fill, lo, hi):
        self.arrays = {}
        for part in parts:
            self.arrays.update(part)
        self.fill, self.lo, self.hi = fill, lo, hi

    def read(self, first, dims):
        from ._callable_bricks import BRICK, assemble
        for a in range(3):
            if max(0, first[a] - 1) // BRICK < max(0, self.lo[a] - 1) // BRICK or \
                    (first[a] + dims[a] - 1) // BRICK > max(self.hi[a] - 1, 0) // BRICK:
                raise RuntimeError("internal error: a brick read beyond the samples it was given")
        return assemble(self.arrays, self.fill, first, dims)


def _sampled_gcp_task(parts, fill, lo_cells, hi_cells, index, first, dims, shape, lo, hi, options,
                      truncation):
    blocks = _SampledBlocks(parts, fill, lo_cells, hi_cells)
    return gcp_brick_piece(blocks.read, index, first, dims, shape, lo, hi, options, truncation)


def _sampled_mc_task(parts, fill, lo_cells, hi_cells, index, first, dims, shape, lo, hi):
    block = _SampledBlocks(parts, fill, lo_cells, hi_cells).read(first, dims)
    return brick_piece(block, index, first, shape, lo, hi)


def _callable_tasks(dask_client, reader, shape, lo, hi, brick, options, truncation):
    """The reconstruction's tasks for a callable: its small bricks sampled once each (grouped by
    the brick of `brick` cells that holds their first sample), each brick's block assembled from
    those within its reach."""
    import dask
    from ._callable_bricks import BRICK
    try:
        small, fill = dask_client.compute(dask.delayed(_active_task)(reader)).result()
    except Exception as error:
        raise _one_line(error) from None
    groups = {}
    for entry in small:
        groups.setdefault(tuple(f // brick for f in entry[1]), []).append(entry)
    sampled = {key: dask.delayed(_sample_task, pure=True)(reader, group)
               for key, group in groups.items()}
    # GCP reads a halo around its brick, which doubles where the contact points' stars need it:
    # the samples of two doublings are at hand.
    reach = 4 * int(_sdfcontour.local_brick_halo(options, shape)) if options is not None else 0
    active = {entry[0] for entry in small}
    tasks = []
    for index, first, dims in bricks(shape, brick):
        cells_lo = [max(0, f - reach) for f in first]
        cells_hi = [min(n, f + d + reach) for f, d, n in zip(first, dims, shape)]
        # (A brick with no sampled small brick among its own cells has no sign change.)
        own = [range(max(0, f - 1) // BRICK, max(f, f + d - 2) // BRICK + 1)
               for f, d in zip(first, dims)]
        if not any((i, j, k) in active for i in own[0] for j in own[1] for k in own[2]):
            continue
        near = [range(max(0, c0 - 1) // BRICK, max(c1 - 1, 0) // BRICK + 1)
                for c0, c1 in zip(cells_lo, cells_hi)]
        keys = sorted({tuple(x * BRICK // brick for x in (i, j, k))
                       for i in near[0] for j in near[1] for k in near[2] if (i, j, k) in active})
        parts = [sampled[k] for k in keys]
        if options is not None:
            tasks.append(dask.delayed(_sampled_gcp_task, pure=True)(
                parts, fill, cells_lo, cells_hi, index, first, dims, shape, lo, hi, options,
                truncation))
        else:
            tasks.append(dask.delayed(_sampled_mc_task, pure=True)(
                parts, fill, cells_lo, cells_hi, index, first, dims, shape, lo, hi))
    return tasks


def _open_path(path, dataset):
    text = os.fspath(path)
    if not os.path.exists(text):
        raise OSError(f"cannot read '{text}': no such file or folder")
    lower = text.rstrip("/").lower()
    if lower.endswith(".npy"):
        return _NpyReader(text)
    if lower.endswith(".vdb"):
        return _VdbReader(text, dataset)
    if lower.endswith((".h5", ".hdf5", ".hdf")):
        import h5py
        with h5py.File(text, "r") as f:
            names = []
            f.visititems(lambda name, item: names.append(name)
                         if isinstance(item, h5py.Dataset) else None)
            if dataset is None:
                if len(names) != 1:
                    raise ValueError(f"'{text}' holds {len(names)} datasets {names[:5]}: name one "
                                     f"with dataset=")
                dataset = names[0]
            if dataset not in f or not isinstance(f[dataset], h5py.Dataset):
                raise ValueError(f"'{text}' has no dataset '{dataset}'")
            return _Hdf5Reader(text, dataset, f[dataset].shape, f[dataset].dtype)
    if os.path.isdir(text) or lower.endswith(".zarr"):
        import zarr
        try:
            array = zarr.open(text, mode="r")
        except Exception as e:  # zarr says why in its own words
            raise OSError(f"cannot read '{text}' as zarr: {e}") from None
        if dataset is not None:
            if not isinstance(array, zarr.hierarchy.Group) or dataset not in array:
                raise ValueError(f"'{text}' has no array '{dataset}'")
            array = array[dataset]
        if not isinstance(array, zarr.Array):
            raise ValueError(f"'{text}' is a zarr group: name its array with dataset=")
        return _ZarrReader(array)
    raise ValueError(f"cannot read '{text}': use a .npy, .zarr, .h5, .hdf5 or .vdb path")


def _reader(source, bounds, resolution, batch_size, dataset):
    """A reader for `source`, or a dask array (read through its own graph)."""
    if callable(source):
        if resolution is None:
            raise ValueError("a callable SDF needs a resolution (samples per axis)")
        n = _checks.whole_in("resolution", resolution, 2, 2**31 - 1)
        lo, hi = _bounds(bounds)
        return _CallableReader(source, lo, hi, int(n), int(batch_size))
    if resolution is not None:
        raise ValueError("resolution is for a callable SDF; a grid has its own shape")
    if isinstance(source, (str, os.PathLike)):
        return _open_path(source, dataset)
    module = type(source).__module__.split(".")[0]
    if module == "zarr":
        return _ZarrReader(source)
    if module == "h5py":
        return _Hdf5Reader(source.file.filename, source.name, source.shape, source.dtype)
    if module == "dask" or isinstance(source, np.ndarray):
        return source
    raise _checks.ArgumentTypeError(
        f"source must be a path (.npy, .zarr, .h5), a zarr array, an HDF5 dataset, a dask or "
        f"numpy array, or a callable SDF; got {type(source).__name__}")


def _check_shape_and_dtype(shape, dtype):
    if len(shape) != 3:
        raise ValueError(f"the grid must have 3 axes (nx, ny, nz), got shape {tuple(shape)}")
    if min(shape) < 2:
        raise ValueError(f"the grid needs at least 2 samples on every axis, got {tuple(shape)}")
    if max(shape) > 2**31 - 1:
        raise ValueError(f"the grid has shape {tuple(shape)}: at most 2147483647 samples per axis")
    if np.dtype(dtype).kind not in "fiu":
        raise _checks.ArgumentTypeError(f"the grid must hold real numbers, not {np.dtype(dtype)}")


def _read(source, first, dims):
    """Samples [first, first + dims) of a reader, a numpy array or a dask array (computed here,
    in the task, by the synchronous scheduler)."""
    if hasattr(source, "read"):
        return source.read(first, dims)
    part = source[tuple(slice(f, f + d) for f, d in zip(first, dims))]
    if type(part).__module__.startswith("dask"):
        part = part.compute(scheduler="sync")
    return np.asarray(part)


def _gcp_task(source, index, first, dims, shape, lo, hi, options, truncation):
    return gcp_brick_piece(lambda f, d: _read(source, f, d), index, first, dims, shape, lo, hi,
                           options, truncation)


def _extremes_task(source, index, first, dims):
    """The single process's truncation counts (band.h, truncation_counts) of one brick's own
    samples."""
    try:
        v = np.asarray(_read(source, first, dims))
    except ValueError as e:
        raise BrickError(f"brick {tuple(index)}: {e}") from None
    if not np.isfinite(v).all():
        at = np.unravel_index(int(np.argmin(np.isfinite(v))), v.shape)
        raise BrickError(f"brick {tuple(index)}: the grid has a non-finite value at "
                         f"{[int(f) + int(a) for f, a in zip(first, at)]}")
    return _sdfcontour.truncation_counts(v)


def _gaps_task(source, index, first, own, shape, lo, hi):
    """(gaps, crossings) over the edges from one brick's own samples (subspacing_gaps), read
    with one sample before and two after them."""
    start = [max(f - 1, 0) for f in first]
    end = [min(f + d + 2, n) for f, d, n in zip(first, own, shape)]
    try:
        block = np.asarray(_read(source, start, [e - b for b, e in zip(start, end)]))
    except ValueError as e:
        raise BrickError(f"brick {tuple(index)}: {e}") from None
    own_end = [f + d for f, d in zip(first, own)]
    return _sdfcontour.subspacing_gaps(block, tuple(start), tuple(shape), tuple(lo), tuple(hi),
                                       tuple(first), tuple(own_end))


def _read_and_contour(reader, index, first, dims, shape, lo, hi):
    try:
        block = reader.read(first, dims)
    except ValueError as e:
        raise BrickError(f"brick {tuple(index)}: {e}") from None
    return brick_piece(block, index, first, shape, lo, hi)


# ---------------------------------------------------------------------------------------------
# The client.

@contextlib.contextmanager
def _main_script_hidden():
    """Hides the caller's script from the worker processes that a local cluster spawns: spawn
    runs the main script again in each child (to find its functions), and a script that calls
    contour() without an `if __name__ == "__main__":` guard would start clusters without end.
    Our tasks never need it: cloudpickle sends functions of __main__ by value."""
    main = sys.modules.get("__main__")
    saved = {k: main.__dict__[k] for k in ("__file__", "__spec__") if main and k in main.__dict__}
    try:
        if "__file__" in saved:
            del main.__file__
        if "__spec__" in saved:
            main.__spec__ = None
        yield
    finally:
        if main is not None:
            main.__dict__.update(saved)


def _start_client(client):
    """(client, whether we started it): a local cluster for None, a scheduler for an address."""
    import distributed
    if client is None:
        cluster = distributed.LocalCluster(processes=True, threads_per_worker=1,
                                           dashboard_address=None, silence_logs=40)
        return distributed.Client(cluster), True
    if isinstance(client, str):
        return distributed.Client(client), True
    if not isinstance(client, distributed.Client):
        raise _checks.ArgumentTypeError(f"client must be a dask.distributed Client, a scheduler "
                                        f"address or None, got {type(client).__name__}")
    return client, False


def _stop_client(client):
    cluster = getattr(client, "cluster", None)
    client.close()
    if cluster is not None:
        cluster.close()


def _one_line(error):
    """The exception a failed brick raised, as the caller should see it: the brick's one line,
    without Dask's traceback."""
    import distributed
    if getattr(error, "sdfcontour_from_callable", False):
        return error  # the callable's own exception, its type and message as in one process
    text = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
    if isinstance(error, OSError):
        return OSError(text)
    if isinstance(error, distributed.KilledWorker):
        return RuntimeError(f"a brick's task killed {error.args[-1] if error.args else 'its'} "
                            f"workers (out of memory?): {text}")
    if isinstance(error, ValueError):
        return ValueError(text)
    return RuntimeError(f"{type(error).__name__}: {text}")


def contour(source, bounds=None, method="mc", *, brick=256, client=None, out=None,
            resolution=None, dataset=None, batch_size=65536, band="auto", truncation="auto",
            subdivisions="auto", projection="auto", zero_set="auto", progress=False,
            return_stats=False, split_sag="auto", thin_parts="auto", edge_fans="auto"):
    """Contour a grid too large for one process, brick by brick on Dask.

    Parameters
    ----------
    source : path, zarr array, HDF5 dataset, dask or numpy array, or callable
        The grid (nx, ny, nz) of signed distances: a ``.npy`` file (memory-mapped on each
        worker), a ``.zarr`` folder or zarr array, an ``.h5``/``.hdf5`` file (with ``dataset``)
        or h5py dataset, a dask array, or a callable ``f(points (k, 3)) -> (k,)`` sampled on a
        ``resolution``^3 grid, block by block on the workers and near the surface only; or an
        OpenVDB ``.vdb`` level set (``dataset``: its grid name), read box by box, never
        densified, bricks without active voxels skipped. Each task reads only its brick.
    bounds : (lo, hi), optional
        Positions of the first and last samples, each a number or 3 numbers. Default (-1, 1).
    method : {"mc", "gcp"}
        Marching cubes, or GCP with its local reconstruction (``reconstruction="local"`` of
        :func:`sdfcontour.contour`, brick-local from end to end: the joined mesh equals the
        single process's bit for bit). GCP's screened Poisson solve is global and is not offered
        here; neither are the whole-mesh stages after it (carving).
    brick : int
        Cells per brick side, from 8 (default 256: a float32 brick of 257^3 samples is 68 MB).
        The grid may have at most 2^17 bricks: one task graph holds them all.
    client : dask.distributed.Client, str or None
        The Dask client to run on; a scheduler address ("tcp://host:8786") to connect to; or
        None for a local cluster of one single-threaded worker process per core, closed after.
    out : path, optional
        Stream the joined mesh into this binary PLY (written atomically) instead of returning
        it; the join then holds the mesh's keys on disk, never all pieces in memory.
    resolution : int
        Samples per axis for a callable source.
    dataset : str, optional
        The dataset inside an HDF5 file or zarr group, or the grid inside a ``.vdb``.
    band, subdivisions, projection, split_sag, thin_parts, edge_fans
        GCP: as in :func:`sdfcontour.contour` (thin_parts "auto": off for a callable; from 192 to
        256 samples per axis, the bricks' gaps are counted in a first pass, as the single process
        counts them on the whole grid).
    zero_set : bool or "auto"
        GCP: True moves the vertices onto each brick's tricubic zero set, uncarved: for values
        that are no exact distances (a neural SDF's grid), which :func:`sdfcontour.contour` finds
        by itself. "auto" and False: the values are taken as distances (no pass measures them
        here).
    truncation : "auto", "none" or a number (or a number as text)
        GCP: values clamped at +-T carry no distance. "auto" finds T as the single process does,
        in a first pass over the bricks (one more read of the grid; a ``.vdb``'s background is
        its truncation, a callable has none); "none" skips that pass.
    progress : bool
        Print the bricks done on stderr.

    Returns
    -------
    V : ndarray (n, 3) float64, F : ndarray (m, 3) int32
        Unless ``out`` is given; with ``return_stats``, also a stats dict. With ``out``, the stats
        dict alone: bricks, empty_bricks, vertices, triangles, seconds.

    Raises
    ------
    ValueError
        Bad input: a wrong shape, a NaN (named by brick and [i, j, k]), no surface crossing.
    OSError
        A file that cannot be read or written.
    """
    if method in ("gtcp", "mt-rt", "mt-dt"):
        raise ValueError(f"method '{method}' cannot run brick by brick on Dask: it needs a "
                         f"triangulation of all samples; use method='mc' or 'gcp' here, or "
                         f"sdfcontour.contour() in one process")
    _checks.choice("method", method, ("mc", "gcp"))
    options = None
    if method == "gcp":
        from ._arguments import _count_or_auto, _options, _split_sag, _switch
        options = _options("gcp", band, 1.0, truncation, "auto", "james", 18, False, "auto",
                           "auto", 0.0, "auto", 5, 10.0, 1.5, 1.1, "neumann", 1e-4, False)
        options["reconstruction"] = "local"
        options["subdivisions"] = _count_or_auto("subdivisions", subdivisions, 4)
        options["split_sag"] = _split_sag(split_sag)
        options["projection"] = _switch("projection", projection)
        options["zero_set"] = _switch("zero_set", zero_set)
        options["thin_parts"] = _switch("thin_parts", thin_parts)
        options["edge_fans"] = _switch("edge_fans", edge_fans)
        if options["thin_parts"] == "auto" and callable(source):
            options["thin_parts"] = "off"  # (as contour(): a callable may be no distance)
    # (Smaller bricks cost more halo than cells: GCP's reads ~60 cells beyond its own.)
    brick = _checks.whole_in("brick", brick, 8, 2**20)
    batch_size = _checks.whole_in("batch_size", batch_size, 1, 2**26)
    progress = _checks.flag("progress", progress)
    reader = _reader(source, bounds, resolution, batch_size, dataset)
    shape = tuple(int(n) for n in reader.shape)
    if options is not None and isinstance(reader, _CallableReader):
        # Read as a distance: values are not rescaled here (sdfcontour.contour() does).
        reader.reach = max(_sdfcontour.local_values_reach(options, shape), 4.0) * reader.reach
    _check_shape_and_dtype(shape, reader.dtype)
    # (A level set's bricks are those that meet its leaves: two spheres 1e5 voxels apart make
    # a few hundred, not the 1e11 of their box.)
    count = (len(reader.active(brick)) if isinstance(reader, _VdbReader) else
             np.prod([max(1, -(-(n - 1) // brick)) for n in shape], dtype=np.float64))
    if count > _MAX_BRICKS:
        raise ValueError(f"{shape} samples in bricks of {brick} cells make {count:.3g} bricks, "
                         f"more than {_MAX_BRICKS} tasks for one graph: give a larger brick")
    if isinstance(reader, _VdbReader):
        if bounds is not None:
            raise ValueError("a .vdb level set places itself (its transform): give no bounds")
        lo, hi = reader.bounds
    else:
        lo, hi = _bounds(bounds)
    if out is not None:
        out = os.fspath(out)
        if os.path.isdir(out):
            raise OSError(f"cannot write '{out}': it is a folder")
        if not out.lower().endswith(".ply"):
            raise ValueError(f"cannot write '{out}': sdfcontour.dask writes binary PLY (.ply)")
        parent = os.path.dirname(os.path.abspath(out))
        if not os.path.isdir(parent):
            raise OSError(f"cannot write '{out}': no folder '{parent}'")

    with _main_script_hidden():
        return _contour_on(reader, shape, lo, hi, int(brick), client, out, progress,
                           return_stats, options)


_MAX_BRICKS = 2**17


def _gcp_truncation(dask_client, reader, source, shape, brick, options):
    """(inside, outside): the whole grid's truncation, as the single process finds it."""
    given = options["truncation"]
    if given == "none" or isinstance(reader, _CallableReader):
        return (float("inf"), float("inf"))
    if given != "auto":
        value = _sdfcontour.parse_number(given)  # checked in _options: the core's reading
        return (value, value)
    if isinstance(reader, _VdbReader):
        return (reader.background, reader.background)
    import dask
    tasks = []
    for index, first, dims in bricks(shape, brick):
        # Each sample once: a brick's own samples, its high side's only at the grid's end.
        own = [d - 1 if f + d < n else d for f, d, n in zip(first, dims, shape)]
        tasks.append(dask.delayed(_extremes_task, pure=True)(source, index, first, own))
    try:
        parts = dask_client.gather(dask_client.compute(tasks))
    except Exception as error:
        raise _one_line(error) from None
    return _sdfcontour.truncation_of_parts(parts)  # the single process's rule


def _gcp_thin_parts(dask_client, source, shape, brick, lo, hi, options, active):
    """"on" or "off": the single process's choice of thin parts (auto_thin_parts), from the
    subspacing gaps counted brick by brick where the grid's size leaves it open."""
    given = options["thin_parts"]
    samples = max(shape)
    if given != "auto" or options["zero_set"] == "on":
        return given
    if _sdfcontour.edge_fans_chosen(options, tuple(shape)):
        return "off"  # the fans' finer grid only when asked, as in the single process
    if not _sdfcontour.thin_parts_need_gaps(samples):
        return "on" if _sdfcontour.auto_thin_parts(samples, 0, 0) else "off"
    import dask
    tasks = []
    for index, first, dims in bricks_among(shape, brick, active):  # (no active voxel: no gap)
        own = [d - 1 if f + d < n else d for f, d, n in zip(first, dims, shape)]
        tasks.append(dask.delayed(_gaps_task, pure=True)(source, index, first, own, shape, lo, hi))
    try:
        parts = dask_client.gather(dask_client.compute(tasks))
    except Exception as error:
        raise _one_line(error) from None
    gaps, crossings = sum(p[0] for p in parts), sum(p[1] for p in parts)
    return "on" if _sdfcontour.auto_thin_parts(samples, gaps, crossings) else "off"


def _grid_tasks(reader, source, shape, lo, hi, brick, options, truncation, active):
    """The reconstruction's tasks for a grid: one per brick, reading its own block (with its
    halo for GCP); a brick without an active voxel holds no surface: not even listed."""
    import dask
    tasks = []
    for index, first, dims in bricks_among(shape, brick, active):
        if options is not None:
            task = dask.delayed(_gcp_task, pure=True)(source, index, first, dims, shape, lo,
                                                      hi, options, truncation)
        elif isinstance(reader, np.ndarray) or type(reader).__module__.startswith("dask"):
            sl = tuple(slice(f, f + d) for f, d in zip(first, dims))
            block = reader[sl]
            task = dask.delayed(brick_piece, pure=True)(block, index, first, shape, lo, hi)
        else:
            task = dask.delayed(_read_and_contour, pure=True)(reader, index, first, dims,
                                                              shape, lo, hi)
        tasks.append(task)
    return tasks


def _contour_on(reader, shape, lo, hi, brick, client, out, progress, return_stats, options):
    started = time.perf_counter()
    dask_client, owned = _start_client(client)
    try:
        active = reader.active(brick) if isinstance(reader, _VdbReader) else None
        source = reader
        if options is not None and isinstance(reader, np.ndarray):
            # Sent to each worker once, not per task, under a key of its own: by the array's
            # hash (dask's default), a second call with the same array could take the first's
            # key while the first's release was still on its way, and lose the data
            # (CancelledError in test_dask on a busy machine).
            source = dask_client.scatter(reader, hash=False)
        truncation = None
        if options is not None:
            truncation = _gcp_truncation(dask_client, reader, source, shape, brick, options)
            options = dict(options, thin_parts=_gcp_thin_parts(dask_client, source, shape, brick,
                                                               lo, hi, options, active))
        if isinstance(reader, _CallableReader):
            tasks = _callable_tasks(dask_client, reader, shape, lo, hi, brick, options,
                                    truncation)
        else:
            tasks = _grid_tasks(reader, source, shape, lo, hi, brick, options, truncation, active)
        if not tasks:
            raise ValueError("the level set has no active voxels: no surface to contour")
        futures = dask_client.compute(tasks)
        order = {f.key: b for b, f in enumerate(futures)}
        done = _Progress(len(futures), progress)
        results = _arrivals(futures, order, done)
        if isinstance(reader, _VdbReader) and reader.placement is not None:
            results = reader.place(results)
        if out is None:
            V, F, stats = join_pieces(results, len(futures))
        else:
            stats = write_pieces_as_ply(results, len(futures), out)
    finally:
        if owned:
            _stop_client(dask_client)
    stats["bricks"] = len(futures)
    stats["seconds"] = time.perf_counter() - started
    if stats["triangles"] == 0:  # nothing was written
        raise ValueError("the grid has no sign change: no surface to contour")
    if out is not None:
        return stats
    return (V, F, stats) if return_stats else (V, F)


class _Progress:
    def __init__(self, total, enabled):
        self.total, self.enabled, self.done = total, enabled, 0

    def tick(self):
        self.done += 1
        if self.enabled:
            print(f"[sdfcontour] bricks {self.done}/{self.total}", file=sys.stderr,
                  end="\n" if self.done == self.total else "\r", flush=True)


def _arrivals(futures, order, done):
    """Yields (brick number, piece) as the bricks finish; a failed brick cancels the rest and
    raises its own one-line error."""
    import distributed
    try:
        for future, piece in distributed.as_completed(futures, with_results=True,
                                                      raise_errors=True):
            done.tick()
            yield order[future.key], piece
    except Exception as error:  # a brick failed: say which and why, in one line
        for f in futures:
            f.cancel()
        raise _one_line(error) from None

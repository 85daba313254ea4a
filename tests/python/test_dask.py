"""sdfcontour.dask (issue 38): a grid contoured brick by brick on a local cluster of 2 worker
processes is the single-process mesh exactly, from every kind of source, across seams through
thin parts and sharp edges, and after a worker is killed mid-run."""
import os
import sys

import numpy as np
import pytest
from conftest import shared_mesh

import sdfcontour

distributed = pytest.importorskip("distributed")
zarr = pytest.importorskip("zarr")
h5py = pytest.importorskip("h5py")
import cloudpickle  # noqa: E402  (Dask's own dependency)

import sdfcontour.dask  # noqa: E402

# The workers cannot import this test file: send its functions by value.
cloudpickle.register_pickle_by_value(sys.modules[__name__])

N = 129  # 128 cells a side: 8 bricks of 64
LO, HI = np.array([-1.0, -1.0, -1.0]), np.array([1.0, 1.0, 1.0])
H = (HI - LO) / (N - 1)


def shape_sdf(p):
    """A torus, a box whose edges and corners cross the seams at x = 0 and y = 0 (cell boundaries
    of the 64-cell bricks), and a plate 0.3 spacings thick whose faces straddle the seam z = 0;
    as a union (min), so that the signs are right and the values near each part are distances."""
    x, y, z = p[:, 0], p[:, 1], p[:, 2]
    torus = np.sqrt((np.sqrt(x ** 2 + z ** 2) - 0.55) ** 2 + (y - 0.5) ** 2) - 0.15
    q = np.abs(p - np.array([0.0, -0.1, -0.45])) - np.array([0.3001, 0.2501, 0.2])
    box = np.linalg.norm(np.maximum(q, 0), axis=1) + np.minimum(q.max(axis=1), 0)
    plate_q = np.abs(p - np.array([0.4, -0.5, 0.0])) - np.array([0.3, 0.3, 0.15 * H[2]])
    plate = np.linalg.norm(np.maximum(plate_q, 0), axis=1) + np.minimum(plate_q.max(axis=1), 0)
    return np.minimum(np.minimum(torus, box), plate)


def positions(n=N):
    """The grid's sample positions, by the formula that the library and the callable sampler use
    (lo + index * h), so that a callable and a stored grid see the same points."""
    i = np.arange(n)
    h = (HI - LO) / (n - 1)
    X, Y, Z = np.meshgrid(LO[0] + i * h[0], LO[1] + i * h[1], LO[2] + i * h[2], indexing="ij")
    return np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])


@pytest.fixture(scope="module")
def grid():
    return shape_sdf(positions()).reshape(N, N, N).astype(np.float32)


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=None, silence_logs=40)
    with distributed.Client(cluster) as c:
        yield c
    cluster.close()


@pytest.fixture(scope="module")
def single(grid):
    return sdfcontour.contour(grid, method="mc")


def assert_same_mesh(a, b):
    ca, cb = sdfcontour.dask.canonical_mesh(*a), sdfcontour.dask.canonical_mesh(*b)
    assert np.array_equal(ca[0], cb[0])
    assert np.array_equal(ca[1], cb[1])


def assert_identical(a, b):
    """The same arrays, in the same order (GCP's pieces join as the core's bricks do)."""
    assert np.array_equal(np.asarray(a[0]), np.asarray(b[0]))
    assert np.array_equal(np.asarray(a[1]), np.asarray(b[1]))


def assert_closed_manifold(F):
    """Every directed edge once, and its reverse once: closed, 2-manifold, oriented."""
    directed = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]).astype(np.int64)
    code = directed[:, 0] * (F.max() + 1) + directed[:, 1]
    reverse = directed[:, 1] * (F.max() + 1) + directed[:, 0]
    assert len(np.unique(code)) == len(code), "an edge is used twice in one direction"
    assert np.array_equal(np.sort(code), np.sort(reverse)), "an edge has one triangle"


def test_eight_bricks_on_two_workers_are_the_single_process_mesh(grid, client, single):
    V, F, stats = sdfcontour.dask.contour(grid, method="mc", brick=64, client=client,
                                          return_stats=True)
    assert stats["bricks"] == 8
    assert_same_mesh((V, F), single)
    assert_closed_manifold(F)
    # The seams run through the thin plate and the box's edges: there are vertices on them.
    for axis, value in ((0, 0.0), (1, 0.0), (2, 0.0)):
        assert np.sum(np.abs(V[:, axis] - value) < 1e-12) > 10


def test_marching_cubes_pieces_join_in_the_core(grid, single):
    # The pieces of bricks of 40 (seams through every part) join through the core's
    # join_mesh_pieces, in whatever order they arrive: the single process's mesh, vertices in key
    # order; a piece that puts a shared vertex elsewhere is refused.
    from sdfcontour._io_join import join_pieces
    shape, todo = grid.shape, sdfcontour.dask.bricks(grid.shape, 40)
    pieces = [sdfcontour.dask.brick_piece(grid[tuple(slice(f, f + d) for f, d in zip(first, dims))],
                                          index, first, shape, LO, HI)
              for index, first, dims in todo]
    arrivals = list(enumerate(pieces))[::-1]
    V, F, stats = join_pieces(arrivals, len(pieces))
    assert stats["vertices"] == len(V) and stats["triangles"] == len(F)
    assert_same_mesh((V, F), single)
    assert_closed_manifold(F)
    keys = np.unique(np.concatenate([p[0] for p in pieces]))
    assert len(keys) == len(V)
    shared = [b for b, p in enumerate(pieces) if len(p[0]) and np.isin(p[0], np.concatenate(
        [q[0] for c, q in enumerate(pieces) if c != b])).any()]
    b = shared[0]
    keys_b, V_b, F_b = pieces[b]
    moved = np.array(V_b, copy=True)
    moved[np.isin(keys_b, np.concatenate([q[0] for c, q in enumerate(pieces) if c != b]))] += 1e-9
    bad = pieces[:b] + [(keys_b, moved, F_b)] + pieces[b + 1:]
    with pytest.raises(RuntimeError, match="differently"):
        join_pieces(list(enumerate(bad)), len(bad))


def test_sources_agree_zarr_hdf5_npy_dask_callable(grid, client, single, tmp_path):
    import dask.array as da
    z = zarr.open(str(tmp_path / "g.zarr"), mode="w", shape=grid.shape, chunks=(32, 32, 32),
                  dtype="f4", fill_value=1.0, write_empty_chunks=False)
    z[...] = np.minimum(grid, 1.0)  # truncated at 1: chunks far from the surface are not stored
    assert z.nchunks_initialized < z.nchunks
    with h5py.File(tmp_path / "g.h5", "w") as f:
        f.create_dataset("sdf/values", data=grid, chunks=(32, 32, 32))
    np.save(tmp_path / "g.npy", grid)
    meshes = {
        "zarr path": sdfcontour.dask.contour(str(tmp_path / "g.zarr"), brick=64, client=client),
        "zarr array": sdfcontour.dask.contour(z, brick=50, client=client),
        "hdf5 path": sdfcontour.dask.contour(tmp_path / "g.h5", brick=64, client=client),
        "npy memory-map": sdfcontour.dask.contour(tmp_path / "g.npy", brick=40, client=client),
        "dask array": sdfcontour.dask.contour(da.from_array(grid, chunks=64), brick=64,
                                              client=client),
    }
    with h5py.File(tmp_path / "g.h5", "r") as f:
        meshes["hdf5 dataset"] = sdfcontour.dask.contour(f["sdf/values"], brick=64, client=client)
    # The callable is sampled in float64 near the surface only: compare it with the float64 grid.
    V64, F64 = sdfcontour.contour(shape_sdf(positions()).reshape(N, N, N), method="mc")
    callable_mesh = sdfcontour.dask.contour(shape_sdf, resolution=N, brick=64, client=client)
    for name, mesh in meshes.items():
        assert_same_mesh(mesh, single), name
    assert_same_mesh(callable_mesh, (V64, F64))


def test_streamed_ply_is_the_joined_mesh(grid, client, single, tmp_path):
    out = tmp_path / "mesh.ply"
    stats = sdfcontour.dask.contour(grid, brick=48, client=client, out=out)
    V, F = sdfcontour.read_mesh(str(out))
    assert (stats["vertices"], stats["triangles"]) == (len(V), len(F))
    assert_same_mesh((V, F), single)
    assert [p.name for p in tmp_path.iterdir()] == ["mesh.ply"]  # no temporary left


def test_a_killed_worker_loses_nothing(client, tmp_path):
    marker = str(tmp_path / "killed")

    def dies_once(p):
        # The first evaluation anywhere kills its worker process, as a crash or OOM kill would.
        if not os.path.exists(marker):
            open(marker, "w").close()
            os._exit(1)
        return shape_sdf(p)

    n = 65
    V, F = sdfcontour.dask.contour(dies_once, resolution=n, brick=32, client=client)
    assert os.path.exists(marker)
    expected = sdfcontour.dask.contour(shape_sdf, resolution=n, brick=64, client=client)
    assert_same_mesh((V, F), expected)


def test_a_bad_brick_stops_the_run_with_its_index(grid, client, tmp_path):
    bad = grid.copy()
    bad[70, 3, 100] = np.nan
    out = tmp_path / "never.ply"
    with pytest.raises(ValueError) as error:
        sdfcontour.dask.contour(bad, brick=64, client=client, out=out)
    message = str(error.value)
    assert message == ("brick (1, 0, 1) (samples [64:129, 0:65, 64:129]): the grid has a "
                       "non-finite value at [70, 3, 100]")
    assert error.value.__cause__ is None and error.value.__suppress_context__
    assert list(tmp_path.iterdir()) == []  # no output, no temporary


@pytest.mark.slow
def test_gcp_in_eight_bricks_is_the_single_process_local_mesh(client, grid, tmp_path):
    # GCP's local reconstruction, brick-local from end to end: each brick reads a halo for its
    # contact points' stars, and the joined pieces are the single process's mesh bit for bit,
    # across seams through the plate, the box's edges and corners (zarr source, truncation found
    # per brick as the single process finds it on the whole grid).
    single = sdfcontour.contour(grid, reconstruction="local")
    store = str(tmp_path / "g.zarr")
    z = zarr.open(store, mode="w", shape=grid.shape, chunks=(32, 32, 32), dtype=grid.dtype)
    z[:] = grid
    V, F, stats = sdfcontour.dask.contour(store, method="gcp", brick=64, client=client,
                                          return_stats=True)
    assert stats["bricks"] == 8
    assert_identical((V, F), single)
    assert_closed_manifold(F)
    # Closer to the surface than marching cubes: mean |sdf| at the triangles' centroids.
    def error(V, F):
        return np.abs(shape_sdf(V[F].mean(axis=1))).mean()
    assert error(V, F) < 0.6 * error(*sdfcontour.contour(grid, method="mc"))
    # A bad sample: one line naming the brick (the first whose halo meets it) and the sample.
    bad = grid.copy()
    bad[70, 3, 100] = np.nan
    words = r"^brick \(\d, \d, \d\) \(samples .*\]\): the grid has a non-finite value at \[70, 3, 100\]$"
    with pytest.raises(ValueError, match=words):
        sdfcontour.dask.contour(bad, method="gcp", brick=64, client=client, truncation="none")


def test_gcp_with_edge_fans_in_bricks_is_the_single_process_mesh(client, grid, tmp_path):
    # Edge fans read one ring of cells beyond a brick's own (no repair stages): bricks of 32 give
    # the single process's arrays bit for bit (joined in memory, or streamed into a PLY), closed,
    # on the grid and on its finer grid.
    single = sdfcontour.contour(grid, edge_fans=True, band=3)
    V, F = sdfcontour.dask.contour(grid, method="gcp", brick=32, client=client, edge_fans=True,
                                   band=3)
    assert_identical((V, F), single)
    out = str(tmp_path / "fans.ply")
    sdfcontour.dask.contour(grid, method="gcp", brick=32, client=client, edge_fans=True, band=3,
                            out=out)
    assert_identical(sdfcontour.read_mesh(out), single)
    assert_closed_manifold(F)
    # The finer grid only when asked, there too.
    finer = sdfcontour.contour(grid, edge_fans=True, band=3, thin_parts=True)
    assert len(finer[1]) > 2 * len(F)
    assert_identical(sdfcontour.dask.contour(grid, method="gcp", brick=32, client=client,
                                             edge_fans=True, band=3, thin_parts=True), finer)
    with pytest.raises(ValueError, match="edge_fans"):
        sdfcontour.dask.contour(grid, method="gcp", client=client, edge_fans="yes")


def test_gcp_edge_fans_auto_is_the_single_process_choice(client):
    # Edge fans by default from 384 samples along the longest axis, in bricks as in one process: a
    # sphere in a long, thin grid (384 and 383 by 16 by 16) gives the single process's arrays,
    # fanned at 384 (those of edge_fans=True) and repaired at 383.
    for n in (383, 384):
        x = (np.arange(n) - (n - 1) / 2) * 0.05
        y = (np.arange(16) - 7.5) * 0.05
        X, Y, Z = np.meshgrid(x, y, y, indexing="ij")
        grid = np.sqrt(X**2 + Y**2 + Z**2) - 0.27
        bounds = ((x[0], y[0], y[0]), (x[-1], y[-1], y[-1]))
        V, F, stats = sdfcontour.contour(grid, bounds, return_stats=True)
        assert stats["local_edge_fans"] == (n >= 384)
        assert_identical((V, F), sdfcontour.contour(grid, bounds, edge_fans=n >= 384))
        assert_identical(sdfcontour.dask.contour(grid, bounds, method="gcp", brick=32,
                                                 client=client), (V, F))
        assert_closed_manifold(F)


@pytest.mark.slow
def test_gcp_of_a_callable_in_bricks_is_the_single_process_mesh(client):
    # Each brick samples the callable near the surface, exactly wherever the local
    # reconstruction reads a value (not only at the crossings, as marching cubes needs).
    def torus(p):
        q = np.sqrt(p[:, 0] ** 2 + p[:, 1] ** 2) - 0.5
        return np.sqrt(q ** 2 + p[:, 2] ** 2) - 0.2
    single = sdfcontour.contour(torus, resolution=48, refine=False)
    V, F, stats = sdfcontour.dask.contour(torus, method="gcp", resolution=48, brick=24,
                                          client=client, return_stats=True)
    assert stats["bricks"] == 8
    assert_identical((V, F), single)


class _Jittery:
    """The torus's distance with a new +-1e-9 on every call, as a network on a GPU answers: a
    point evaluated twice may differ."""

    def __call__(self, p):
        q = np.sqrt(p[:, 0] ** 2 + p[:, 1] ** 2) - 0.5
        return np.sqrt(q ** 2 + p[:, 2] ** 2) - 0.2 + np.random.uniform(-1e-9, 1e-9, len(p))


@pytest.mark.parametrize("method", ["mc", "gcp"])
def test_a_callable_that_does_not_repeat_itself_gives_one_closed_mesh(client, method):
    # Each sample is evaluated once, by one task: bricks that share it read the same value
    # (sampled twice, two bricks placed one vertex differently: an internal error).
    V, F = sdfcontour.dask.contour(_Jittery(), method=method, resolution=40, brick=16,
                                   client=client)
    assert_closed_manifold(F)
    d = np.abs(np.sqrt((np.sqrt(V[:, 0] ** 2 + V[:, 1] ** 2) - 0.5) ** 2 + V[:, 2] ** 2) - 0.2)
    assert d.max() < 0.5 * 2 / 39


@pytest.mark.slow
def test_gcp_onto_the_zero_set_in_bricks_is_the_single_process_mesh(client):
    # zero_set=True (for values that are no exact distances, which no pass measures on Dask):
    # the bricks' vertices go onto their blocks' tricubic zero set, as in one process.
    x = np.linspace(-1, 1, 48)
    X, Y, Z = np.meshgrid(x, x, x, indexing="ij")
    torus = np.sqrt((np.sqrt(X ** 2 + Y ** 2) - 0.5) ** 2 + Z ** 2) - 0.2
    single = sdfcontour.contour(torus, reconstruction="local", zero_set=True)
    V, F = sdfcontour.dask.contour(torus, method="gcp", brick=24, client=client, zero_set=True)
    assert_identical((V, F), single)
    # A distance times a factor in [0.8, 1.2]: closer to the torus than marching cubes.
    values = torus * (1 + 0.2 * np.sin(2 * X + 1) * np.cos(3 * Y))
    V, F = sdfcontour.dask.contour(values, method="gcp", brick=24, client=client, zero_set=True)
    assert_closed_manifold(F)
    def error(V):
        return np.abs(np.sqrt((np.sqrt(V[:, 0] ** 2 + V[:, 1] ** 2) - 0.5) ** 2 + V[:, 2] ** 2)
                      - 0.2).mean()
    assert 4 * error(V) < error(sdfcontour.contour(values, method="mc")[0])


def test_a_gcp_brick_whose_reader_misbehaves_is_one_clear_error(grid):
    # The core's brick driver reads through the given reader: a block of the wrong shape, of no
    # numbers, or the reader's own exception, each one line (or the reader's error) naming the
    # brick, never a piece of the wrong block.
    first, dims = (32, 32, 32), (33, 33, 33)
    def good(f, d):
        return grid[f[0]:f[0] + d[0], f[1]:f[1] + d[1], f[2]:f[2] + d[2]]
    keys, V, F, names = sdfcontour.dask.gcp_brick_piece(
        good, (0, 0, 0), first, dims, grid.shape, LO, HI, {"edge_fans": True}, (np.inf, np.inf))
    assert len(F) > 0 and len(names) == len(F)
    for read, kind, words in [
            (lambda f, d: good(f, d)[:-1], ValueError,
             r"^brick \(0, 0, 0\) \(samples \[\d+:\d+, .*\]\): the grid's reader returned an array "
             r"of shape \(\d+, \d+, \d+\) for a block of \(\d+, \d+, \d+\)$"),
            (lambda f, d: good(f, d).ravel(), ValueError, "reader returned an array of shape"),
            (lambda f, d: np.full(tuple(d), "x"), ValueError, "real numbers"),
            (lambda f, d: 1 / 0, ZeroDivisionError, "division by zero")]:
        with pytest.raises(kind, match=words):
            sdfcontour.dask.gcp_brick_piece(read, (0, 0, 0), first, dims, grid.shape, LO, HI,
                                            {"edge_fans": True}, (np.inf, np.inf))


@pytest.mark.parametrize("call, kind, words", [
    (lambda c: sdfcontour.dask.contour(np.zeros((8, 8, 8)) + 1j, client=c), TypeError,
     "real numbers"),
    (lambda c: sdfcontour.dask.contour(np.ones((9, 9, 9)), client=c), ValueError, "no sign change"),
    (lambda c: sdfcontour.dask.contour(np.ones((9, 9)), client=c), ValueError, "3 axes"),
    (lambda c: sdfcontour.dask.contour(np.ones((9, 9, 9)), method="gcp", client=c), ValueError,
     "no sign change"),
    (lambda c: sdfcontour.dask.contour(np.ones((9, 9, 9)), method="mt-rt", client=c), ValueError,
     "triangulation of all samples"),
    (lambda c: sdfcontour.dask.contour("/nonexistent/g.zarr", client=c), OSError, "no such"),
    (lambda c: sdfcontour.dask.contour(np.ones((9, 9, 9)), brick=0, client=c), ValueError,
     "brick must be from 8"),
    (lambda c: sdfcontour.dask.contour(np.ones((11, 11, 11)), brick=1, method="gcp", client=c),
     ValueError, "brick must be from 8"),
    (lambda c: sdfcontour.dask.contour(shape_sdf, resolution=10**7, client=c), ValueError,
     "bricks.*give a larger brick"),
    (lambda c: sdfcontour.dask.contour(shape_sdf, client=c), ValueError, "needs a resolution"),
    (lambda c: sdfcontour.dask.contour(np.ones((9, 9, 9)), client=5), TypeError, "client must"),
])
def test_bad_input_is_one_clear_error(client, call, kind, words):
    with pytest.raises(kind, match=words):
        call(client)


def _failing_sdf(p):
    # (A built-in type: a class of this module is sent to the workers by value, as a copy.)
    raise ZeroDivisionError("the network is not loaded")


def test_errors_are_the_modules_or_the_callables_own(client, tmp_path):
    # A missing zarr array is the module's ValueError, not zarr's KeyError.
    z = zarr.open(str(tmp_path / "g.zarr"), mode="w")
    z.create_dataset("a", data=np.ones((9, 9, 9)))
    with pytest.raises(ValueError, match="no array 'b'"):
        sdfcontour.dask.contour(str(tmp_path / "g.zarr"), dataset="b", client=client)
    # A callable's own exception reaches the caller with its type and words, on Dask as in one
    # process.
    for run in (lambda: sdfcontour.contour(_failing_sdf, resolution=16),
                lambda: sdfcontour.dask.contour(_failing_sdf, resolution=16, brick=8,
                                                client=client)):
        with pytest.raises(ZeroDivisionError, match="not loaded"):
            run()


@pytest.mark.slow
def test_openvdb_level_set_read_box_by_box(client, tmp_path):
    # Split by its active leaves, never densified whole: the same mesh as marching cubes on the
    # level set's box read in one piece, and next to GCP's mesh of the same file, which is the
    # single process's.
    import subprocess
    root = os.path.join(os.path.dirname(__file__), "..", "..")
    cli = os.environ.get("SDFCONTOUR_CLI", os.path.join(root, "build", "sdfcontour"))
    vdb = str(tmp_path / "spot.vdb")
    subprocess.run([cli, "sample", shared_mesh("spot.obj"),
                    "--res", "64", "-o", vdb, "--quiet"], check=True, capture_output=True)
    V, F, stats = sdfcontour.dask.contour(vdb, brick=16, client=client, return_stats=True)
    reader = sdfcontour.dask._VdbReader(vdb, None)
    whole = sdfcontour._sdfcontour.read_vdb_box(vdb, "", tuple(int(x) for x in reader.first),
                                                reader.shape)
    assert_same_mesh((V, F), sdfcontour.contour(whole, bounds=reader.bounds, method="mc"))
    assert_same_mesh((V, F), sdfcontour.contour(vdb, method="mc"))  # box by box in one process
    assert stats["bricks"] < len(sdfcontour.dask.bricks(reader.shape, 16))  # empty ones unread
    assert_closed_manifold(F)
    V_gcp, F_gcp = sdfcontour.contour(vdb)
    assert sdfcontour.distances(V, F, V_gcp, F_gcp, samples=20000)["L1"] < 0.5 * (2 / 63)
    # GCP's local reconstruction of the file, read box by box in one process (the default for a
    # .vdb) and on Dask in bricks of 32: the same mesh.
    assert_identical(sdfcontour.dask.contour(vdb, method="gcp", brick=32, client=client),
                     (V_gcp, F_gcp))
    with pytest.raises(ValueError, match="places itself"):
        sdfcontour.dask.contour(vdb, bounds=(-1, 1), client=client)
    with pytest.raises(ValueError, match="no float grid named"):
        sdfcontour.dask.contour(vdb, dataset="density", client=client)


def rotated_box_distance(V):
    """The exact distance to the box in tests/data/rotated_box.vdb (make_rotated_box.cpp)."""
    q = np.abs(V - np.array([0.15, 0.05, 0.25])) - np.array([0.3, 0.2, 0.12])
    return np.linalg.norm(np.maximum(q, 0), axis=1) + np.minimum(q.max(axis=1), 0)


def test_a_rotated_level_set_is_placed_by_its_transform_on_every_path(client):
    # Its transform rotates and moves it: read box by box (the default, marching cubes, Dask) or
    # sparse (Poisson), the surface lies where the transform puts it, not at the voxels' indices.
    vdb = os.path.join(os.path.dirname(__file__), "..", "data", "rotated_box.vdb")
    voxel = 0.05
    meshes = {
        "gcp": sdfcontour.contour(vdb),
        "mc": sdfcontour.contour(vdb, method="mc"),
        "poisson": sdfcontour.contour(vdb, reconstruction="poisson"),
        "dask mc": sdfcontour.dask.contour(vdb, brick=8, client=client),
        "dask gcp": sdfcontour.dask.contour(vdb, method="gcp", brick=16, client=client),
    }
    for name, (V, F) in meshes.items():
        d = np.abs(rotated_box_distance(V))
        assert d.mean() < 0.05 * voxel and d.max() < 0.5 * voxel, (name, d.mean(), d.max())
        assert_closed_manifold(F)
    assert_identical(meshes["dask gcp"], meshes["gcp"])


def test_gcp_finds_thin_parts_on_a_fine_grid_as_the_single_process_does(client):
    # 193 samples along x, where the size alone leaves thin parts off: a fin 0.4 spacings thick
    # between the samples 127 and 128, on the seam of the 64-cell bricks. The bricks' gap counts
    # (one sample read before and two after their own) turn thin parts on as the single process
    # does, and the fin is in both meshes, alike; without thin parts it is not.
    n = (193, 24, 24)
    hi = np.array(n, float) - 1
    p = np.stack(np.meshgrid(*[np.arange(k, dtype=float) for k in n], indexing="ij"),
                 axis=-1).reshape(-1, 3)

    def box(points, center, half):
        q = np.abs(points - np.array(center)) - np.array(half)
        return np.linalg.norm(np.maximum(q, 0), axis=1) + np.minimum(q.max(axis=1), 0)

    def on_fin(V):
        return np.sum(np.abs(box(V, (127.5, 11.5, 11.5), (0.2, 6, 6))) < 0.05)
    grid = np.minimum(box(p, (50, 11.5, 11.5), (25.3, 6.2, 6.3)),
                      box(p, (127.5, 11.5, 11.5), (0.2, 6, 6))).reshape(n)
    *single, stats = sdfcontour.contour(grid, bounds=(0, hi), return_stats=True)
    assert stats["local_thin_parts"] and stats["subspacing_gaps"] == 12 * 12  # the fin's edges
    V, F = sdfcontour.dask.contour(grid, bounds=(0, hi), method="gcp", brick=64, client=client)
    assert_identical((V, F), single)
    assert_closed_manifold(F)
    assert on_fin(V) > 200
    assert on_fin(sdfcontour.contour(grid, bounds=(0, hi), thin_parts=False)[0]) == 0


FAR_SPHERES = os.path.join(os.path.dirname(__file__), "..", "data", "far_spheres.vdb")


def assert_on_far_spheres(V):
    """Vertices on both spheres of tests/data/far_spheres.vdb (radius 0.6, at the origin and at
    5000 along the diagonal), within half a voxel."""
    far = 1e5 * 0.05
    away = V[:, 0] > far / 2
    assert away.sum() > 100 and (~away).sum() > 100
    W = V - np.where(away[:, None], far, 0.0)
    assert np.abs(np.linalg.norm(W, axis=1) - 0.6).max() < 0.5 * 0.05


@pytest.mark.slow
def test_a_level_set_far_apart_costs_its_voxels_on_every_path(client, tmp_path):
    # Two spheres 1e5 voxels apart: a box of 1e15 voxels, a few hundred leaves. Read box by box
    # (GCP's default, marching cubes), sparse (Poisson) and on Dask, each costs the leaves: in a
    # child process, its peak memory under 1 GB; on Dask, the bricks that meet a leaf only.
    import subprocess
    import sys
    for call in ("sdfcontour.contour(path)", "sdfcontour.contour(path, method='mc')",
                 "sdfcontour.contour(path, reconstruction='poisson')"):
        child = (f"import resource, numpy as np, sdfcontour\npath = {FAR_SPHERES!r}\n"
                 f"V, F = {call}\nnp.save({str(tmp_path / 'V.npy')!r}, V)\n"
                 f"import sys; print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, "
                 f"file=sys.stderr)")
        run = subprocess.run([sys.executable, "-c", child], capture_output=True, timeout=600)
        assert run.returncode == 0, (call, run.stderr[-1000:])
        assert_on_far_spheres(np.load(tmp_path / "V.npy"))
        assert int(run.stderr.split()[-1]) < 1 << 20, (call, run.stderr[-200:])  # KB: < 1 GB
    for method, brick in (("mc", 16), ("gcp", 32)):
        V, F, stats = sdfcontour.dask.contour(FAR_SPHERES, method=method, brick=brick,
                                              client=client, return_stats=True)
        assert_on_far_spheres(V)
        assert_closed_manifold(F)
        assert stats["bricks"] < 2000, stats["bricks"]


"""Reliability round 3 (issue 36), through the Python module: every argument is converted and
checked once, in Python, so that no input reaches the C++ core as a string, a NaN, a wrapped index
or an option out of range (the interpreter never dies); stray scattered samples are dropped and
said; objects far apart are reconstructed each in its own octree."""
import os
import subprocess
import sys
import warnings

import numpy as np
import pytest
from conftest import shared_mesh

import sdfcontour


def tetrahedron():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float) * 0.8 - 0.2
    F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    return V, F


@pytest.mark.parametrize("call", [
    lambda: sdfcontour.poisson([[0, 0, "x"]], [[0, 0, 1]]),
    lambda: sdfcontour.poisson("abc", "abc"),
    lambda: sdfcontour.sample("abc", [[0, 1, 2]]),
    lambda: sdfcontour.sample(tetrahedron()[0], [["a", "b", "c"]]),
    lambda: sdfcontour.distances([[1j, 0, 0]], [[0, 0, 0]], *tetrahedron()),
    lambda: sdfcontour.write_mesh("never.ply", [[object(), 0, 0]], [[0, 0, 0]]),
    lambda: sdfcontour.contour(np.array([[["a"]]])),
    lambda: sdfcontour.contour(lambda p: p[:, 0] + 0j, resolution=8),
    lambda: sdfcontour.contour(np.zeros((4, 4, 4)), fn="no"),
])
def test_non_numbers_are_type_errors(call):
    with pytest.raises(TypeError):
        call()


@pytest.mark.parametrize("bad", [np.inf, 1e308, np.nan, -1e31])
def test_huge_or_non_finite_vertices_are_value_errors(bad):
    V, F = tetrahedron()
    V[3, 2] = bad
    for call in (lambda: sdfcontour.sample(V, F, 16), lambda: sdfcontour.write_mesh("never.ply", V, F),
                 lambda: sdfcontour.distances(V, F, *tetrahedron()),
                 lambda: sdfcontour.poisson(V, np.ones_like(np.nan_to_num(V)))):
        with pytest.raises(ValueError, match="NaN, infinite or too large"):
            call()


def test_indices_are_checked_before_narrowing(tmp_path):
    V, F = tetrahedron()
    wrapped = F.astype(np.int64)
    wrapped[0, 0] += 2**32  # would read as 0 in 32 bits
    with pytest.raises(ValueError, match="indexes a vertex"):
        sdfcontour.sample(V, wrapped, 8)
    with pytest.raises(ValueError, match="empty"):
        sdfcontour.write_mesh(tmp_path / "e.ply", np.zeros((0, 3)), np.zeros((0, 3), int))
    assert not (tmp_path / "e.ply").exists()


@pytest.mark.parametrize("keyword, value, kind", [
    ("knn", 10**9, ValueError), ("tie_tolerance", -1, ValueError), ("full_depth", 30, ValueError),
    ("alpha", 1e300, ValueError), ("scale", 1e300, ValueError), ("depth", 16, ValueError),
    ("brick_size", 1, ValueError), ("margin", np.nan, ValueError), ("gradient", 5, ValueError),
    ("weights", "heavy", ValueError), ("knn", 3.5, TypeError), ("boundary", None, ValueError),
])
def test_options_out_of_the_shared_table_are_refused_in_python_words(keyword, value, kind):
    grid = np.zeros((4, 4, 4))
    with pytest.raises(kind) as info:
        sdfcontour.contour(grid, **{keyword: value})
    assert keyword in str(info.value) and "--" not in str(info.value)


def test_poisson_options_and_bounds_are_bounded():
    P = np.random.default_rng(0).normal(size=(200, 3))
    for keyword, value in [("alpha", 1e300), ("scale", 1e300), ("full_depth", 30), ("depth", 20)]:
        with pytest.raises(ValueError, match=keyword):
            sdfcontour.poisson(P, P, **{keyword: value})
    for bounds in [(-1e308, 1e308), (-1e160, 1e160)]:
        with pytest.raises(ValueError, match="bounds"):
            sdfcontour.contour(np.zeros((4, 4, 4)), bounds=bounds, method="mc")


def test_a_stray_scattered_sample_is_dropped_and_said():
    rng = np.random.default_rng(0)
    P = rng.uniform(-1, 1, (3000, 3))
    samples = np.column_stack([P, np.linalg.norm(P, axis=1) - 0.6])
    samples[5, 1] = 1e3  # a row far from the rest
    with pytest.warns(sdfcontour.DroppedSamplesWarning, match="dropped 1 isolated"):
        V, F, stats = sdfcontour.contour(samples, return_stats=True)
    assert stats["isolated_samples"] == 1
    radius = np.linalg.norm(V, axis=1)
    assert radius.max() < 0.61 and radius.min() > 0.59  # no spike towards the stray row


def test_objects_far_apart_each_get_their_own_octree():
    h = 1 / 32
    x = np.arange(-12, 13) * h
    P = np.stack(np.meshgrid(x, x, x, indexing="ij"), -1).reshape(-1, 3)
    d = np.linalg.norm(P, axis=1) - 0.25
    near = np.abs(d) < 3 * h
    P, d = P[near], d[near]
    for gap in (1e5, 1e9):  # spacings between the two spheres
        Q = P + [gap * h, 0, 0]
        samples = np.vstack([np.column_stack([P, d]), np.column_stack([Q, d])])
        V, F, stats = sdfcontour.contour(samples, band="all", truncation="none", return_stats=True)
        left = V[:, 0] < gap * h / 2
        assert left.any() and (~left).any()
        for part, centre in ((V[left], [0, 0, 0]), (V[~left], [gap * h, 0, 0])):
            radius = np.linalg.norm(part - centre, axis=1)
            assert abs(np.median(radius) - 0.25) < 0.01 * 0.25


def test_overlapping_parts_are_sampled_as_their_union():
    def cube(lo, hi):
        V = np.array([[x, y, z] for x in (lo, hi) for y in (lo, hi) for z in (lo, hi)], float)
        F = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                      [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
        return V, F
    (V1, F1), (V2, F2) = cube(-0.6, 0.2), cube(-0.2, 0.6)
    grid = sdfcontour.sample(np.vstack([V1, V2]), np.vstack([F1, F2 + 8]), 31, bounds=(-0.6, 0.6),
                             scale=None)
    # The origin (sample 15) lies in both cubes: inside, sqrt(0.08) from the union's boundary.
    assert grid[15, 15, 15] == pytest.approx(-np.sqrt(0.08), abs=1e-9)


def random_argument(rng):
    """Something a careless caller might pass where an array belongs."""
    kind = rng.integers(12)
    shape = tuple(int(s) for s in rng.integers(0, 5, size=rng.integers(0, 4)))
    if kind == 0:
        return "abc"
    if kind == 1:
        return [[0, 0, "x"]]
    if kind == 2:
        return np.zeros(shape, dtype=object)
    if kind == 3:
        return np.ones(shape, dtype=complex)
    if kind == 4:
        return np.ones(shape, dtype=bool)
    if kind == 5:
        return np.full(shape, 2**63 - 1, dtype=np.uint64)
    if kind == 6:
        return np.full(shape, np.nan)
    if kind == 7:
        return np.full(shape, 1e308)
    if kind == 8:
        return None
    if kind == 9:
        return [[1, 2], [3]]  # ragged
    if kind == 10:
        return rng.normal(size=shape).astype(np.float16)
    return rng.integers(-3, 3, size=shape)


def test_random_arguments_raise_python_errors_only():
    """A property test of the module's conversions: random dtypes and shapes in every array
    argument end in TypeError or ValueError, never in a dead interpreter or another error."""
    rng = np.random.default_rng(36)
    V, F = tetrahedron()
    calls = [
        lambda a, b: sdfcontour.poisson(a, b, depth=4),
        lambda a, b: sdfcontour.sample(a, F, 6),
        lambda a, b: sdfcontour.sample(V, b, 6),
        lambda a, b: sdfcontour.distances(a, F, V, b, samples=100),
        lambda a, b: sdfcontour.write_mesh("/nonexistent/never.ply", a, b),
        lambda a, b: sdfcontour.contour(a, method="mc"),
        lambda a, b: sdfcontour.contour((a, b)),
        lambda a, b: sdfcontour.contour(np.zeros((4, 4, 4)), bounds=(a, b)),
        lambda a, b: sdfcontour.poisson(V, V, weights=a, depth=4),
    ]
    for trial in range(400):
        call = calls[trial % len(calls)]
        a, b = random_argument(rng), random_argument(rng)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                call(a, b)
            except (TypeError, ValueError, OSError):
                pass


def test_an_axis_beyond_32_bits_is_refused_not_wrapped():
    # 2**32 + 4 samples along x without the memory (a zero stride), as a memory-map would be.
    huge = np.lib.stride_tricks.as_strided(np.zeros(1), shape=(2**32 + 4, 2, 2), strides=(0, 0, 0))
    with pytest.raises(ValueError, match="2147483647"):
        sdfcontour.contour(huge, method="mc")


def test_fallbacks_and_rescalings_are_warned_and_strict_refuses():
    x = np.linspace(-1, 1, 48)
    X, Y, Z = np.meshgrid(x, x, x, indexing="ij")
    # A smooth implicit, no distance: (x^2+y^2+z^2+R^2-r^2)^2 - 4R^2(x^2+y^2).
    implicit = (X**2 + Y**2 + Z**2 + 0.55**2 - 0.25**2) ** 2 - 4 * 0.55**2 * (X**2 + Y**2)
    # Found no exact distance, its mesh lies on the grid's zero set: no fallback.
    V, F, stats = sdfcontour.contour(implicit, return_stats=True)
    assert stats["approximate_distances"] and "fallback" not in stats and stats["closed"]
    # Poisson's mesh of its contact points lies off the zero set: marching cubes' instead.
    with pytest.warns(sdfcontour.FallbackWarning, match="marching cubes"):
        V, F, stats = sdfcontour.contour(implicit, reconstruction="poisson", return_stats=True)
    assert stats["fallback"]
    # The discarded GCP run's time is accounted for, beside marching cubes'.
    assert stats["seconds"]["gcp (discarded)"] > 0 and "marching" in stats["seconds"]
    with pytest.raises(ValueError, match="distances"):
        sdfcontour.contour(implicit, reconstruction="poisson", strict=True)
    # A distance scaled by 3: rescaled, and said.
    sphere = np.sqrt(X**2 + Y**2 + Z**2) - 0.6
    with pytest.warns(sdfcontour.RescaleWarning, match="rescaled"):
        V, F, stats = sdfcontour.contour(3 * sphere, return_stats=True)
    assert stats["value_scale"] == pytest.approx(1 / 3, rel=0.05)
    # A NaN is named by its (i, j, k).
    sphere[3, 4, 5] = np.nan
    with pytest.raises(ValueError, match=r"\[3, 4, 5\]"):
        sdfcontour.contour(sphere)
    assert "np" not in dir(sdfcontour)


def test_an_exact_distance_with_thin_parts_keeps_its_values():
    # An exact distance whose thin parts make its gradient norm over all points 0.77 (the plane
    # at 16^3) is no scaled field: its values are taken as given, once, without a warning.
    plane = sdfcontour.sample(*sdfcontour.read_mesh(shared_mesh("plane.obj")), resolution=16)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        V, F, stats = sdfcontour.contour(plane, return_stats=True)
        assert stats["value_scale"] == 1 and "fallback" not in stats and stats["closed"]
        sdfcontour.contour(plane, strict=True)
    # The same field as a callable (its grid's nearest sample), through the sparse grid's
    # Poisson path: the same decision, the same mesh.
    from scipy.interpolate import RegularGridInterpolator
    axis = np.linspace(-1, 1, 16)
    nearest = RegularGridInterpolator((axis, axis, axis), plane, method="nearest")
    Vc, Fc, cstats = sdfcontour.contour(nearest, resolution=16, reconstruction="poisson",
                                        refine=False, return_stats=True)
    # (The grid through the same Poisson path; its default is the local reconstruction, above.)
    V, F, stats = sdfcontour.contour(plane, reconstruction="poisson", return_stats=True)
    assert cstats["value_scale"] == stats["value_scale"] == 1
    from sdfcontour.dask import canonical_mesh
    (A, B), (C, D) = canonical_mesh(V, F), canonical_mesh(Vc, Fc)
    assert np.array_equal(A, C) and np.array_equal(B, D)


@pytest.mark.parametrize("text", ["0_1", " 0.1", "0.1 ", "nan", "inf", "0x"])
def test_a_truncation_is_read_as_the_cli_reads_it(text):
    # Python's float() reads "0_1" as 1.0 and strips blanks; the core's one parser refuses both.
    grid = np.linspace(-1, 1, 8)[:, None, None] + np.zeros((8, 8, 8))
    with pytest.raises(ValueError, match="truncation"):
        sdfcontour.contour(grid, truncation=text)


def test_a_truncation_given_as_a_number_is_the_same_as_its_text():
    # A TSDF clamped at 3 spacings: truncation=0.3 (a float), 0.3 as text and numpy's float
    # give one mesh; a non-positive, non-finite or boolean one is refused.
    x = np.linspace(-1, 1, 21)
    X, Y, Z = np.meshgrid(x, x, x, indexing="ij")
    grid = np.clip(np.sqrt(X**2 + Y**2 + Z**2) - 0.5, -0.3, 0.3)
    V, F = sdfcontour.contour(grid, truncation="0.3")
    for given in (0.3, np.float64(0.3)):
        Vn, Fn = sdfcontour.contour(grid, truncation=given)
        assert np.array_equal(V, Vn) and np.array_equal(F, Fn)
    for bad in (0, -0.3, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="truncation"):
            sdfcontour.contour(grid, truncation=bad)
    with pytest.raises(TypeError, match="truncation"):
        sdfcontour.contour(grid, truncation=True)


def test_lattice_gradients_run_the_local_reconstruction_and_are_refused_elsewhere():
    x = np.linspace(-1, 1, 24)
    X, Y, Z = np.meshgrid(x, x, x, indexing="ij")
    sphere = np.sqrt(X**2 + Y**2 + Z**2) - 0.6
    V, F, stats = sdfcontour.contour(sphere, gradient="lattice", return_stats=True)
    assert stats["closed"] and stats["reconstruction"] == "local"
    assert np.abs(np.linalg.norm(V, axis=1) - 0.6).max() < 0.05 * (x[1] - x[0])
    with pytest.raises(ValueError, match="lattice"):
        sdfcontour.contour(sphere, gradient="lattice", reconstruction="poisson")


def test_poisson_from_too_few_or_coincident_points_is_a_value_error():
    n = np.tile([[1.0, 0, 0]], (6, 1))
    for P in (np.zeros((1, 3)) + 0.5, np.zeros((6, 3)) + 0.5):
        with pytest.raises(ValueError, match="no surface|one place"):
            sdfcontour.poisson(P, n[:len(P)])


def test_a_npy_path_truncated_after_it_was_opened_does_not_kill_python(tmp_path):
    # Another process truncates the file while it is contoured: a memory-mapped grid would die of
    # SIGBUS on its next read; the path's grid is read into memory (maps only above 2 GiB). In a
    # child process, so that a signal fails the test instead of pytest.
    x = np.linspace(-1, 1, 24)
    X, Y, Z = np.meshgrid(x, x, x, indexing="ij")
    path = tmp_path / "sphere.npy"
    np.save(path, np.sqrt(X**2 + Y**2 + Z**2) - 0.5)
    child = f"""
import os, numpy as np, sdfcontour
from sdfcontour._running import _from_path
grid, _, _ = _from_path({str(path)!r}, None)
os.truncate({str(path)!r}, 128)
V, F = sdfcontour.contour(grid, method="mc")
assert len(F) > 0 and np.isfinite(V).all()
"""
    run = subprocess.run([sys.executable, "-c", child], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, (run.returncode, run.stderr[-1000:])

"""The Python module against the command-line tool, analytic surfaces and bad input.

Run with the module installed (pip install --no-build-isolation .) and the CLI built:
    SDFCONTOUR_CLI=build/sdfcontour python -m pytest tests/python
"""
import json
import os
import signal
import subprocess
import threading
import time
import warnings

import numpy as np
import pytest
from conftest import shared_mesh

import sdfcontour

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CLI = os.environ.get("SDFCONTOUR_CLI", os.path.join(ROOT, "build", "sdfcontour"))
POISSON_CLI = [CLI, "contour", "--reconstruction", "poisson"]  # GCP, the paper's Poisson path
MESHES = os.path.join(ROOT, "..", "shared", "data", "meshes")


def sphere(p):
    return np.linalg.norm(p, axis=1) - 0.6


def torus(p):
    q = np.sqrt(p[:, 0] ** 2 + p[:, 1] ** 2) - 0.55
    return np.sqrt(q ** 2 + p[:, 2] ** 2) - 0.25


def full_grid(f, n, lo=-1.0, hi=1.0):
    x = np.linspace(lo, hi, n)
    return f(np.stack(np.meshgrid(x, x, x, indexing="ij"), -1).reshape(-1, 3)).reshape(n, n, n)


def mean_abs(f, V):
    return float(np.mean(np.abs(f(V))))


@pytest.mark.parametrize("method", ["gcp", "mc"])
def test_same_mesh_as_the_cli_on_a_grid_file(tmp_path, method):
    grid = full_grid(torus, 32)
    np.save(tmp_path / "torus.npy", grid)
    subprocess.run([CLI, "contour", str(tmp_path / "torus.npy"), "-o", str(tmp_path / "cli.ply"),
                    "--method", method, "-q"], check=True, stdout=subprocess.DEVNULL)
    V_cli, F_cli = sdfcontour.read_mesh(tmp_path / "cli.ply")
    V, F = sdfcontour.contour(grid, method=method)
    assert V.dtype == np.float64 and V.shape[1] == 3 and F.shape[1] == 3
    np.testing.assert_array_equal(V, V_cli)
    np.testing.assert_array_equal(F, F_cli)


@pytest.mark.slow
def test_same_mesh_as_the_cli_on_a_shared_mesh(tmp_path):
    mesh = os.path.join(MESHES, "bunny.obj")
    if not os.path.exists(mesh):
        pytest.skip("../shared/data/meshes is missing")
    subprocess.run([CLI, "sample", mesh, "--res", "32", "-o", str(tmp_path / "b"), "-q"], check=True,
                   stdout=subprocess.DEVNULL)
    subprocess.run([*POISSON_CLI, str(tmp_path / "b.npy"), "-o", str(tmp_path / "cli.ply"), "-q",
                    "--stats", str(tmp_path / "cli.json")], check=True, stdout=subprocess.DEVNULL)
    V_cli, F_cli = sdfcontour.read_mesh(tmp_path / "cli.ply")
    grid = np.load(tmp_path / "b.npy")
    # The default on grids, the local reconstruction: the CLI's default mesh.
    subprocess.run([CLI, "contour", str(tmp_path / "b.npy"), "-o", str(tmp_path / "local.ply"), "-q"],
                   check=True, stdout=subprocess.DEVNULL)
    V_local, F_local, local_stats = sdfcontour.contour(grid, return_stats=True)
    np.testing.assert_array_equal(V_local, sdfcontour.read_mesh(tmp_path / "local.ply")[0])
    np.testing.assert_array_equal(F_local, sdfcontour.read_mesh(tmp_path / "local.ply")[1])
    assert local_stats["reconstruction"] == "local"
    # The paper's Poisson path, asked for, from here on.
    def poisson(*args, **kwargs):
        return sdfcontour.contour(*args, reconstruction="poisson", **kwargs)
    start = time.perf_counter()
    V, F, stats = poisson(grid, return_stats=True)
    elapsed = time.perf_counter() - start
    np.testing.assert_array_equal(V, V_cli)
    np.testing.assert_array_equal(F, F_cli)
    # The seconds per stage: the CLI's stages but reading and writing files, and together no
    # longer than the call.
    with open(tmp_path / "cli.json") as f:
        cli_stages = set(json.load(f)["seconds"]) - {"input", "output"}
    assert set(stats["seconds"]) == cli_stages
    assert {"contact_points", "poisson", "carving"} <= cli_stages
    assert all(s >= 0 for s in stats["seconds"].values())
    assert sum(stats["seconds"].values()) <= elapsed
    # At 32^3 the automatic setting turns the sign constraints on; forcing them gives the same mesh.
    assert stats["sign_constraints"] and stats["sign_violations"] > 0
    assert not stats["sign_constraints_dropped"]
    V_on, _ = poisson(np.load(tmp_path / "b.npy"), sign_constraints=True)
    np.testing.assert_array_equal(V_on, V)
    for bad in ("sometimes", 1, None):  # only True, False or "auto", as for projection
        with pytest.raises(ValueError, match="sign_constraints"):
            poisson(np.load(tmp_path / "b.npy"), sign_constraints=bad)
    # Bricks of any size give the automatic bricks' mesh; a bad size is a ValueError.
    V_b, F_b = poisson(np.load(tmp_path / "b.npy"), brick_size=8)
    np.testing.assert_array_equal(V_b, V)
    np.testing.assert_array_equal(F_b, F)
    for bad in ("big", -2):
        with pytest.raises(ValueError, match="brick_size"):
            poisson(np.load(tmp_path / "b.npy"), brick_size=bad)
    with pytest.raises(ValueError, match="tolerance"):
        poisson(np.load(tmp_path / "b.npy"), finest_solver_tolerance=0.0)
    # Without the sign constraints: the CLI's --no-sign-constraints mesh, a different one.
    subprocess.run([*POISSON_CLI, str(tmp_path / "b.npy"), "-o", str(tmp_path / "free.ply"), "-q",
                    "--no-sign-constraints"], check=True, stdout=subprocess.DEVNULL)
    V_free, F_free = poisson(np.load(tmp_path / "b.npy"), sign_constraints=False)
    np.testing.assert_array_equal(V_free, sdfcontour.read_mesh(tmp_path / "free.ply")[0])
    assert V_free.shape != V.shape or not np.array_equal(V_free, V)
    # Carving is on by default and moves vertices; carve=False is the CLI's --no-carve mesh, with
    # the same triangles and a larger L1.
    assert stats["carved_vertices"] > 0
    subprocess.run([*POISSON_CLI, str(tmp_path / "b.npy"), "-o", str(tmp_path / "uncarved.ply"),
                    "-q", "--no-carve"], check=True, stdout=subprocess.DEVNULL)
    V_plain, F_plain, plain_stats = poisson(np.load(tmp_path / "b.npy"), carve=False,
                                                       return_stats=True)
    np.testing.assert_array_equal(V_plain, sdfcontour.read_mesh(tmp_path / "uncarved.ply")[0])
    np.testing.assert_array_equal(F_plain, F)
    assert plain_stats["carved_vertices"] == 0
    with pytest.raises(ValueError, match="carve"):
        poisson(np.load(tmp_path / "b.npy"), carve="auto")
    # side_passes=0 (vertices only) is the CLI's --side-passes 0 mesh, and differs from the
    # default's, whose triangles also leave the spheres.
    subprocess.run([*POISSON_CLI, str(tmp_path / "b.npy"), "-o", str(tmp_path / "vertices.ply"),
                    "-q", "--side-passes", "0"], check=True, stdout=subprocess.DEVNULL)
    V_vertices, _ = poisson(np.load(tmp_path / "b.npy"), side_passes=0)
    np.testing.assert_array_equal(V_vertices, sdfcontour.read_mesh(tmp_path / "vertices.ply")[0])
    assert not np.array_equal(V_vertices, V)
    for bad in (-1, 1.5, "all", True):
        with pytest.raises(ValueError, match="side_passes"):
            poisson(np.load(tmp_path / "b.npy"), side_passes=bad)
    # The projection onto the contact points is on by default;
    # projection=False is the CLI's --projection off mesh (same triangles, vertices unprojected).
    assert stats["projected_vertices"] > 0
    subprocess.run([*POISSON_CLI, str(tmp_path / "b.npy"), "-o", str(tmp_path / "unprojected.ply"),
                    "-q", "--projection", "off"], check=True, stdout=subprocess.DEVNULL)
    V_unprojected, F_unprojected, unprojected_stats = poisson(
        np.load(tmp_path / "b.npy"), projection=False, return_stats=True)
    np.testing.assert_array_equal(V_unprojected,
                                  sdfcontour.read_mesh(tmp_path / "unprojected.ply")[0])
    np.testing.assert_array_equal(F_unprojected, F)
    assert unprojected_stats["projected_vertices"] == 0 and not np.array_equal(V_unprojected, V)
    for bad in ("on", 1, None):
        with pytest.raises(ValueError, match="projection"):
            poisson(np.load(tmp_path / "b.npy"), projection=bad)
    # The refinement's dilation: "auto" is 2 cells below 256 samples per axis; 1 is the CLI's
    # --refine-dilation 1 mesh, another one.
    np.testing.assert_array_equal(poisson(np.load(tmp_path / "b.npy"),
                                                     refine_dilation=2)[0], V)
    subprocess.run([*POISSON_CLI, str(tmp_path / "b.npy"), "-o", str(tmp_path / "dilated1.ply"),
                    "-q", "--refine-dilation", "1"], check=True, stdout=subprocess.DEVNULL)
    V_one = poisson(np.load(tmp_path / "b.npy"), refine_dilation=1)[0]
    np.testing.assert_array_equal(V_one, sdfcontour.read_mesh(tmp_path / "dilated1.ply")[0])
    assert V_one.shape != V.shape or not np.array_equal(V_one, V)
    for bad in (0, 5, 1.5, True, "one"):
        with pytest.raises(ValueError, match="refine_dilation"):
            poisson(np.load(tmp_path / "b.npy"), refine_dilation=bad)
    # And the mesh is close to the ground truth the CLI wrote.
    V_gt, F_gt = sdfcontour.read_mesh(tmp_path / "b_mesh.ply")
    d = sdfcontour.distances(V, F, V_gt, F_gt, samples=20000)
    assert d["closed"] and d["L1"] < 0.25 * 2 / 31
    d_plain = sdfcontour.distances(V_plain, F_plain, V_gt, F_gt, samples=20000)
    assert d["L1"] < d_plain["L1"]


def test_float32_and_float64_agree():
    grid32 = full_grid(sphere, 40).astype(np.float32)
    V32, F32 = sdfcontour.contour(grid32)
    V64, F64 = sdfcontour.contour(grid32.astype(np.float64))
    assert V32.shape == V64.shape
    assert np.max(np.abs(V32 - V64)) <= 1e-6
    np.testing.assert_array_equal(F32, F64)


@pytest.mark.parametrize("reconstruction", ["poisson", "local"])
def test_a_grid_that_cuts_the_surface_gives_gcp_cut_at_its_side(reconstruction):
    # A cropped volume (the sphere runs out of the grid at x = 0.3): GCP's mesh ends at the
    # grid's side like marching cubes' and stays closer to the sphere. (Poisson's surface closes
    # outside the grid and is cut there; the local mesh ends at the grid's last cells.)
    x = np.linspace(-1.0, 0.3, 40)
    yz = np.linspace(-1.0, 1.0, 61)
    p = np.stack(np.meshgrid(x, yz, yz, indexing="ij"), -1).reshape(-1, 3)
    grid = sphere(p).reshape(40, 61, 61)
    bounds = ((-1.0, -1.0, -1.0), (0.3, 1.0, 1.0))
    V, F, stats = sdfcontour.contour(grid, bounds=bounds, reconstruction=reconstruction,
                                     return_stats=True)
    assert "fallback" not in stats
    assert stats["clipped_to_grid"] == (reconstruction == "poisson")
    assert V[:, 0].max() <= 0.3
    V_mc, _ = sdfcontour.contour(grid, bounds=bounds, method="mc")
    assert mean_abs(sphere, V) < 0.25 * mean_abs(sphere, V_mc)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_grid_is_read_in_place(dtype):
    grid = full_grid(sphere, 24).astype(dtype)
    _, _, stats = sdfcontour.contour(grid, method="mc", return_stats=True)
    assert stats["grid_address"] == grid.ctypes.data  # the binding read the caller's buffer
    # A non-contiguous view is copied once, and gives the same mesh as its contiguous copy.
    view = np.swapaxes(grid, 0, 2)
    V, F, stats = sdfcontour.contour(view, method="mc", return_stats=True)
    assert stats["grid_address"] != view.ctypes.data
    V2, F2 = sdfcontour.contour(np.ascontiguousarray(view), method="mc")
    np.testing.assert_array_equal(V, V2)


def test_memory_mapped_grid_is_read_in_place(tmp_path):
    # A grid larger than memory arrives as np.load(..., mmap_mode="r"): read-only, never copied.
    grid = full_grid(sphere, 24).astype(np.float32)
    np.save(tmp_path / "g.npy", grid)
    mapped = np.load(tmp_path / "g.npy", mmap_mode="r")
    assert not mapped.flags.writeable
    V, F, stats = sdfcontour.contour(mapped, method="mc", return_stats=True)
    assert stats["grid_address"] == mapped.ctypes.data
    V2, F2 = sdfcontour.contour(grid, method="mc")
    np.testing.assert_array_equal(V, V2)
    np.testing.assert_array_equal(F, F2)


@pytest.mark.slow
@pytest.mark.parametrize("f", [sphere, torus], ids=["sphere", "torus"])
def test_callable_is_sampled_near_the_surface_only(f):
    n = 128
    # A callable's automatic reconstruction is the local one: compared with the full grid's.
    V, F, stats = sdfcontour.contour(f, resolution=n, refine=False, return_stats=True)
    assert stats["reconstruction"] == "local"
    assert stats["evaluations"] == round(stats["evaluated_fraction"] * n ** 3)
    # (The shell that the local reconstruction reads: its band of 8 spacings and margin of 1 at
    # 128^3, and 4 spacings more for the gradients: 20-23% of the grid here.)
    assert stats["evaluated_fraction"] <= 0.25
    Vg, Fg = sdfcontour.contour(full_grid(f, n), reconstruction="local")
    assert abs(mean_abs(f, V) - mean_abs(f, Vg)) <= 0.05 * mean_abs(f, Vg)
    assert mean_abs(f, V) < 0.05 * 2 / (n - 1)
    # Refined on the callable (the default): the same triangles, every vertex on the zero set.
    Vr, Fr, stats = sdfcontour.contour(f, resolution=n, return_stats=True)
    np.testing.assert_array_equal(Fr, F)
    assert stats["refined_vertices"] > 0.9 * len(V) and stats["refine_evaluations"] <= 5 * len(V)
    assert mean_abs(f, Vr) < 1e-3 * mean_abs(f, V)


def test_callable_marching_cubes_equals_the_full_grid():
    # The same vertices and triangles (the bricked path numbers them in grid-edge order).
    V, F = sdfcontour.contour(torus, resolution=48, method="mc")
    Vg, Fg = sdfcontour.contour(full_grid(torus, 48), method="mc")
    assert len(V) == len(Vg) and len(F) == len(Fg)
    assert {tuple(map(tuple, V[t])) for t in F} == {tuple(map(tuple, Vg[t])) for t in Fg}


@pytest.mark.slow
def test_scattered_samples_contact_points_and_poisson():
    rng = np.random.default_rng(0)
    points = rng.uniform(-1, 1, (20000, 3))
    values = sphere(points)
    V, F = sdfcontour.contour((points, values))
    V2, F2 = sdfcontour.contour(np.column_stack([points, values]))
    np.testing.assert_array_equal(V, V2)
    assert mean_abs(sphere, V) < 0.02
    P, N = sdfcontour.contact_points(full_grid(sphere, 32))
    assert np.max(np.abs(sphere(P))) < 0.01  # GCP is exact on a sphere up to its gradients
    assert np.min(np.sum(N * P / np.linalg.norm(P, axis=1)[:, None], axis=1)) > 0.99
    Vp, Fp = sdfcontour.poisson(P, N, depth=7)
    assert mean_abs(sphere, Vp) < 0.01
    # Unit weights change nothing; a light, shifted copy pulls the surface less than a full one.
    Vw, Fw = sdfcontour.poisson(P, N, weights=np.ones(len(P)), depth=7)
    np.testing.assert_array_equal(Vp, Vw)
    P2, N2 = np.vstack([P, 1.05 * P]), np.vstack([N, N])
    V_full, _ = sdfcontour.poisson(P2, N2, depth=7)
    V_light, _ = sdfcontour.poisson(P2, N2, weights=np.r_[np.ones(len(P)), np.full(len(P), 0.05)],
                                    depth=7)
    assert mean_abs(sphere, V_light) < 0.5 * mean_abs(sphere, V_full)
    with pytest.raises(ValueError, match="weight"):
        sdfcontour.poisson(P, N, weights=np.ones(3))
    # Quadratic elements: as close on a sphere, a different function (so a different mesh).
    V2, F2 = sdfcontour.poisson(P, N, depth=7, degree=2)
    assert mean_abs(sphere, V2) < 0.01
    assert V2.shape != Vp.shape or not np.array_equal(V2, Vp)
    for bad in (0, 3, 1.5, True):
        with pytest.raises(ValueError, match="degree"):
            sdfcontour.poisson(P, N, degree=bad)


def test_sample_and_distances():
    V, F = sdfcontour.contour(full_grid(sphere, 32), method="mc")
    grid = sdfcontour.sample(V, F, resolution=20, scale=None)
    assert grid.shape == (20, 20, 20)
    exact = full_grid(sphere, 20)
    assert np.max(np.abs(grid - exact)) < 0.01  # the MC mesh is within 0.01 of the sphere
    d = sdfcontour.distances(V, F, V, F, samples=5000)
    assert d["L1"] < 1e-12 and d["L_inf"] < 1e-12 and d["components"] == 1


@pytest.mark.parametrize("bad, message", [
    (np.full((8, 8, 8), np.nan), "NaN"),
    (np.zeros((3, 3)), "neither a grid"),
    (np.ones((8, 8, 8)), "no surface"),
    (np.zeros((0, 4, 4)), "0 samples"),
    (np.array([["a"]]), "numbers"),
])
def test_bad_input_raises_value_error(bad, message):
    with pytest.raises(ValueError, match=message):
        sdfcontour.contour(bad)


def test_bad_options_raise_value_error():
    grid = full_grid(sphere, 16)
    for kwargs, message in [({"method": "marching"}, "unknown method"), ({"band": -1}, "band"),
                            ({"bounds": (1, -1)}, "bounds"), ({"weights": "heavy"}, "weights"),
                            ({"depth": 40}, "depth"), ({"resolution": 64}, "callable")]:
        with pytest.raises(ValueError, match=message):
            sdfcontour.contour(grid, **kwargs)
    with pytest.raises(ValueError, match="resolution"):
        sdfcontour.contour(sphere)
    with pytest.raises(ValueError, match="NaN"):
        sdfcontour.contour(lambda p: np.full(len(p), np.nan), resolution=16)
    with pytest.raises(ValueError, match="values for"):
        sdfcontour.contour(lambda p: np.zeros(3), resolution=16)
    with pytest.raises(ValueError, match="closed"):
        sdfcontour.sample(np.eye(3), np.array([[0, 1, 2]]))


_CTRL_C_CHILD = """
import os, signal, sys, threading, time
# (A process that ignores SIGINT passes that on to its children: Python's own handler, as an
# interactive session has it.)
signal.signal(signal.SIGINT, signal.default_int_handler)
signal.pthread_sigmask(signal.SIG_UNBLOCK, {{signal.SIGINT}})  # (a blocked mask is inherited too)
sys.path.insert(0, {here!r})
import sdfcontour
from test_module import full_grid, sphere, torus
at, options = {at!r}, {options!r}
grid = full_grid(torus, 256 if not options else 96)
sent = []
timer = threading.Timer(at, lambda: (sent.append(time.monotonic()),
                                     os.kill(os.getpid(), signal.SIGINT)))
timer.start()
try:
    sdfcontour.contour(grid, **options)
    sys.exit("did not raise KeyboardInterrupt")
except KeyboardInterrupt:
    stopped = time.monotonic()
timer.join()
assert sent and stopped - sent[0] < 1.0, stopped - sent[0]
V, F = sdfcontour.contour(full_grid(sphere, 16), method="mc")  # works on after an interrupt
assert len(F) > 0
"""


@pytest.mark.parametrize("at, options", [(1.0, {}), (4.0, {}),
                                         (1.0, {"band": "all", "brick_size": 0})])
def test_ctrl_c_interrupts_within_a_second(at, options):
    # GCP takes ~6 s at 256^3 (on 2 cores; 160^3 took under 4 s once the sphere tests went box
    # by box), so both times fall inside the run; the last case is one long global
    # triangulation with no checkpoint inside, left to finish in the background. In a fresh
    # interpreter: the threads that earlier tests leave (a Dask client's loop) do not share it.
    import sys
    child = _CTRL_C_CHILD.format(here=os.path.dirname(os.path.abspath(__file__)), at=at,
                                 options=options)
    run = subprocess.run([sys.executable, "-c", child], capture_output=True, text=True,
                         timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]


def test_files(tmp_path):
    V, F = sdfcontour.contour(full_grid(sphere, 16), method="mc")
    for name, ascii in [("m.ply", False), ("m.ply", True), ("m.obj", False)]:
        sdfcontour.write_mesh(tmp_path / name, V, F, ascii=ascii)
        V2, F2 = sdfcontour.read_mesh(tmp_path / name)
        np.testing.assert_allclose(V2, V, rtol=1e-15 if name.endswith("ply") and not ascii else 1e-6)
        np.testing.assert_array_equal(F2, F)
    with pytest.raises(OSError):
        sdfcontour.read_mesh(tmp_path / "missing.obj")
    with pytest.raises(OSError):
        sdfcontour.write_mesh(tmp_path / "no" / "dir" / "m.ply", V, F)
    (tmp_path / "bad.ply").write_text("ply\nformat ascii 1.0\nproperty float x\n")
    with pytest.raises(ValueError, match="before any element"):
        sdfcontour.read_mesh(tmp_path / "bad.ply")


def test_help_explains_each_option():
    doc = sdfcontour.contour.__doc__
    for name in ["sdf", "bounds", "method", "resolution", "band", "depth", "progress", "Examples"]:
        assert name in doc


@pytest.mark.slow
def assert_the_clis_mesh(tmp_path, grid, mesh, *options):
    """`sdfcontour contour` of `grid` (saved as .npy) with `options` gives `mesh` (V, F) bit for
    bit."""
    np.save(tmp_path / "cli_grid.npy", grid)
    out = tmp_path / "cli_mesh.ply"
    subprocess.run([CLI, "contour", str(tmp_path / "cli_grid.npy"), "-o", str(out), *options,
                    "--quiet"], check=True)
    V, F = sdfcontour.read_mesh(str(out))
    assert np.array_equal(mesh[0], V) and np.array_equal(mesh[1], F)


def test_local_reconstruction_matches_the_cli_and_the_surface(tmp_path):
    # A callable torus, contoured locally: the same mesh as the CLI on the same grid, closed, and
    # its vertices within 0.02 spacings of the torus on average (marching cubes: ~0.05).
    n = 32
    g = full_grid(torus, n)
    V, F, stats = sdfcontour.contour(g, reconstruction="local", return_stats=True)
    assert stats["reconstruction"] == "local"
    h = 2 / (n - 1)
    assert np.abs(torus(V)).mean() < 0.02 * h
    assert_the_clis_mesh(tmp_path, g, (V, F), "--reconstruction", "local")
    with pytest.raises(ValueError, match="reconstruction"):
        sdfcontour.contour(g, reconstruction="global")
    with pytest.raises(ValueError, match="subdivisions"):
        sdfcontour.contour(g, reconstruction="local", subdivisions=9)
    # Without the split of the sagging edges: fewer triangles, the CLI's mesh alike.
    V3, F3 = sdfcontour.contour(g, reconstruction="local", split_sag="off")
    assert 0 < len(F3) < len(F)
    assert_the_clis_mesh(tmp_path, g, (V3, F3), "--reconstruction", "local", "--split-sag", "0")
    for bad in (2, -0.1, "some", True):
        with pytest.raises(ValueError, match="split_sag"):
            sdfcontour.contour(g, reconstruction="local", split_sag=bad)
    # Without the grid at twice the resolution (on below 96 samples per axis): the CLI's mesh
    # alike, and no point of it in a thin part (the torus has none).
    V5, F5, s5 = sdfcontour.contour(g, reconstruction="local", thin_parts=False, return_stats=True)
    assert stats["local_thin_points"] == 0 and s5["local_thin_points"] == 0
    assert V5.shape != V.shape or not np.array_equal(V5, V)  # the finer grid's cells
    assert_the_clis_mesh(tmp_path, g, (V5, F5), "--reconstruction", "local", "--thin-parts",
                         "off")
    for bad in ("on", 1, None):
        with pytest.raises(ValueError, match="thin_parts"):
            sdfcontour.contour(g, reconstruction="local", thin_parts=bad)


def test_edge_fans_give_the_clis_mesh_near_the_surface_with_a_few_times_mcs_triangles(tmp_path):
    # The torus at 32^3 with edge fans: the CLI's mesh bit for bit, closed (every edge in two
    # triangles, Euler characteristic 0), 2-4x marching cubes' triangles (the default has ~20x),
    # its vertices within 0.05 spacings of the torus on average; refused where it cannot run.
    n = 32
    g = full_grid(torus, n)
    V, F = sdfcontour.contour(g, edge_fans=True)
    _, F_mc = sdfcontour.contour(g, method="mc")
    assert 2 * len(F_mc) <= len(F) <= 4 * len(F_mc)
    edges = np.sort(F[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    assert np.all(counts == 2)
    assert len(V) - len(counts) + len(F) == 0
    h = 2 / (n - 1)
    assert np.abs(torus(V)).mean() < 0.05 * h
    assert_the_clis_mesh(tmp_path, g, (V, F), "--edge-fans", "on")
    # On the finer grid of thin parts: two to five times the triangles, closer to the torus.
    V2, F2 = sdfcontour.contour(g, edge_fans=True, thin_parts=True)
    assert 2 * len(F) <= len(F2) <= 5 * len(F)
    assert np.abs(torus(V2)).mean() < np.abs(torus(V)).mean()
    assert_the_clis_mesh(tmp_path, g, (V2, F2), "--edge-fans", "on", "--thin-parts", "on")
    for bad in ("on", 1, None):
        with pytest.raises(ValueError, match="edge_fans"):
            sdfcontour.contour(g, edge_fans=bad)
    # Every sample's contact points (one triangulation of the whole band) take the same bricks.
    V3, F3 = sdfcontour.contour(g, edge_fans=True, band="all", reconstruction="local")
    assert 0.5 * len(F) <= len(F3) <= 2 * len(F)
    assert np.abs(torus(V3)).mean() < 0.05 * h
    with pytest.warns(UserWarning, match="edge_fans"):  # every sample: Poisson's mesh
        sdfcontour.contour(g, edge_fans=True, band="all")


def test_pip_installs_the_command_beside_the_interpreter(tmp_path):
    # `pip install .` puts a `sdfcontour` command next to the environment's python, which runs
    # the C++ program carried in the package: the same mesh as the module's.
    import sys
    command = os.path.join(os.path.dirname(sys.executable), "sdfcontour")
    if not os.path.exists(command):
        pytest.skip("the module is not pip-installed here (run through PYTHONPATH)")
    assert "contour" in subprocess.run([command, "--help"], capture_output=True, text=True,
                                       check=True).stdout
    g = full_grid(torus, 24)
    np.save(tmp_path / "g.npy", g)
    subprocess.run([command, "contour", str(tmp_path / "g.npy"), "-o", str(tmp_path / "m.ply"),
                    "--method", "mc", "--quiet"], check=True)
    V, F = sdfcontour.read_mesh(str(tmp_path / "m.ply"))
    V2, F2 = sdfcontour.contour(g, method="mc")
    assert np.array_equal(V, V2) and np.array_equal(F, F2)


def test_sample_places_the_mesh_as_the_cli_does(tmp_path):
    # Default scale 0.9: the CLI's normalisation, bit for bit; a mesh reaching past the box is
    # brought inside it instead of being cut off.
    V, F = sdfcontour.read_mesh(shared_mesh("spot.obj"))
    V = V * 1.7 + 0.3  # past [-1, 1]
    sdfcontour.write_mesh(tmp_path / "spot.obj", V, F)
    grid, V_unit = sdfcontour.sample(V, F, resolution=24, return_mesh=True)
    subprocess.run([CLI, "sample", str(tmp_path / "spot.obj"), "--res", "24", "-o",
                    str(tmp_path / "s"), "--quiet"], check=True, capture_output=True)
    assert np.array_equal(grid, np.load(tmp_path / "s.npy"))
    V_cli, _ = sdfcontour.read_mesh(tmp_path / "s_mesh.ply")
    assert np.array_equal(V_unit, V_cli)
    assert np.isclose(np.abs(V_unit).max(), 0.9)
    with pytest.raises(ValueError, match="scale"):
        sdfcontour.sample(V, F, 8, scale=0)


@pytest.mark.slow
def test_gcp_output_follows_the_grid():
    # The automatic Poisson depth grows with the samples per axis: at 32^3 the mesh has tens of
    # times marching cubes' triangles at most (depth 8 gave 70x), and is still closer.
    V_gt, F_gt = sdfcontour.read_mesh(shared_mesh("spot.obj"))
    grid, V_gt = sdfcontour.sample(V_gt, F_gt, resolution=32, return_mesh=True)
    mc = sdfcontour.contour(grid, method="mc")
    gcp = sdfcontour.contour(grid, reconstruction="poisson")
    assert gcp.stats["poisson_depth"] == 7
    assert len(gcp.F) < 25 * len(mc.F)
    # The default, local: subdivided on the grid at twice the resolution (21x, 0.15x measured).
    local = sdfcontour.contour(grid)
    # A Poisson option with it is said (the CLI's warning), and changes nothing.
    with pytest.warns(UserWarning, match="reconstruction='poisson'"):
        np.testing.assert_array_equal(sdfcontour.contour(grid, depth=8, alpha=10).V, local.V)
    # So are the local reconstruction's options on the Poisson path, and nothing on the path
    # that reads them.
    with pytest.warns(UserWarning, match="subdivisions, thin_parts set the local"):
        np.testing.assert_array_equal(
            sdfcontour.contour(grid, reconstruction="poisson", subdivisions=1,
                               thin_parts=False).V, gcp.V)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sdfcontour.contour(grid, subdivisions=1)
    assert len(local.F) < 25 * len(mc.F)
    l1 = {name: sdfcontour.distances(m.V, m.F, V_gt, F_gt, samples=50000)["L1"]
          for name, m in (("mc", mc), ("gcp", gcp), ("local", local))}
    assert l1["gcp"] < 0.5 * l1["mc"]
    assert l1["local"] < 0.3 * l1["mc"]


def test_write_mesh_off_and_stl(tmp_path):
    V, F = sdfcontour.contour(full_grid(torus, 20), method="mc")
    sdfcontour.write_mesh(tmp_path / "m.off", V, F)
    V2, F2 = sdfcontour.read_mesh(tmp_path / "m.off")  # 17 digits: exact round trip
    assert np.array_equal(V, V2) and np.array_equal(F, F2)
    sdfcontour.write_mesh(tmp_path / "m.stl", V, F)
    raw = (tmp_path / "m.stl").read_bytes()
    count = int(np.frombuffer(raw[80:84], "<u4")[0])
    records = np.frombuffer(raw[84:], np.dtype([("n", "<f4", 3), ("p", "<f4", (3, 3)),
                                                 ("spare", "<u2")]))
    assert count == len(F) == len(records)
    assert np.array_equal(records["p"], V[F].astype(np.float32))
    cross = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    assert np.allclose(records["n"], cross / np.linalg.norm(cross, axis=1, keepdims=True),
                       atol=1e-6)
    with pytest.raises(ValueError, match=".stl"):
        sdfcontour.write_mesh(tmp_path / "m.xyz", V, F)


def test_paths_as_input_npy_and_vdb(tmp_path):
    # A .vdb is read sparse as the CLI reads it: the same mesh bit for bit; a .npy is mapped.
    subprocess.run([CLI, "sample", shared_mesh("spot.obj"),
                    "--res", "32", "-o", str(tmp_path / "spot.vdb"), "--quiet"], check=True,
                   capture_output=True)
    subprocess.run([CLI, "contour", str(tmp_path / "spot.vdb"), "-o", str(tmp_path / "cli.ply"),
                    "--quiet"], check=True, capture_output=True)
    mesh = sdfcontour.contour(tmp_path / "spot.vdb")
    V, F = sdfcontour.read_mesh(tmp_path / "cli.ply")
    assert np.array_equal(mesh.V, V) and np.array_equal(mesh.F, F)
    with pytest.raises(ValueError, match="no float grid named"):
        sdfcontour.contour(tmp_path / "spot.vdb", grid_name="density")
    g = full_grid(torus, 20)
    np.save(tmp_path / "g.npy", g)
    V1, F1 = sdfcontour.contour(str(tmp_path / "g.npy"), method="mc")
    V2, F2 = sdfcontour.contour(g, method="mc")
    assert np.array_equal(V1, V2) and np.array_equal(F1, F2)
    with pytest.raises(OSError):
        sdfcontour.contour(tmp_path / "missing.npy")
    with pytest.raises(ValueError, match=".npy or .vdb"):
        sdfcontour.contour(str(tmp_path / "cli.ply"))


def small_parts(p):
    """A ball of radius 0.5 and two of radius 0.04, far apart: parts a sampler could skip."""
    d = np.linalg.norm(p - [0.3, 0, 0], axis=1) - 0.5
    d = np.minimum(d, np.linalg.norm(p - [-0.7, 0.6, 0.5], axis=1) - 0.04)
    return np.minimum(d, np.linalg.norm(p - [-0.6, -0.7, -0.4], axis=1) - 0.04)


def test_callable_marching_cubes_by_bricks_is_the_full_grids_mesh():
    # Sampled brick by brick near the surface only: the full grid's mesh, from a few percent of
    # the evaluations and without an n^3 array.
    n = 129
    axis = -1 + np.arange(n) * (2 / (n - 1))  # the sampler's positions, lo + i h
    P = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)
    V, F, stats = sdfcontour.contour(small_parts, resolution=n, method="mc", return_stats=True)
    V2, F2 = sdfcontour.contour(small_parts(P).reshape(n, n, n), method="mc")
    from sdfcontour.dask import canonical_mesh  # same positions bit for bit, same triangles
    (Vc, Fc), (Vc2, Fc2) = canonical_mesh(V, F), canonical_mesh(V2, F2)
    assert np.array_equal(Vc, Vc2) and np.array_equal(Fc, Fc2)
    assert stats["evaluated_fraction"] < 0.06 and stats["components"] == 3 and stats["closed"]


@pytest.mark.slow
@pytest.mark.parametrize("scale,n,brick", [(1.0, 48, 24), (1.3, 64, "auto"), (1.0, 64, 24)])
def test_callable_gcp_by_bricks_is_the_full_grids_local_mesh(scale, n, brick):
    # GCP's local reconstruction of a callable goes brick by brick too, from bricks sampled near
    # the surface: bit for bit the full grid's mesh; a field steeper than a distance is rescaled
    # by the same factor (and sampled over the wider band that its values then need).
    def f(p):
        return scale * torus(p)
    axis = -1 + np.arange(n) * (2 / (n - 1))
    P = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sdfcontour.RescaleWarning)
        V, F, stats = sdfcontour.contour(f, resolution=n, refine=False, brick_size=brick,
                                         lipschitz=scale, return_stats=True)
        # (thin_parts: a callable's "auto" is off, an array's on below 96 samples per axis.)
        V2, F2, stats2 = sdfcontour.contour(f(P).reshape(n, n, n), reconstruction="local",
                                            brick_size=brick, thin_parts=False, return_stats=True)
    from sdfcontour.dask import canonical_mesh
    (Vc, Fc), (Vc2, Fc2) = canonical_mesh(V, F), canonical_mesh(V2, F2)
    assert np.array_equal(Vc, Vc2) and np.array_equal(Fc, Fc2)
    assert stats["value_scale"] == stats2["value_scale"]
    assert abs(stats["value_scale"] - 1 / scale) < 1e-3
    assert stats["reconstruction"] == "local" and stats["closed"] and stats["manifold"]
    assert stats["local_bricks"] == {(48, 24): 8, (64, 24): 27}.get((n, brick), 1)


def test_callable_gcp_says_whether_its_mesh_is_edge_fanned():
    # A callable's stats say which local mesh ran, as a grid's do: at 48 samples per axis the
    # repaired one by default, the fans when asked, with their fewer triangles (no subdivision).
    def f(p):
        return np.linalg.norm(p, axis=1) - 0.4
    V, F, stats = sdfcontour.contour(f, resolution=48, return_stats=True)
    Vf, Ff, fanned = sdfcontour.contour(f, resolution=48, return_stats=True, edge_fans=True)
    assert stats["local_edge_fans"] is False and fanned["local_edge_fans"] is True
    assert len(Ff) < len(F) / 2 and fanned["closed"] and fanned["manifold"]


@pytest.mark.slow
def test_callable_poisson_and_contact_points_come_from_the_bricks_near_the_surface():
    # The Poisson path and contact_points() of a callable read the bricks sampled near the
    # surface as the core's sparse grid: the full grid's mesh and points, bit for bit, without an
    # n^3 array (a field 1.3x a distance: rescaled by the same factor).
    n = 72

    def f(p):
        return 1.3 * sphere(p)
    axis = -1 + np.arange(n) * (2 / (n - 1))
    P = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)
    grid = f(P).reshape(n, n, n)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sdfcontour.RescaleWarning)
        V, F, stats = sdfcontour.contour(f, resolution=n, reconstruction="poisson", refine=False,
                                         lipschitz=1.3, return_stats=True)
        V2, F2, stats2 = sdfcontour.contour(grid, reconstruction="poisson", return_stats=True)
        Pc, Nc, pstats = sdfcontour.contact_points(f, resolution=n, lipschitz=1.3,
                                                   return_stats=True)
        Pc2, Nc2 = sdfcontour.contact_points(grid)
        # lipschitz left at 1: the field breaks it, and is sampled again with a larger bound
        # (and over the wider band its value scale asks for), evaluating only what the first
        # pass did not: the same points, for far fewer than two passes' evaluations.
        Pc3, Nc3, again = sdfcontour.contact_points(f, resolution=n, return_stats=True)
    from sdfcontour.dask import canonical_mesh
    (Vc, Fc), (Vc2, Fc2) = canonical_mesh(V, F), canonical_mesh(V2, F2)
    assert np.array_equal(Vc, Vc2) and np.array_equal(Fc, Fc2)
    assert np.array_equal(Pc, Pc2) and np.array_equal(Nc, Nc2)
    assert stats["value_scale"] == stats2["value_scale"] and stats["reconstruction"] == "poisson"
    assert 0 < stats["sampled_bricks"] < 3**3  # bricks of 32 cells: some left unread
    assert np.array_equal(Pc, Pc3) and np.array_equal(Nc, Nc3)
    assert again["lipschitz"] > 1.3 and again["evaluations"] < 1.4 * pstats["evaluations"]
    # The same path for marching tetrahedra: the full grid's mesh.
    Vt, Ft = sdfcontour.contour(f, resolution=40, method="mt-rt", lipschitz=1.3)
    axis = -1 + np.arange(40) * (2 / 39)
    P = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)
    Vt2, Ft2 = sdfcontour.contour(f(P).reshape(40, 40, 40), method="mt-rt")
    (Vc, Fc), (Vc2, Fc2) = canonical_mesh(Vt, Ft), canonical_mesh(Vt2, Ft2)
    assert np.array_equal(Vc, Vc2) and np.array_equal(Fc, Fc2)


@pytest.mark.slow
def test_callable_local_mesh_with_adaptivity_is_the_full_grids():
    # Adaptivity merges the joined mesh of the callable's bricks over their own contact points,
    # in the core's order: the full grid's merged mesh, bit for bit, for any bricks.
    grid = full_grid(torus, 48)
    # (thin_parts: a callable's "auto" is off, an array's on below 96 samples per axis.)
    Vg, Fg, sg = sdfcontour.contour(grid, reconstruction="local", adaptivity=0.1, thin_parts=False,
                                    return_stats=True)
    from sdfcontour.dask import canonical_mesh
    for brick in ("auto", 24):
        V, F, stats = sdfcontour.contour(torus, resolution=48, refine=False, brick_size=brick,
                                         adaptivity=0.1, return_stats=True)
        (Vc, Fc), (Vc2, Fc2) = canonical_mesh(V, F), canonical_mesh(Vg, Fg)
        assert np.array_equal(Vc, Vc2) and np.array_equal(Fc, Fc2)
        assert stats["adaptivity"] == sg["adaptivity"]
        assert stats["adaptivity"]["triangles_after"] * 20 < stats["adaptivity"]["triangles_before"]


@pytest.mark.parametrize("method,reconstruction,adaptivity", [
    ("gcp", "poisson", 0.0), ("gcp", "local", 0.1), ("mc", "auto", 0.1), ("points", "auto", 0.0)])
def test_no_callable_path_makes_an_n3_array(method, reconstruction, adaptivity):
    # Memory follows the surface on every path: a small sphere peaks well below an n^3 float64
    # array in Python's allocations (the sampler's batches of bricks; the core's allocations are
    # its bricks' and the band's). The local reconstruction reads its bricks of 256 cells (their
    # halos included) as dense blocks: below an n^3 array from n = 512.
    import tracemalloc
    n = 512 if reconstruction == "local" else 256
    centre = np.array([-0.5, -0.5, -0.5])

    def small(p):
        return np.linalg.norm(p - centre, axis=1) - 0.1
    tracemalloc.start()
    try:
        if method == "points":
            P, N = sdfcontour.contact_points(small, resolution=n)
            assert len(P) > 1000
        else:
            V, F, stats = sdfcontour.contour(small, resolution=n, method=method,
                                             reconstruction=reconstruction, refine=False,
                                             adaptivity=adaptivity, return_stats=True)
            assert stats["closed"] and np.abs(small(V)).max() < 2 / (n - 1)
            assert ("adaptivity" in stats) == (adaptivity > 0)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 0.4 * 8 * n**3


def test_adaptivity_merges_flat_parts_and_says_so():
    grid = full_grid(torus, 40)
    V, F, stats = sdfcontour.contour(grid, reconstruction="local", return_stats=True)
    Va, Fa, sa = sdfcontour.contour(grid, reconstruction="local", adaptivity=0.1,
                                    return_stats=True)
    assert sa["adaptivity"] == {"triangles_before": len(F), "triangles_after": len(Fa),
                                "merges": sa["adaptivity"]["merges"],
                                "freeze_rounds": sa["adaptivity"]["freeze_rounds"],
                                "fitted_vertices": sa["adaptivity"]["fitted_vertices"]}
    # The last step fits the merged vertices to the surface: most move.
    assert len(Va) / 2 < sa["adaptivity"]["fitted_vertices"] <= len(Va)
    assert 5 * len(Fa) < len(F) and sa["closed"] and sa["manifold"]
    assert np.abs(torus(Va)).max() < 0.25 * 2 / 39
    assert "adaptivity" not in stats
    with pytest.raises(ValueError, match="adaptivity"):
        sdfcontour.contour(grid, adaptivity=-1)


@pytest.mark.slow
@pytest.mark.parametrize("steepness", [3, 10])
def test_a_field_steeper_than_a_distance_keeps_its_small_parts(steepness):
    def steep(p):
        return steepness * small_parts(p)
    for method in ("mc", "gcp"):
        with pytest.warns(sdfcontour.LipschitzWarning, match="sampled again"):
            mesh = sdfcontour.contour(steep, resolution=128, method=method)
        assert mesh.stats["components"] == 3, method
        assert mesh.stats["lipschitz"] >= steepness
    # Said up front: one pass, no warning.
    with warnings.catch_warnings():
        warnings.simplefilter("error", sdfcontour.LipschitzWarning)
        mesh = sdfcontour.contour(steep, resolution=128, method="mc", lipschitz=steepness)
    assert mesh.stats["components"] == 3
    with pytest.raises(ValueError, match="lipschitz"):
        sdfcontour.contour(steep, resolution=16, lipschitz=0)


def test_progress_callback_gets_fractions():
    # One callback for every stage: start messages (total 0) and fractions that end complete.
    events = []
    sdfcontour.contour(full_grid(torus, 40), progress=lambda *e: events.append(e))
    bricks = [(done, total) for stage, done, total in events if stage == "bricks"]
    assert bricks and bricks[-1][0] == bricks[-1][1] > 0  # the default, local, brick by brick
    events = []
    sdfcontour.contour(full_grid(torus, 40), reconstruction="poisson",
                       progress=lambda *e: events.append(e))
    assert any(total == 0 for _, _, total in events)
    # The stages after the solve report theirs too, each run rising to complete (untangling
    # runs after projection and again after carving).
    for name in ("poisson", "projection", "carving", "untangling"):
        fractions = [(done, total) for stage, done, total in events if stage == name]
        assert fractions, name
        runs = [[fractions[0]]]
        for (done, total), (before, _) in zip(fractions[1:], fractions):
            if done < before:
                runs.append([])
            runs[-1].append((done, total))
        assert all(run[-1][0] == run[-1][1] > 0 for run in runs), (name, runs)
        assert len(runs) <= (2 if name == "untangling" else 1), name
    events.clear()
    sdfcontour.contour(torus, resolution=65, method="mc", progress=lambda *e: events.append(e))
    bricks = [(done, total) for stage, done, total in events if stage == "bricks"]
    assert bricks and bricks[-1][0] == bricks[-1][1]
    with pytest.raises(TypeError, match="progress"):
        sdfcontour.contour(full_grid(torus, 20), progress="yes")


def test_the_options_table_is_the_source_of_contours_keywords_and_cli_names():
    # contour_option_names (C++) lists every keyword of sdfcontour.contour() and every option of
    # `sdfcontour contour`; a name added on one side only fails here (Python) or at the CLI's
    # start (C++).
    import inspect
    import re

    from sdfcontour import _sdfcontour
    table = _sdfcontour.contour_option_names()
    keywords = {python for _, python, _ in table if python}
    assert keywords == set(inspect.signature(sdfcontour.contour).parameters)
    cli = CLI
    if not os.path.exists(cli):
        pytest.skip(f"no CLI at {cli}: the CLI checks its own half when it starts")
    listed = subprocess.run([cli, "contour", "--help-all"], capture_output=True, text=True,
                            check=True).stdout
    declared = set(re.findall(r"^\s+(?:-\w,)?--([a-z0-9-]+)", listed, re.M))
    assert declared == {name for name, _, _ in table if name}
    # --help shows the user's options and no more.
    short = subprocess.run([cli, "contour", "--help"], capture_output=True, text=True,
                           check=True).stdout
    assert set(re.findall(r"^\s+(?:-\w,)?--([a-z0-9-]+)", short, re.M)) == {
        name for name, _, user in table if name and user}
    # Every numeric range names a keyword in the table (or none).
    assert set(_sdfcontour.option_ranges()) <= keywords | {"resolution"}

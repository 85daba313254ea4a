"""Random option values through one entry point, for test_option_properties.py: run as
``python random_options.py ENTRY SEED TRIALS [CLI]`` (ENTRY: python, dask, callable or cli). Each
trial gives 1-3 options of the shared table (contour_option_names) values drawn from a pool of
hostile ones. A trial must end in the entry point's own clean error (Python: ValueError,
TypeError, OSError; the CLI: exit 1 with one 'sdfcontour: error:' line and no output file) or
in a sound mesh (finite vertices, triangles indexing them). The script exits 0 when every trial
did; anything else (another exception, a signal, a hang caught by the caller's timeout) fails."""
import os
import subprocess
import sys
import tempfile
import warnings

import numpy as np

import sdfcontour
import sdfcontour.dask
from sdfcontour import _sdfcontour

N = 14  # a small sphere grid: each trial stays well under a second
VALUES = [-1, 0, 1, 2, 0.5, -0.5, 3.7, 1e300, -1e300, float("nan"), float("inf"), float("-inf"),
          2**70, -(2**63), True, False, None, "abc", "", "auto", "on", "off", "all", "none",
          "0_1", " 1", "1e-320", [1, 2], (0.1,), {"a": 1}, b"\x00", np.float32(0.25),
          np.array([1.0, 2.0]), "gcp", "mc", "local", "poisson", "lattice", "regular"]
# Values that many options accept: half the draws, so that trials also reach the pipeline.
PLAUSIBLE = [0, 1, 2, 3, 8, 0.5, 0.01, 1e-3, True, False, "auto", "on", "off"]
# Keywords that name files or the input itself, and those whose valid values cost memory
# without bound on purpose (the caller's choice, bounded by the ranges table).
SKIP = {"sdf", "grid_name"}


def draw(rng):
    pool = PLAUSIBLE if rng.random() < 0.5 else VALUES
    return pool[int(rng.integers(len(pool)))]


def sphere_grid():
    x = np.linspace(-1, 1, N)
    X, Y, Z = np.meshgrid(x, x, x, indexing="ij")
    return np.sqrt(X**2 + Y**2 + Z**2) - 0.5


def sphere_function(P):
    return np.linalg.norm(P, axis=1) - 0.5


def check_mesh(result):
    V, F = result[0], result[1]
    V, F = np.asarray(V), np.asarray(F)
    assert V.ndim == 2 and V.shape[1] == 3 and np.isfinite(V).all(), "vertices not finite"
    assert F.ndim == 2 and F.shape[1] == 3, "triangles not (f, 3)"
    if len(F):
        assert F.min() >= 0 and F.max() < len(V), "a triangle indexes no vertex"
    else:
        raise AssertionError("an empty mesh returned as success")


def python_trials(entry, rng, trials):
    names = [python for _, python, _ in _sdfcontour.contour_option_names()
             if python and python not in SKIP]
    if entry == "dask":
        import inspect
        allowed = set(inspect.signature(sdfcontour.dask.contour).parameters) - {"source", "client",
                                                                                 "out"}
        names = sorted(allowed)
    grid = sphere_grid()
    meshes = 0
    for trial in range(trials):
        chosen = rng.choice(len(names), size=int(rng.integers(1, 4)), replace=False)
        kwargs = {names[i]: draw(rng) for i in chosen}
        if entry == "callable":
            kwargs.setdefault("resolution", N)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                if entry == "python":
                    result = sdfcontour.contour(grid, **kwargs)
                elif entry == "callable":
                    result = sdfcontour.contour(sphere_function, **kwargs)
                else:
                    result = sdfcontour.dask.contour(grid, **kwargs)
            except (TypeError, ValueError, OSError):
                continue
            except Exception as error:  # noqa: BLE001 (what this test looks for)
                print(f"trial {trial}: {kwargs!r} raised {type(error).__name__}: {error}")
                return 1
        try:
            check_mesh(result)
        except AssertionError as error:
            print(f"trial {trial}: {kwargs!r}: {error}")
            return 1
        meshes += 1
    print(f"{trials} trials, {meshes} meshes, {trials - meshes} refused")
    return 0


def cli_trials(cli, rng, trials):
    names = [c for c, _, _ in _sdfcontour.contour_option_names()
             if c and c not in ("help", "help-all", "output", "stats", "points", "grid")]
    flags = {"ascii", "quiet", "no-carve", "no-side-repair", "no-sign-constraints", "fn",
             "serial-triangulation"}
    texts = [str(v) for v in VALUES if not isinstance(v, (bytes, dict, np.ndarray))] + [
        "-1e9", "1e9", "0x10", "1,2", "-1,-1,-1,1,1,1", "2,1", "nan,1"]
    plausible = [str(v).lower() if isinstance(v, bool) else str(v) for v in PLAUSIBLE]
    with tempfile.TemporaryDirectory() as work:
        grid = os.path.join(work, "g.npy")
        np.save(grid, sphere_grid())
        meshes = 0
        for trial in range(trials):
            out = os.path.join(work, f"m{trial}.ply")
            args = [cli, "contour", grid, "-o", out, "-q"]
            for i in rng.choice(len(names), size=int(rng.integers(1, 4)), replace=False):
                args.append("--" + names[i])
                if names[i] not in flags:
                    pool = plausible if rng.random() < 0.5 else texts
                    args.append(pool[int(rng.integers(len(pool)))])
            run = subprocess.run(args, capture_output=True, text=True, timeout=120)
            errors = [line for line in run.stderr.splitlines() if "error" in line]
            if run.returncode == 0:
                if not (os.path.exists(out) and os.path.getsize(out) > 0):
                    print(f"trial {trial}: {args[4:]}: exit 0 without a mesh")
                    return 1
                V, F = sdfcontour.read_mesh(out)
                try:
                    check_mesh((V, F))
                except AssertionError as error:
                    print(f"trial {trial}: {args[4:]}: {error}")
                    return 1
                meshes += 1
            elif run.returncode == 1:
                if len(errors) != 1 or not errors[0].startswith("sdfcontour: error:") or \
                        os.path.exists(out):
                    print(f"trial {trial}: {args[4:]}: exit 1 with {run.stderr!r}")
                    return 1
            else:
                print(f"trial {trial}: {args[4:]}: exit {run.returncode}: {run.stderr[-500:]!r}")
                return 1
    print(f"{trials} trials, {meshes} meshes, {trials - meshes} refused")
    return 0


def main():
    entry, seed, trials = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    rng = np.random.default_rng(seed)
    if entry == "cli":
        return cli_trials(sys.argv[4], rng, trials)
    return python_trials(entry, rng, trials)


if __name__ == "__main__":
    sys.exit(main())

"""A property test per entry point (CLI, Python arrays, callables, Dask): random option values,
among them negative, zero, NaN, inf, huge numbers and wrong types, end in the entry point's own
clean error or in a sound mesh, never in a signal, a hang or another exception. The trials run
in a child process (random_options.py), so a crash fails the test instead of killing pytest."""
import os
import subprocess
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
CLI = os.environ.get("SDFCONTOUR_CLI", os.path.join(HERE, "..", "..", "build", "sdfcontour"))


def trials(entry, seed, count, *extra):
    run = subprocess.run([sys.executable, os.path.join(HERE, "random_options.py"), entry,
                          str(seed), str(count), *extra], capture_output=True, text=True,
                         timeout=600)
    assert run.returncode == 0, (run.returncode, run.stdout[-2000:], run.stderr[-2000:])
    # Some trials reached a mesh: the draws are not all refused at the door.
    meshes = int(run.stdout.split(" meshes")[0].split()[-1])
    assert meshes > 0, run.stdout


@pytest.mark.parametrize("entry", ["python", "callable"])
def test_random_options_through_python_end_cleanly(entry):
    trials(entry, 11, 150)


@pytest.mark.slow
def test_random_options_through_dask_end_cleanly():
    trials("dask", 11, 150)


def test_random_options_through_the_cli_end_cleanly():
    if not os.path.exists(CLI):
        pytest.skip(f"no CLI at {CLI}")
    trials("cli", 11, 120, CLI)

"""Shared helpers of the Python tests."""
import os

import pytest

SHARED_MESHES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "shared",
                             "data", "meshes")


def shared_mesh(name):
    """The path of a shared test mesh (../shared/data/meshes/NAME); skips the calling test where a
    plain clone has none."""
    path = os.path.join(SHARED_MESHES, name)
    if not os.path.exists(path):
        pytest.skip(f"needs the shared test meshes at {os.path.normpath(SHARED_MESHES)}")
    return path


def pytest_configure(config):
    config.addinivalue_line(
        "markers", "slow: over ~15 s on 2 cores; `bash scripts/test.sh` leaves it out, "
        "`bash scripts/test.sh --all` (CI) runs it")

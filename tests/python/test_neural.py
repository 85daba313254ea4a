"""GCP on a neural SDF (bench/data/neural_bunny.npz: a 4x64 MLP fitted to the bunny, evaluated
with numpy): the local reconstruction never gives up on the whole mesh, and with its vertices
refined on the callable it lies far closer to the network's zero set than marching cubes."""
import os
import sys

import numpy as np
import pytest

import sdfcontour

BENCH = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "bench")
sys.path.insert(0, BENCH)
from neural_sdf import load  # noqa: E402


@pytest.mark.slow
def test_local_gcp_follows_the_network_zero_set():
    f = load(os.path.join(BENCH, "data", "neural_bunny.npz"))
    reference = sdfcontour.contour(f, resolution=160, method="mc")  # the network's zero set
    n = 40
    V_mc, F_mc = sdfcontour.contour(f, resolution=n, method="mc")
    V, F, stats = sdfcontour.contour(f, resolution=n, reconstruction="local", return_stats=True)
    assert "fallback" not in stats
    mc = sdfcontour.distances(V_mc, F_mc, *reference, samples=50000)
    local = sdfcontour.distances(V, F, *reference, samples=50000)
    assert local["closed"]
    assert local["L1"] < 0.5 * mc["L1"], (local["L1"], mc["L1"])
    # Every vertex on the network's zero set, to a small fraction of a spacing.
    assert np.median(np.abs(f(V))) < 1e-3 * 2 / (n - 1)

"""A neural SDF fixture: a 4x64 MLP fitted to a shared mesh's signed distance, as users' neural
SDFs are (only approximately a distance: |grad f| != 1, and a zero set a little off the mesh).

    /usr/bin/python3 bench/neural_sdf.py train --mesh bunny --out bench/data/neural_bunny.npz

trains it with python3-torch (CPU; Debian's package) and writes its weights (float32, ~50 KB);
`load(path)` gives a numpy evaluator f(points (k, 3)) -> (k,) that needs numpy only, so tests and
benchmarks run without torch.
"""
import argparse
import os
import sys

import numpy as np

# Softplus sharpness: smooth enough for Newton steps, sharp enough for a detailed surface.
BETA = 50.0


def load(path):
    """The MLP at `path` as a function of points (k, 3) -> values (k,), float64, numpy only."""
    data = np.load(path)
    layers = [(data[f"w{i}"].astype(np.float64), data[f"b{i}"].astype(np.float64))
              for i in range(int(data["layers"]))]

    def f(points):
        x = np.asarray(points, dtype=np.float64)
        for i, (w, b) in enumerate(layers):
            x = x @ w.T + b
            if i + 1 < len(layers):
                x = np.logaddexp(0.0, BETA * x) / BETA  # softplus
        return x[:, 0]

    return f


def train(mesh, out, hidden=64, depth=4, steps=3000, seed=0):
    import torch  # python3-torch, only for training

    import sdfcontour  # installed (scripts/test.sh's build/venv), or on PYTHONPATH
    from scipy.interpolate import RegularGridInterpolator

    V, F = sdfcontour.read_mesh(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..",
                                             "shared", "data", "meshes", mesh + ".obj"))
    centre = (V.max(0) + V.min(0)) / 2
    V = (V - centre) * (1.8 / (V.max(0) - V.min(0)).max())  # as `sdfcontour sample` normalises
    n = 160
    grid = sdfcontour.sample(V, F, n, scale=None)  # normalised above
    axis = np.linspace(-1, 1, n)
    exact = RegularGridInterpolator((axis, axis, axis), grid)
    rng = np.random.default_rng(seed)
    # Most points near the surface, where a contouring method reads the field.
    near = grid.reshape(-1) ** 2 < 0.1 ** 2
    cells = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), -1).reshape(-1, 3)[near]
    points = np.concatenate([
        cells[rng.integers(len(cells), size=400000)] + rng.normal(0, 0.02, (400000, 3)),
        rng.uniform(-1, 1, (100000, 3))]).clip(-1, 1)
    values = exact(points)
    torch.manual_seed(seed)
    sizes = [3] + [hidden] * depth + [1]
    net = torch.nn.Sequential(*[m for i in range(len(sizes) - 1) for m in (
        [torch.nn.Linear(sizes[i], sizes[i + 1])] +
        ([torch.nn.Softplus(beta=BETA)] if i + 2 < len(sizes) else []))])
    optimiser = torch.optim.Adam(net.parameters(), lr=2e-3)
    schedule = torch.optim.lr_scheduler.CosineAnnealingLR(optimiser, steps)
    X = torch.tensor(points, dtype=torch.float32)
    Y = torch.tensor(values, dtype=torch.float32)
    for step in range(steps):
        batch = torch.randint(len(X), (16384,))
        loss = (net(X[batch])[:, 0] - Y[batch]).abs().mean()
        optimiser.zero_grad()
        loss.backward()
        optimiser.step()
        schedule.step()
        if step % 500 == 0 or step == steps - 1:
            print(f"step {step}: mean |error| {loss.item():.5f}", file=sys.stderr)
    linear = [m for m in net if isinstance(m, torch.nn.Linear)]
    np.savez(out, layers=len(linear), **{f"w{i}": m.weight.detach().numpy() for i, m in
                                        enumerate(linear)},
             **{f"b{i}": m.bias.detach().numpy() for i, m in enumerate(linear)})


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("command", choices=["train"])
    ap.add_argument("--mesh", default="bunny")
    ap.add_argument("--out", default=os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                  "data", "neural_bunny.npz"))
    ap.add_argument("--steps", type=int, default=3000)
    a = ap.parse_args()
    train(a.mesh, a.out, steps=a.steps)

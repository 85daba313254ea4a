"""Two builds of `sdfcontour` against scikit-image's marching cubes, alternating per grid:
scikit-image (bench/scale.py's peer: `np.load` + `marching_cubes`, in its own process), build A,
build B, REPEATS times;
prints a JSON line per grid (each run's seconds, the medians' ratios) and, with --png, draws the
geometric means over the meshes per grid size against issue 64's targets. Ours is the whole CLI
run (reading, contouring, writing the PLY) with default options.

    /usr/bin/python3 bench/builds_vs_skimage.py old/sdfcontour build/sdfcontour \\
        bunny_512.npy spot_512.npy --repeats 3 --png docs/img/speed.png

A grid's size is read from its name's last number (bunny_512.npy: 512)."""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import geomean, read_jsonl  # noqa: E402

SCALE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "scale.py")
TARGETS = {64: 20, 256: 5, 512: 3}  # issue 64's, 2 cores


def ours(cli, grid, out):
    start = time.perf_counter()
    subprocess.run([cli, "contour", grid, "-o", out, "--quiet"], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - start


def plot(rows, png, labels):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    sizes = sorted({r["res"] for r in rows})
    fig, ax = plt.subplots(figsize=(6, 4))
    for key, label, style in (("A/sk", labels[0], "o--"), ("B/sk", labels[1], "s-")):
        ax.plot(sizes, [geomean([r[key] for r in rows if r["res"] == n]) for n in sizes], style,
                label=label)
    shown = [n for n in sizes if n in TARGETS]
    ax.plot(shown, [TARGETS[n] for n in shown], "k_", markersize=24, mew=2, label="issue 64's target")
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xticks(sizes, [f"{n}³" for n in sizes])
    ax.set_xlabel("grid")
    ax.set_ylabel("time / scikit-image's (geometric mean)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(png, dpi=120)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("a", help="build A's CLI (before)")
    ap.add_argument("b", help="build B's CLI (after)")
    ap.add_argument("grids", nargs="*", help=".npy grids")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--png", default="", help="draw the runs' geometric means here")
    ap.add_argument("--from-jsonl", default="", help="draw an earlier run's lines instead of running")
    ap.add_argument("--labels", default="A,B", help="the builds' names in the plot")
    args = ap.parse_args()
    if args.repeats < 1:
        ap.error("--repeats must be at least 1")
    rows = read_jsonl(args.from_jsonl) if args.from_jsonl else []
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "mesh.ply")
        for grid in [] if args.from_jsonl else args.grids:
            runs = {"A": [], "B": [], "skimage": []}
            for _ in range(args.repeats):
                # (bench/scale.py's peer: np.load and marching_cubes in their own process)
                r = subprocess.run([sys.executable, SCALE, "--peer", "skimage", grid,
                                    os.path.join(tmp, "skimage.ply")],
                                   capture_output=True, text=True, check=True)
                runs["skimage"].append(json.loads(r.stdout)["seconds"])
                runs["A"].append(ours(args.a, grid, out))
                runs["B"].append(ours(args.b, grid, out))
            m = {k: statistics.median(v) for k, v in runs.items()}
            row = {"grid": os.path.basename(grid), "res": int(re.findall(r"\d+", os.path.basename(grid))[-1]),
                   **{k: [round(x, 4) for x in v] for k, v in runs.items()},
                   "A/sk": m["A"] / m["skimage"], "B/sk": m["B"] / m["skimage"], "B/A": m["B"] / m["A"]}
            rows.append(row)
            print(json.dumps(row), flush=True)
    if args.png and rows:
        plot(rows, args.png, args.labels.split(","))


if __name__ == "__main__":
    main()

"""Where GCP's time goes, in units of scikit-image's marching cubes on the same grid.

For each grid, alternating runs of `sdfcontour contour GRID --stats` (GCP, defaults) and of
scikit-image (np.load + marching_cubes, as bench/scale.py times it); per stage the median of the
runs. The Poisson stage is split into its own steps (`poisson_seconds`), the contact-point stage
is one bar (CGAL's insertion is most of it: docs/scale.md). Prints a markdown table and draws a
stacked bar per grid, with the issue's 20x line.

Grids are bench/scale.py's (`--work`, sampled there if missing: truncated at 8 spacings above
128^3, float32).

Usage: /usr/bin/python3 bench/stage_breakdown.py [--res 256,512] [--meshes bunny]
       [--runs 3] [--png docs/img/stage_breakdown.png]
"""
import argparse
import json
import os
import subprocess
import sys

import numpy as np

from common import CLI, MESHES, timed

HERE = os.path.dirname(os.path.abspath(__file__))
# Stages in pipeline order; repeated stages (untangling) are summed.
STAGES = ["input", "band", "contact_points", "poisson", "projection", "untangling", "carving",
          "side repair", "output"]


def grid_path(cli, work, name, res):
    prefix = os.path.join(work, f"{name}_{res}")
    if not os.path.exists(prefix + ".npy"):
        extra = ["--truncate", "8"] if res > 128 else []
        subprocess.run([cli, "sample", os.path.join(MESHES, name + ".obj"), "--res", str(res), "-o",
                        prefix, "--float32", "-q", *extra], check=True, stdout=subprocess.DEVNULL)
    return prefix + ".npy"


def gcp_run(cli, grid, work):
    stats = os.path.join(work, "breakdown_stats.json")
    wall, _, _, err = timed([cli, "contour", grid, "-o", os.path.join(work, "breakdown.ply"), "-q",
                             "--stats", stats])
    if wall is None:
        sys.exit(f"sdfcontour failed on {grid}: {err}")
    with open(stats) as f:
        s = json.load(f)
    stages = {name: 0.0 for name in STAGES}
    for name, seconds in s["seconds"].items():
        stages[name] = stages.get(name, 0.0) + seconds
    return wall, stages, s.get("poisson_seconds", {})


def skimage_run(grid, work):
    out = os.path.join(work, "breakdown_skimage.ply")
    wall, _, stdout, err = timed([sys.executable, os.path.join(HERE, "scale.py"), "--peer", "skimage",
                                  grid, out])
    if wall is None:
        sys.exit(f"scikit-image failed on {grid}: {err}")
    return json.loads(stdout)["seconds"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", default=CLI)
    ap.add_argument("--res", default="256,512")
    ap.add_argument("--meshes", default="bunny")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--work", default="/tmp/sdfcontour_scale")
    ap.add_argument("--png", default=None)
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    results = []
    for res in map(int, args.res.split(",")):
        for name in args.meshes.split(","):
            grid = grid_path(args.cli, args.work, name, res)
            walls, stages, poisson, peers = [], [], [], []
            for _ in range(args.runs):
                w, s, p = gcp_run(args.cli, grid, args.work)
                walls.append(w)
                stages.append(s)
                poisson.append(p)
                peers.append(skimage_run(grid, args.work))
            median = {k: float(np.median([s.get(k, 0.0) for s in stages])) for k in stages[0]}
            poisson_median = {k: float(np.median([p.get(k, 0.0) for p in poisson])) for k in poisson[0]}
            results.append({"grid": f"{name} {res}³", "wall": float(np.median(walls)),
                            "skimage": float(np.median(peers)), "stages": median,
                            "poisson": poisson_median})
            print(json.dumps(results[-1]), flush=True)
    report(results)
    if args.png:
        plot(results, args.png)


def report(results):
    grids = [r["grid"] for r in results]
    lines = ["| stage | " + " | ".join(f"{g}: s | {g}: × scikit-image" for g in grids) + " |",
             "|---|" + "---|---|" * len(grids)]

    def row(label, values):
        cells = [f"{v:.2f} | {v / r['skimage']:.1f}" for v, r in zip(values, results)]
        lines.append(f"| {label} | " + " | ".join(cells) + " |")

    for stage in STAGES:
        if any(r["stages"].get(stage, 0) > 0 for r in results):
            row(stage, [r["stages"].get(stage, 0.0) for r in results])
            if stage == "poisson":
                for step in results[0]["poisson"]:
                    row(f"  poisson: {step}", [r["poisson"].get(step, 0.0) for r in results])
    row("**whole run (wall)**", [r["wall"] for r in results])
    row("scikit-image (np.load + marching_cubes)", [r["skimage"] for r in results])
    print("\n".join(lines))


def plot(results, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(8, 1.2 + 0.7 * len(results)))
    colours = plt.get_cmap("tab10")
    labels = [r["grid"] for r in results]
    for i, r in enumerate(results):
        left = 0.0
        for k, stage in enumerate(STAGES):
            width = r["stages"].get(stage, 0.0) / r["skimage"]
            if width <= 0:
                continue
            ax.barh(i, width, left=left, color=colours(k), label=stage if i == 0 else None)
            left += width
    ax.axvline(20, color="black", linestyle="--", linewidth=1)
    ax.text(20.3, len(results) - 0.6, "20× target", fontsize=8)
    ax.set_yticks(range(len(results)), labels)
    ax.invert_yaxis()
    ax.set_xlabel("GCP's stages, in units of scikit-image's time on the same grid")
    ax.legend(fontsize=7, ncol=3, loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()

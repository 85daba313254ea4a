"""The local reconstruction's stages (`sdfcontour contour ... --stats FILE`), side by side for two
or more runs of the same grid: horizontal bars per stage, one colour per run.

    /usr/bin/python3 bench/stage_bars.py --run "session 38=old.json" --run "session 39=new.json" \\
        --title "bunny 256³" --png docs/img/stages_s39.png
"""
import argparse
import json

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--run", action="append", required=True, metavar="LABEL=STATS.json")
    ap.add_argument("--title", default="")
    ap.add_argument("--png", required=True)
    args = ap.parse_args()
    runs = []
    for spec in args.run:
        label, path = spec.split("=", 1)
        with open(path) as f:
            stats = json.load(f)
        runs.append((label, stats["local_seconds"], stats["seconds_total"]))
    stages = list(runs[0][1])
    height = 0.8 / len(runs)
    fig, ax = plt.subplots(figsize=(7, 0.5 + 0.45 * len(stages) * len(runs) / 2))
    for r, (label, seconds, total) in enumerate(runs):
        ys = [s + r * height for s in range(len(stages))]
        ax.barh(ys, [seconds.get(k, 0) for k in stages], height=height,
                label=f"{label} (whole run {total:.1f} s)")
    ax.set_yticks([s + height * (len(runs) - 1) / 2 for s in range(len(stages))])
    ax.set_yticklabels(stages)
    ax.invert_yaxis()
    ax.set_xlabel("seconds (2 cores)")
    ax.set_title(args.title)
    ax.legend(loc="upper right")
    fig.tight_layout()
    fig.savefig(args.png, dpi=110)


if __name__ == "__main__":
    main()

"""Draws the thread scaling that ../shared/tools/scaling.py measures (its scaling.jsonl, with each
run's `local_seconds` copied in, as docs/notes/results/device_session11.jsonl holds them): GCP's wall time
against the thread count per grid, scikit-image's marching cubes (one thread) as a line, and the
local reconstruction's stages against the thread count for one grid.

Usage: /usr/bin/python3 bench/threads_plot.py docs/notes/results/device_session11.jsonl \
           --png docs/img/threads_device.png [--stages-res 256]
"""
import argparse
import json

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

STAGES = ["contact points", "reconstruction", "subdivision and projection", "carving", "untangling"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("jsonl")
    ap.add_argument("--png", required=True)
    ap.add_argument("--stages-res", type=int, default=256)
    a = ap.parse_args()
    rows = [json.loads(line) for line in open(a.jsonl)]
    runs = [r for r in rows if "threads" in r and r.get("gcp_s")]
    skimage = {(r["mesh"], r["res"]): r["skimage_s"] for r in rows if "skimage_s" in r}
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    for i, key in enumerate(sorted({(r["mesh"], r["res"]) for r in runs}, key=lambda k: k[1])):
        mine = sorted((r for r in runs if (r["mesh"], r["res"]) == key), key=lambda r: r["threads"])
        colour = f"C{i}"
        left.plot([r["threads"] for r in mine], [r["gcp_s"] for r in mine], "o-", color=colour,
                  label=f"GCP-local, {key[0]} {key[1]}³")
        if key in skimage:
            left.axhline(skimage[key], color=colour, ls=":", lw=1,
                         label=f"scikit-image MC, {key[1]}³ ({skimage[key]:.2f} s)")
    left.set_xscale("log", base=2); left.set_yscale("log")
    left.set_xlabel("threads"); left.set_ylabel("wall time (s)")
    left.set_title("Wall time against threads (16-CPU machine)")
    left.legend(fontsize=7)
    mine = sorted((r for r in runs if r["res"] == a.stages_res and "local_seconds" in r),
                  key=lambda r: r["threads"])
    threads = [r["threads"] for r in mine]
    for k, stage in enumerate(STAGES):
        right.plot(threads, [r["local_seconds"].get(stage, 0) for r in mine], "o-", color=f"C{k}",
                   label=stage)
    if mine:  # a perfect speed-up of the slowest stage, for the eye
        first = mine[0]["local_seconds"][STAGES[0]]
        right.plot(threads, [first * threads[0] / t for t in threads], "k:", lw=1,
                   label="ideal (contact points)")
    right.set_xscale("log", base=2); right.set_yscale("log")
    right.set_xlabel("threads"); right.set_ylabel("seconds")
    right.set_title(f"Local reconstruction's stages, bunny {a.stages_res}³")
    right.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(a.png, dpi=110)


if __name__ == "__main__":
    main()

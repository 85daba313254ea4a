"""One thread against two, in alternating pairs: runs `sdfcontour contour INPUT ARGS --threads 1`
and `--threads 2` PAIRS times each, alternating (this machine's speed drifts between runs), and
prints the median totals and local stages (`--stats`) of each and the speed-up, per pair and of
the medians. Issue 64 asks for at least 1.9x.

    /usr/bin/python3 bench/threads_pairs.py 3 bunny256.npy --edge-fans on --gradient lattice --band 2

SDFCONTOUR_CLI names the binary (default: build/sdfcontour)."""
import os
import statistics
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from common import contour_stats  # noqa: E402


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    pairs, args = int(sys.argv[1]), sys.argv[2:]
    cli = os.environ.get("SDFCONTOUR_CLI", os.path.join(HERE, "..", "build", "sdfcontour"))
    totals, stages = {1: [], 2: []}, {1: [], 2: []}
    with tempfile.TemporaryDirectory() as tmp:
        mesh, stats = os.path.join(tmp, "mesh.ply"), os.path.join(tmp, "stats.json")
        for _ in range(pairs):
            for threads in (1, 2):
                total, stage = contour_stats(cli, [*args, "--threads", str(threads)], mesh, stats)
                totals[threads].append(total)
                stages[threads].append(stage)
    for threads in (1, 2):
        median = {k: statistics.median(s[k] for s in stages[threads])
                  for k in stages[threads][0]}
        print(f"{threads} thread(s): total median {statistics.median(totals[threads]):.3f} s",
              " ".join(f"{k}={v:.3f}" for k, v in median.items() if v > 0.001))
    print("speed-up of the medians %.3f, per pair %s" % (
        statistics.median(totals[1]) / statistics.median(totals[2]),
        [round(a / b, 3) for a, b in zip(totals[1], totals[2])]))


if __name__ == "__main__":
    main()

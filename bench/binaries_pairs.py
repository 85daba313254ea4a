"""Two builds of `sdfcontour` against each other, in alternating pairs (this machine's speed
drifts between runs): runs `A contour ARGS` and `B contour ARGS` PAIRS times each, alternating,
checks that both write the same bytes, and prints each one's median total and local stages
(`--stats`) and B's time over A's, per pair and of the medians. With `--different-meshes` first,
builds whose meshes are meant to differ (a change of the last bits) are timed alike, and the
script says whether the meshes differed instead of stopping.

    /usr/bin/python3 bench/binaries_pairs.py 5 old/sdfcontour build/sdfcontour \\
        bunny256.npy --edge-fans on --gradient lattice --band 2
"""
import filecmp
import os
import statistics
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import contour_stats  # noqa: E402


def main():
    argv = sys.argv[1:]
    different = bool(argv) and argv[0] == "--different-meshes"
    argv = argv[1:] if different else argv
    if len(argv) < 4:
        sys.exit(__doc__)
    pairs, clis, args = int(argv[0]), argv[1:3], argv[3:]
    same = True
    totals, stages = ([], []), ([], [])
    with tempfile.TemporaryDirectory() as tmp:
        meshes = [os.path.join(tmp, f"{k}.ply") for k in "ab"]
        stats = os.path.join(tmp, "stats.json")
        for _ in range(pairs):
            for k in (0, 1):
                total, stage = contour_stats(clis[k], args, meshes[k], stats)
                totals[k].append(total)
                stages[k].append(stage)
            if not filecmp.cmp(meshes[0], meshes[1], shallow=False):
                if not different:
                    sys.exit("the two builds wrote different meshes")
                same = False
    print(f"{' '.join(args)}: {pairs} pairs, "
          + ("the same mesh bytes from both builds" if same else "different meshes"))
    for k, name in enumerate("AB"):
        print(f"{name} {clis[k]}: median {statistics.median(totals[k]):.3f} s")
    print("B / A per pair: " + ", ".join(f"{b / a:.3f}" for a, b in zip(*totals)))
    print(f"B / A of the medians: "
          f"{statistics.median(totals[1]) / statistics.median(totals[0]):.3f}")
    for name in sorted(stages[0][0]):
        a = statistics.median(s.get(name, 0) for s in stages[0])
        b = statistics.median(s.get(name, 0) for s in stages[1])
        if a > 0.01:
            print(f"  {name}: {a:.3f} -> {b:.3f} s ({b / a:.2f}x)")


if __name__ == "__main__":
    main()

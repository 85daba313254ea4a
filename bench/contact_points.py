"""Contact-point quality per gradient variant on built-in shapes: kept points, |phi(c)| in units of
the grid spacing (median, 95th percentile), normal alignment, and seconds per stage.

Usage: /usr/bin/python3 bench/contact_points.py [--cli build/sdfcontour] [--shapes torus,box]
       [--resolutions 32,64] [--out docs/contact_points.md]
"""
import argparse
import json
import os
import subprocess
import tempfile

VARIANTS = [
    ("regular/uniform", ["--gradient", "regular", "--weights", "uniform"]),
    ("regular/volume", ["--gradient", "regular", "--weights", "volume"]),
    ("regular/james", ["--gradient", "regular", "--weights", "james"]),
    ("delaunay/james", ["--gradient", "delaunay", "--weights", "james"]),
    ("knn6", ["--gradient", "knn", "--knn", "6"]),
    ("knn18", ["--gradient", "knn", "--knn", "18"]),
    ("knn26", ["--gradient", "knn", "--knn", "26"]),
    ("regular/james +FN", ["--gradient", "regular", "--weights", "james", "--fn"]),
]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cli", default="build/sdfcontour")
    ap.add_argument("--shapes", default="torus,box")
    ap.add_argument("--resolutions", default="32,64")
    ap.add_argument("--out", default="")
    args = ap.parse_args()
    rows = ["| shape | N | gradient | kept / samples | hidden | median abs(phi(c)) / h | p95 / h | "
            "median n·∇Φ | seconds: triangulation, gradients, contact points |",
            "|---|---|---|---|---|---|---|---|---|"]
    with tempfile.TemporaryDirectory() as d:
        for shape in args.shapes.split(","):
            for n in args.resolutions.split(","):
                for name, flags in VARIANTS:
                    stats = os.path.join(d, "s.json")
                    cmd = [args.cli, "contour", f"builtin:{shape}@{n}", "--points", os.path.join(d, "cp.ply"),
                           "--stats", stats, "--quiet", *flags]
                    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
                    s = json.load(open(stats))
                    c, e, t = s["contact_points"], s["contact_points"]["error"], s["seconds"]
                    tri = t.get("triangulation", 0) + t.get("delaunay_triangulation", 0)
                    rows.append(f"| {shape} | {n}³ | {name} | {c['kept']} / {s['samples']} | {s['hidden_samples']} | "
                                f"{e['abs_value_median_in_spacing']:.2e} | {e['abs_value_p95_in_spacing']:.2e} | "
                                f"{e['normal_alignment_median']:.6f} | {tri:.2f}, {t['gradients']:.3f}, "
                                f"{t['contact_points']:.3f} |")
                    print(rows[-1], flush=True)
    if args.out:
        with open(args.out, "w") as f:
            f.write("# Contact points per gradient variant\n\nMade by `/usr/bin/python3 bench/contact_points.py "
                    f"--shapes {args.shapes} --resolutions {args.resolutions}` on 2 cores.\n\n")
            f.write("\n".join(rows) + "\n")


if __name__ == "__main__":
    main()

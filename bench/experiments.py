"""The paper's experiments, reproduced with sdfcontour on the meshes in ../shared/data/meshes
(scaled to [-0.9, 0.9]^3, SDFs sampled over [-1, 1]^3). Each experiment writes a CSV and PNG plots
to docs/results/ and a section docs/results/<name>.md; docs/results.md collects the sections.

  gradients   (Fig. 3)  contact-point quality of every gradient variant, 32^3 and 64^3
  screening   (Fig. 5)  GTCP reconstructions for alpha in {0.5, 1, 2, 4, 10}, MC for reference
  resolution  (Figs. 8, 11, 16, 17) MC, MT-RT, GCP and GTCP from 16^3 to 128^3: distances, time
  random      (Figs. 6, 7) scattered samples against grids on the armadillo
  timing      (Fig. 10) seconds per stage against resolution, MC's in the same runs

Usage: /usr/bin/python3 bench/experiments.py EXPERIMENT [...] [--meshes a,b] [--resolutions ...]
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
MESHES = os.path.join(ROOT, "..", "shared", "data", "meshes")
RESULTS = os.path.join(ROOT, "docs", "results")
CLI = os.path.join(ROOT, "build", "sdfcontour")
CACHE = os.path.join(ROOT, "build", "experiments")


def sh(cmd):
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def sample(name, res=None, random=None, seed=0):
    """Cached `sdfcontour sample`; returns the output prefix."""
    tag = f"{name}_{res}" if res else f"{name}_random{random}_{seed}"
    prefix = os.path.join(CACHE, tag)
    if not os.path.exists(prefix + "_mesh.ply"):
        extra = ["--res", str(res)] if res else ["--random", str(random), "--seed", str(seed)]
        sh([CLI, "sample", os.path.join(MESHES, name + ".obj"), "-o", prefix, "-q", *extra])
    return prefix


def has_surface(prefix):
    """False when no sample is inside (a thin part between grid points): nothing to contour."""
    values = np.load(prefix + ".npy")
    values = values[:, 3] if values.ndim == 2 else values
    return bool((values < 0).any() and (values >= 0).any())


def grid_cases(names, resolutions):
    """(name, res, sample prefix, ground-truth mesh) for every mesh and resolution that has a
    surface to contour."""
    for name in names:
        for res in resolutions:
            prefix = sample(name, res)
            if not has_surface(prefix):
                print(name, res, "no sample inside the shape: skipped", flush=True)
                continue
            yield name, res, prefix, prefix + "_mesh.ply"


def log_axis(ax, resolutions):
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xticks(resolutions)
    ax.set_xticklabels([str(r) for r in resolutions])
    ax.minorticks_off()


def evaluate(mesh, gt):
    r = subprocess.run([CLI, "eval", mesh, gt, "--samples", "50000"], capture_output=True, text=True, check=True)
    e = json.loads(r.stdout)
    return {"L1": e["L1"], "L2": e["L2"], "Linf": e["L_inf"], "closed": e["recon_mesh"]["closed"],
            "genus": e["recon_mesh"].get("genus", -1)}


def contour(source, out, method, extra=()):
    """Runs `sdfcontour contour`; returns (wall seconds, stats)."""
    stats = out + ".json"
    start = time.perf_counter()
    sh([CLI, "contour", source, "-o", out, "--method", method, "--stats", stats, "-q", *extra])
    wall = time.perf_counter() - start
    return wall, json.load(open(stats))


def poisson(points, out, extra=()):
    stats = out + ".json"
    start = time.perf_counter()
    sh([CLI, "poisson", points, "-o", out, "--stats", stats, "-q", *extra])
    return time.perf_counter() - start, json.load(open(stats))


def write_csv(name, rows):
    path = os.path.join(RESULTS, name + ".csv")
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    return path


def geomean(values):
    values = [v for v in values if v > 0]
    return math.exp(sum(math.log(v) for v in values) / len(values)) if values else float("nan")


def depth_for(res):
    """Poisson depth for contact points of an res^3 grid: about two cells per grid spacing."""
    return 8 if res <= 64 else 9


def section(name, text):
    # The section's own file sits beside its plots; docs/results.md one folder up.
    with open(os.path.join(RESULTS, name + ".md"), "w") as f:
        f.write(text.replace("](results/", "]("))
    order = ["findings", "gradients", "screening", "resolution", "random", "timing"]
    parts = ["# Results\n\nThe paper's experiments reproduced with sdfcontour on the 17 test meshes of "
             "`../shared/data/meshes` (scaled to [-0.9, 0.9]³, SDFs over [-1, 1]³), on the 2-core machine. "
             "Each section names the command that made it; CSVs and plots are in `docs/results/`.\n"]
    for n in order:
        p = os.path.join(RESULTS, n + ".md")
        if os.path.exists(p):
            parts.append(open(p).read().replace("](", "](results/").replace("](results/http", "](http"))
    with open(os.path.join(ROOT, "docs", "results.md"), "w") as f:
        f.write("\n".join(parts))


def command_line():
    return "/usr/bin/python3 bench/experiments.py " + " ".join(sys.argv[1:])


# --- Experiment 1: gradient variants -------------------------------------------------------------
def exp_gradients(args, names):
    binary = os.path.join(ROOT, "build", "bench", "gradient_variants")
    r = subprocess.run([binary, *[os.path.join(MESHES, n + ".obj") for n in names], "--res", "32,64"],
                       capture_output=True, text=True, check=True)
    rows = list(csv.DictReader(r.stdout.splitlines()))
    write_csv("gradients", rows)
    variants = list(dict.fromkeys(row["variant"] for row in rows))
    table = ["| res | variant | +FN | kept / samples | median abs(phi(c)) / h | mean abs(phi(c)) / h | median n·∇Φ(c) |",
             "|---|---|---|---|---|---|---|"]
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.5))
    for res, marker in (("32", "o"), ("64", "s")):
        for fn in ("0", "1"):
            kept, err, align = [], [], []
            for v in variants:
                sel = [row for row in rows if row["res"] == res and row["variant"] == v and row["fn"] == fn]
                kept.append(np.mean([int(s["kept"]) / int(s["samples"]) for s in sel]))
                err.append(np.mean([float(s["median_abs_phi_h"]) for s in sel]))
                align.append(np.mean([float(s["median_alignment"]) for s in sel]))
                table.append(f"| {res}³ | {v} | {'yes' if fn == '1' else 'no'} | {kept[-1]:.3f} | {err[-1]:.2e} | "
                             f"{np.mean([float(s['mean_abs_phi_h']) for s in sel]):.2e} | {align[-1]:.5f} |")
            label = f"{res}³{' +FN' if fn == '1' else ''}"
            x = np.arange(len(variants))
            axes[0].plot(x, kept, marker=marker, linestyle="-" if fn == "0" else "--", label=label)
            axes[1].plot(x, err, marker=marker, linestyle="-" if fn == "0" else "--", label=label)
            axes[2].plot(x, align, marker=marker, linestyle="-" if fn == "0" else "--", label=label)
    for ax, title in zip(axes, ("contact points kept / samples", "median |Φ(c)| / h (mean over meshes)",
                                "median n·∇Φ(c) (mean over meshes)")):
        ax.set_xticks(range(len(variants)))
        ax.set_xticklabels(variants, rotation=45, ha="right")
        ax.set_title(title)
        ax.legend()
    axes[1].set_yscale("log")
    fig.tight_layout()
    fig.savefig(os.path.join(RESULTS, "gradients.png"), dpi=110)
    section("gradients", f"## 1. Gradient variants (paper Fig. 3)\n\n`{command_line()}`; means over {len(names)} "
            "meshes. reg/del: gradients from the regular / Delaunay triangulation; uniform, volume, james: the "
            "averaging weights; knnK: least squares over K nearest neighbours. The filter is always the exact "
            "power-cell test on the regular triangulation; +FN tries the regular tets' own gradients when the "
            "averaged one's point is discarded.\n\n![gradients](results/gradients.png)\n\n" + "\n".join(table) + "\n")


# --- Experiment 2: screening weight --------------------------------------------------------------
def exp_screening(args, names):
    alphas = [0.5, 1, 2, 4, 10]
    resolutions = [int(r) for r in args.resolutions.split(",")] if args.resolutions else [16, 24, 32, 48, 64]
    rows = []
    for name, res, prefix, gt in grid_cases(names, resolutions):
        wall, _ = contour(prefix + ".npy", prefix + "_out_mc.ply", "mc")
        rows.append({"mesh": name, "res": res, "method": "mc", "alpha": "", **evaluate(prefix + "_out_mc.ply", gt),
                     "seconds": wall})
        for alpha in alphas:
            out = f"{prefix}_out_gtcp_a{alpha}.ply"
            wall, _ = poisson(prefix + "_gtcp.ply", out, ["--alpha", str(alpha), "--depth", str(depth_for(res))])
            rows.append({"mesh": name, "res": res, "method": "gtcp", "alpha": alpha, **evaluate(out, gt), "seconds": wall})
        print(name, res, flush=True)
    write_csv("screening", rows)
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.5))
    table = ["| res | " + " | ".join(["MC"] + [f"GTCP α={a:g}" for a in alphas]) + " |", "|---" * (len(alphas) + 2) + "|"]
    for metric, ax in zip(("L1", "L2", "Linf"), axes):
        for label, sel in [("MC", lambda r: r["method"] == "mc")] + [
                (f"GTCP α={a:g}", (lambda a: lambda r: r["method"] == "gtcp" and r["alpha"] == a)(a)) for a in alphas]:
            ys = [np.mean([r[metric] for r in rows if r["res"] == res and sel(r)]) for res in resolutions]
            ax.plot(resolutions, ys, marker="o", label=label)
        log_axis(ax, resolutions)
        ax.set_xlabel("grid resolution N (N³ samples)")
        ax.set_title(f"{metric} distance to ground truth (mean over meshes)")
        ax.legend()
    for res in resolutions:
        cells = [np.mean([r["L1"] for r in rows if r["res"] == res and r["method"] == "mc"])]
        cells += [np.mean([r["L1"] for r in rows if r["res"] == res and r["method"] == "gtcp" and r["alpha"] == a])
                  for a in alphas]
        table.append(f"| {res}³ | " + " | ".join(f"{c:.2e}" for c in cells) + " |")
    fig.tight_layout()
    fig.savefig(os.path.join(RESULTS, "screening.png"), dpi=110)
    section("screening", f"## 2. Screening weight (paper Fig. 5)\n\n`{command_line()}`; screened Poisson of the "
            f"ground-truth contact points for each α (depth 8, 9 above 64³), marching cubes for reference. "
            f"Mean L1 over {len(names)} meshes:\n\n" + "\n".join(table) + "\n\n![screening](results/screening.png)\n")


# --- Experiment 3 (and 5): resolution sweep with per-stage timing --------------------------------
METHODS = ["mc", "mt-rt", "gcp", "gtcp"]


def load_rows(path):
    """A results CSV back as typed rows."""
    rows = []
    for row in csv.DictReader(open(path)):
        typed = {}
        for key, value in row.items():
            if value in ("True", "False"):
                typed[key] = value == "True"
            else:
                try:
                    typed[key] = int(value)
                except ValueError:
                    try:
                        typed[key] = float(value)
                    except ValueError:
                        typed[key] = value
        rows.append(typed)
    return rows


def exp_resolution(args, names):
    resolutions = [int(r) for r in args.resolutions.split(",")] if args.resolutions else [16, 24, 32, 48, 64, 96, 128]
    # With --update, rows of the meshes not re-run now are kept from the last run.
    path = os.path.join(RESULTS, "resolution.csv")
    kept = [r for r in load_rows(path) if r["mesh"] not in names] if args.update and os.path.exists(path) else []
    rows = []
    for name, res, prefix, gt in grid_cases(names, resolutions):
        for method in METHODS:
            out = f"{prefix}_out_{method}.ply"
            depth = ["--depth", str(depth_for(res))]
            if method == "gtcp":
                wall, stats = poisson(prefix + "_gtcp.ply", out, depth)
                stages = {"poisson_" + k: v for k, v in stats["seconds"].items()}
            else:
                wall, stats = contour(prefix + ".npy", out, method, depth if method == "gcp" else ())
                stages = dict(stats["seconds"])
                stages.update({"poisson_" + k: v for k, v in stats.get("poisson_seconds", {}).items()})
            row = {"mesh": name, "res": res, "method": method, **evaluate(out, gt), "seconds": wall}
            for key in ("triangulation", "gradients", "contact_points", "marching", "poisson", "poisson_octree",
                        "poisson_solve", "poisson_extraction", "poisson_density"):
                row["s_" + key] = stages.get(key, 0.0)
            rows.append(row)
        print(name, res, " ".join(f"{r['method']} {r['L1']:.2e}" for r in rows[-4:]), flush=True)
        write_csv("resolution", sorted(kept + rows, key=lambda r: (r["mesh"], r["res"])))  # partial runs leave data
    rows = sorted(kept + rows, key=lambda r: (r["mesh"], r["res"]))
    plot_resolution(rows, resolutions, sorted({r["mesh"] for r in rows}))


def plot_resolution(rows, resolutions, names):
    fig, axes = plt.subplots(1, 4, figsize=(20, 4.5))
    summary = ["| res | " + " | ".join(f"{m} L1" for m in METHODS) + " | GCP/MC L1 | GCP/GTCP L1 | " +
               " | ".join(f"{m} s" for m in METHODS) + " |", "|---" * (2 * len(METHODS) + 3) + "|"]
    for metric, ax in zip(("L1", "L2", "Linf", "seconds"), axes):
        for method in METHODS:
            mean, low, high = [], [], []
            for res in resolutions:
                v = np.array([r[metric] for r in rows if r["res"] == res and r["method"] == method])
                mean.append(v.mean() if len(v) else np.nan)
                low.append(max(v.mean() - v.std(), 1e-12) if len(v) else np.nan)
                high.append(v.mean() + v.std() if len(v) else np.nan)
            ax.plot(resolutions, mean, marker="o", label=method)
            ax.fill_between(resolutions, low, high, alpha=0.15)
        log_axis(ax, resolutions)
        ax.set_xlabel("grid resolution N (N³ samples)")
        ax.set_title(("wall time (s)" if metric == "seconds" else f"{metric} distance") + ", mean ± std over meshes")
        ax.legend()
    for res in resolutions:
        by = {m: [r for r in rows if r["res"] == res and r["method"] == m] for m in METHODS}
        if not all(by.values()):
            continue
        l1 = {m: np.mean([r["L1"] for r in by[m]]) for m in METHODS}
        sec = {m: np.mean([r["seconds"] for r in by[m]]) for m in METHODS}
        gcp_mc = geomean([g["L1"] / m["L1"] for g, m in zip(by["gcp"], by["mc"])])
        gcp_gt = geomean([g["L1"] / t["L1"] for g, t in zip(by["gcp"], by["gtcp"])])
        summary.append(f"| {res}³ | " + " | ".join(f"{l1[m]:.2e}" for m in METHODS) + f" | {gcp_mc:.3f} | {gcp_gt:.3f} | "
                       + " | ".join(f"{sec[m]:.2f}" for m in METHODS) + " |")
    fig.tight_layout()
    fig.savefig(os.path.join(RESULTS, "resolution.png"), dpi=110)
    open_count = sum(1 for r in rows if not r["closed"])
    section("resolution", f"## 3. Resolution sweep (paper Figs. 8, 11, 16, 17)\n\n`{command_line()}`; {len(names)} "
            "meshes. L1 columns are means over meshes; GCP/MC and GCP/GTCP are geometric means of per-mesh L1 "
            "ratios (below 1: GCP closer to the truth); seconds are whole `sdfcontour` runs (GTCP: `poisson` on the "
            "exact contact points). GCP and GTCP use James weights and screened Poisson at the defaults, depth 8 "
            f"(9 above 64³). Meshes that came out open: {open_count} of {len(rows)}.\n\n" + "\n".join(summary) +
            "\n\n![resolution](results/resolution.png)\n")


# --- Experiment 4: random samples -----------------------------------------------------------------
def exp_random(args, names):
    name = "armadillo"
    rows = []
    for res in (32, 64):
        count = res ** 3
        grid = sample(name, res)
        gt = grid + "_mesh.ply"
        scattered = sample(name, random=count, seed=1)
        for kind, prefix in (("grid", grid), ("random", scattered)):
            for method in (["mc"] if kind == "grid" else []) + ["mt-dt", "mt-rt", "gcp", "gtcp"]:
                out = f"{prefix}_out_{method}.ply"
                if method == "gtcp":
                    wall, _ = poisson(prefix + "_gtcp.ply", out)
                else:
                    wall, _ = contour(prefix + ".npy", out, method)
                rows.append({"samples": count, "layout": kind, "method": method, **evaluate(out, gt), "seconds": wall})
                print(rows[-1], flush=True)
    write_csv("random", rows)
    table = ["| samples | layout | method | L1 | L2 | L∞ | closed | genus | seconds |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        table.append(f"| {r['samples']} | {r['layout']} | {r['method']} | {r['L1']:.2e} | {r['L2']:.2e} | {r['Linf']:.2e} | "
                     f"{'yes' if r['closed'] else 'no'} | {r['genus']} | {r['seconds']:.2f} |")
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for (kind, res), marker in zip([("grid", 32), ("grid", 64), ("random", 32), ("random", 64)], "osov"):
        sel = [r for r in rows if r["layout"] == kind and r["samples"] == res ** 3]
        ax.plot([r["method"] for r in sel], [r["L1"] for r in sel], marker=marker, label=f"{kind}, {res ** 3} samples")
    ax.set_yscale("log")
    ax.set_title("armadillo: L1 distance to the ground truth")
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(RESULTS, "random.png"), dpi=110)
    section("random", f"## 4. Random samples against grids (paper Figs. 6, 7)\n\n`{command_line()}`; the armadillo, "
            "SDF sampled at as many uniform random points as a 32³ and a 64³ grid (seed 1), and on the grids.\n\n" +
            "\n".join(table) + "\n\n![random](results/random.png)\n")


# --- Experiment 5: timing per stage (from the resolution sweep's CSV) -----------------------------
def exp_timing(args, names):
    rows = list(csv.DictReader(open(os.path.join(RESULTS, "resolution.csv"))))
    mesh = "koala_lowres"
    resolutions = sorted({int(r["res"]) for r in rows})
    stages = [("triangulation", "s_triangulation"), ("gradients", "s_gradients"), ("filter", "s_contact_points"),
              ("poisson solve", "s_poisson_solve"), ("poisson octree", "s_poisson_octree"),
              ("extraction", "s_poisson_extraction")]
    table = ["| res | " + " | ".join(s for s, _ in stages) + " | GCP total | MC total | GCP / MC |", "|---" * (len(stages) + 4) + "|"]
    fig, ax = plt.subplots(figsize=(8, 5))
    for label, key in stages:
        ys = [float(next(r[key] for r in rows if r["mesh"] == mesh and int(r["res"]) == res and r["method"] == "gcp"))
              for res in resolutions]
        ax.plot(resolutions, ys, marker="o", label=label)
    gcp = [float(next(r["seconds"] for r in rows if r["mesh"] == mesh and int(r["res"]) == res and r["method"] == "gcp"))
           for res in resolutions]
    mc = [float(next(r["seconds"] for r in rows if r["mesh"] == mesh and int(r["res"]) == res and r["method"] == "mc"))
          for res in resolutions]
    ax.plot(resolutions, gcp, "k-", linewidth=2, label="GCP total")
    ax.plot(resolutions, mc, "k--", linewidth=2, label="MC total")
    log_axis(ax, resolutions)
    for i, res in enumerate(resolutions):
        r = next(r for r in rows if r["mesh"] == mesh and int(r["res"]) == res and r["method"] == "gcp")
        table.append(f"| {res}³ | " + " | ".join(f"{float(r[k]):.3f}" for _, k in stages) +
                     f" | {gcp[i]:.2f} | {mc[i]:.3f} | {gcp[i] / mc[i]:.0f} |")
    ax.set_xlabel("grid resolution N")
    ax.set_ylabel("seconds")
    ax.set_title(f"{mesh}: GCP seconds per stage, and MC")
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(RESULTS, "timing.png"), dpi=110)
    section("timing", f"## 5. Time per stage (paper Fig. 10)\n\n`{command_line()}` (read from the resolution "
            f"sweep's runs); {mesh}, GCP's stages from `--stats`, totals are whole runs including I/O.\n\n" +
            "\n".join(table) + "\n\n![timing](results/timing.png)\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("experiments", nargs="+", choices=["gradients", "screening", "resolution", "random", "timing"])
    ap.add_argument("--meshes", default="")
    ap.add_argument("--resolutions", default="")
    ap.add_argument("--update", action="store_true", help="resolution: keep the other meshes' rows of the last run")
    args = ap.parse_args()
    os.makedirs(RESULTS, exist_ok=True)
    os.makedirs(CACHE, exist_ok=True)
    names = args.meshes.split(",") if args.meshes else sorted(f[:-4] for f in os.listdir(MESHES) if f.endswith(".obj"))
    for e in args.experiments:
        globals()["exp_" + e](args, names)


if __name__ == "__main__":
    main()

"""Helpers the benchmarks share: timing a command's wall time and peak RSS, L1 from
`sdfcontour eval`, geometric means, where the shared meshes are."""
import json
import math
import os
import re
import subprocess
import time

HERE = os.path.dirname(os.path.abspath(__file__))
MESHES = os.path.join(HERE, "..", "..", "shared", "data", "meshes")
CLI = os.environ.get("SDFCONTOUR_CLI", os.path.join(HERE, "..", "build", "sdfcontour"))


def timed(cmd):
    """Runs cmd under /usr/bin/time: (wall seconds, peak RSS in MB, stdout, None) or, if it failed,
    (None, None, stdout, the last lines of stderr)."""
    start = time.perf_counter()  # (/usr/bin/time's %e counts in 10 ms: a small grid's MC is 0)
    r = subprocess.run(["/usr/bin/time", "-f", "TIME %e %M", *cmd], capture_output=True, text=True)
    wall = time.perf_counter() - start
    m = re.search(r"TIME ([\d.]+) (\d+)", r.stderr)
    if r.returncode != 0 or not m:
        # The program's own last lines, not those /usr/bin/time appends (its exit status, TIME).
        own = [line for line in r.stderr.strip().splitlines()
               if not line.startswith(("TIME ", "Command exited with non-zero status", "Command terminated by signal"))]
        return None, None, r.stdout, own[-2:] or [f"exit status {r.returncode}"]
    return wall, int(m.group(2)) / 1024, r.stdout, None


def contour_stats(cli, args, mesh, stats):
    """Runs `cli contour ARGS -o MESH --quiet --stats STATS` (quiet, failing on error): its total
    seconds and its local stages' seconds (`--stats`)."""
    subprocess.run([cli, "contour", *args, "-o", mesh, "--quiet", "--stats", stats], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(stats) as f:
        d = json.load(f)
    return d["seconds_total"], d.get("local_seconds", {})


def evaluate(cli, mesh, gt, *options):
    """`cli eval MESH GT [OPTIONS]`'s JSON (distances, and the reconstruction's topology under
    "recon_mesh"), or None if eval failed."""
    r = subprocess.run([cli, "eval", mesh, gt, *options], capture_output=True, text=True)
    return json.loads(r.stdout) if r.returncode == 0 else None


def l1(cli, mesh, gt):
    """The paper's L1 distance between two meshes, or None if eval failed."""
    e = evaluate(cli, mesh, gt)
    return e["L1"] if e else None


def keep(rows, row):
    """Adds a result row and prints it as a JSON line."""
    rows.append(row)
    print(json.dumps(row), flush=True)


def read_jsonl(path):
    """The JSON objects of a benchmark's lines (other lines skipped)."""
    with open(path) as f:
        return [json.loads(line) for line in f if line.strip().startswith("{")]


def geomean(values):
    v = [x for x in values if x]
    return math.exp(sum(math.log(x) for x in v) / len(v)) if v else float("nan")


def over_peer(rows, res, method, key, peer):
    """The geometric mean over the meshes of `method`'s row[key] over `peer`'s (bench/scale.py's
    rows at res^3), leaving out the meshes where either is missing or zero; nan if none is left."""
    theirs = {r["mesh"]: r.get(key) for r in rows if r["res"] == res and r["method"] == peer}
    return geomean([r[key] / theirs[r["mesh"]] for r in rows
                    if r["res"] == res and r["method"] == method and r.get(key) and theirs.get(r["mesh"])])


def report(text, out):
    """Prints a benchmark's markdown and writes it to `out` (if given)."""
    print(text)
    if out:
        with open(out, "w") as f:
            f.write(text)


def mesh_names(given):
    """The shared meshes a benchmark runs: `given` (comma-separated names) or every one."""
    if given:
        return given.split(",")
    return sorted(f[:-4] for f in os.listdir(MESHES) if f.endswith(".obj"))


def scale_grid(cli, work, name, res):
    """The prefix of bench/scale.py's grid of the shared mesh `name` at res^3 in `work` (float32;
    exact at <= 128^3, truncated at 8 spacings above), sampled if it is not there yet."""
    prefix = os.path.join(work, f"{name}_{res}")
    if not os.path.exists(prefix + ".npy"):
        extra = ["--truncate", "8"] if res > 128 else []
        subprocess.run([cli, "sample", os.path.join(MESHES, name + ".obj"), "--res", str(res), "-o",
                        prefix, "--float32", "-q", *extra], check=True, stdout=subprocess.DEVNULL)
    return prefix


def sample_shared_mesh(name, res, folder, truncate=None):
    """Samples the shared mesh `name` on a res^3 grid into `folder` (`sdfcontour sample`; with
    `truncate`, the distances truncated at that many spacings): the prefix of its `.npy` grid and
    `_mesh.ply` ground truth."""
    prefix = os.path.join(folder, name)
    extra = ["--truncate", str(truncate)] if truncate else []
    subprocess.run([CLI, "sample", os.path.join(MESHES, name + ".obj"), "--res", str(res), "-o",
                    prefix, "-q", *extra], check=True, stdout=subprocess.DEVNULL)
    return prefix

"""Every option of `sdfcontour contour` (as `--help-all` lists them) does what it says: given a
value other than its default, it changes the output on the path it names, or it is warned about
(`sdfcontour: warning:`) or refused (`sdfcontour: error:`) where it does not apply; an option
whose promise is the same output (threads, bricks, serial insertion) keeps it byte for byte.
A new option that this table does not know fails the test.

    /usr/bin/python3 tests/test_cli_options.py build/sdfcontour
"""
import os
import re
import shutil
import tempfile

import numpy as np
from cli_checks import check, finish, run

GRID = "builtin:torus@20"           # the local reconstruction, the default on grids
BOX = "builtin:box@24"
# Two spheres' union on a 20^3 grid (written below): samples the Poisson surface leaves on the
# wrong side, which the sign constraints correct.
CSG = os.path.join(tempfile.mkdtemp(prefix="sdfcontour-options-"), "csg.npy")
POISSON = [CSG, "--reconstruction", "poisson"]
SCATTERED = "builtin:torus@random:3000"
ADAPT = [GRID, "--adaptivity", "0.1"]
ZERO_SET = [GRID, "--zero-set", "on"]
KNN = [GRID, "--gradient", "knn", "--reconstruction", "poisson"]

# option: (the run it is given to, its value or None for a flag, what it does there)
OPTIONS = {
    "--method": ([GRID], "mt-rt", "changes"),
    "--bounds": ([GRID], "-1.1,1.1", "changes"),
    "--band": ([GRID], "3", "changes"),
    "--reconstruction": ([GRID], "poisson", "changes"),
    "--adaptivity": ([GRID], "0.1", "changes"),
    "--grid": ([GRID], "surface", "refused"),
    "--truncation": ([GRID], "0.12", "changes"),
    "--seed": ([SCATTERED], "5", "changes"),
    "--ascii": ([GRID], None, "changes"),
    "--threads": ([GRID], "1", "same"),
    "--gradient": ([GRID], "lattice", "changes"),
    "--weights": ([GRID], "uniform", "changes"),
    "--knn": (KNN, "6", "changes"),
    "--james-epsilon": ([GRID], "1", "changes"),
    "--tie-tolerance": ([BOX], "0", "changes"),
    "--sign-constraints": ([GRID], None, "warns"),
    "--no-sign-constraints": ([GRID], None, "warns"),
    "--no-carve": ([GRID], None, "changes"),
    "--no-side-repair": ([GRID], None, "warns"),
    "--side-passes": ([GRID], "3", "refused"),
    "--adaptivity-bricks": (ADAPT, "16", "changes"),
    "--adaptivity-fit": (ADAPT, "0", "changes"),
    "--subdivisions": ([GRID], "0", "changes"),
    "--split-sag": ([GRID], "0.001", "changes"),
    "--thin-parts": ([GRID], "off", "changes"),
    "--edge-fans": ([GRID], "on", "changes"),
    "--local-reach": ([GRID], "0.4", "changes"),
    "--local-feature-ratio": ([GRID], "0.3", "changes"),
    "--local-robust-rounds": ([GRID], "0", "changes"),
    "--local-min-points": ([GRID], "6", "changes"),
    "--local-max-field-miss": ([GRID], "0.01", "changes"),
    "--local-depth-scale": ([GRID], "0.5", "changes"),
    "--zero-set": ([GRID], "on", "changes"),
    "--zero-set-mismatch": (ZERO_SET, "0.01", "changes"),
    "--projection": ([GRID], "off", "changes"),
    "--margin": ([GRID], "0", "changes"),
    "--brick-size": (POISSON, "8", "same"),
    "--brick-halo": (POISSON, "6", "same"),
    "--serial-triangulation": ([GRID], None, "same"),
}
# The Poisson path's options: they change its mesh, and draw a warning on the local path.
POISSON_ONLY = {
    "--projection-radius": "3", "--projection-max-move": "0.001", "--projection-agreement": "0.2",
    "--projection-depth-scale": "0.5", "--projection-variance": "1.5",
    "--projection-residual": "0.0001", "--sign-band": "0", "--sign-radius": "3",
    "--sign-margin": "0.2", "--sign-trigger": "0.2", "--alpha": "1", "--depth": "6",
    "--degree": "2", "--full-depth": "3", "--refine-dilation": "1", "--samples-per-node": "4",
    "--scale": "1.5", "--boundary": "dirichlet", "--solver-tolerance": "0.1",
    "--finest-solver-tolerance": "0.3", "--fn": None,
}
# Options that name what to write or how to run, checked by the other CLI tests.
NOT_WALKED = {"-h", "--help", "--help-all", "-o", "--output", "--points", "--stats", "-q",
              "--quiet", "-m"}


def listed_options():
    r = run("contour", "--help-all")
    names = set()
    for line in r.stdout.splitlines():
        m = re.match(r"\s+((?:-\w,)?--[\w-]+)", line)
        if m:
            names.update(m.group(1).split(","))
    return names


def contour(d, name, base, extra):
    out = os.path.join(d, name + ".ply")
    r = run("contour", *base, *extra, "-o", out, "-q")
    data = open(out, "rb").read() if r.returncode == 0 and os.path.exists(out) else None
    return r, data


def main():
    x = np.linspace(-1, 1, 20)
    X, Y, Z = np.meshgrid(x, x, x, indexing="ij")
    np.save(CSG, np.minimum(np.sqrt((X - 0.2)**2 + Y**2 + Z**2) - 0.45,
                            np.sqrt((X + 0.3)**2 + Y**2 + Z**2) - 0.35))
    listed = listed_options()
    known = set(OPTIONS) | set(POISSON_ONLY) | NOT_WALKED
    check("every listed option is in the table", not listed - known, sorted(listed - known))
    check("every option in the table is listed", not known - listed,
          sorted(known - listed))
    defaults = {}
    with tempfile.TemporaryDirectory() as d:
        def default(base):
            key = tuple(base)
            if key not in defaults:
                r, data = contour(d, f"default{len(defaults)}", base, [])
                check(f"default run {base}", data is not None, r.stderr)
                defaults[key] = data
            return defaults[key]

        cases = [(o, *v) for o, v in OPTIONS.items()]
        for o, value in POISSON_ONLY.items():
            cases.append((o, POISSON, value, "changes"))
            cases.append((o, [GRID], value, "warns"))
        for i, (option, base, value, does) in enumerate(cases):
            given = [option] if value is None else [option, value]
            r, data = contour(d, f"run{i}", base, given)
            said = [line for line in r.stderr.splitlines() if line.startswith("sdfcontour: ")]
            what = f"{option} {value or ''} on {' '.join(base)}"
            if does == "changes":
                check(f"{what} changes the mesh", data is not None and data != default(base),
                      r.stderr[-300:])
            elif does == "same":
                check(f"{what} keeps the mesh", data is not None and data == default(base),
                      r.stderr[-300:])
            elif does == "warns":
                check(f"{what} is warned about", data is not None and any(
                    "warning" in line and option in line for line in said), said)
            else:
                check(f"{what} is refused", r.returncode == 1 and data is None and said and
                      said[-1].startswith("sdfcontour: error:"), said)
    shutil.rmtree(os.path.dirname(CSG))
    finish()


main()

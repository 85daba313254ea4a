"""Reliability round 4 (issue 65), through the command line: values that used to reach an
internal assertion are refused where they enter, numbers are read one way, what goes to standard
output arrives or the run fails, and an output name of the file system's longest is written.
And the command line by levels (issue 66): --help on one screen, --help-all with the rest.

Usage: test_cli_round4.py PATH_TO_SDFCONTOUR
"""
import os
import subprocess
import tempfile

from cli_checks import CLI, check, expect_error, finish, run

with tempfile.TemporaryDirectory() as d:
    p = lambda name: os.path.join(d, name)
    r = run("contour", "builtin:box@12", "-o", p("box.obj"), "--method", "mc", "-q")
    check("a mesh to sample", r.returncode == 0, r.stderr)

    # A count that would wrap to a huge size (Eigen's assertion before) is refused up front.
    for count in ("-1", "0x7fffffffffff", "1e12"):
        expect_error(f"--random {count}", ["sample", p("box.obj"), "--random", count, "-o", p("r")],
                     "--random", [p("r.npy")])
    r = run("sample", p("box.obj"), "--random", "50", "--seed", "3", "-o", p("r"), "-q")
    check("--random 50 samples", r.returncode == 0 and os.path.exists(p("r.npy")), r.stderr)

    # Numbers as the CLI and Python both read them: "0_1" is no number (Python's float() says 1).
    for text in ("0_1", " 0.1", "0.1 ", "nan", "inf", ""):
        expect_error(f"--truncation {text!r}", ["contour", "builtin:sphere@12", "-o", p("t.ply"),
                                                "--truncation", text], "truncation", [p("t.ply")])
    # A subnormal truncation is a number: every value lies beyond it, which is said in one line.
    r = run("contour", "builtin:sphere@12", "-o", p("sub.ply"), "--truncation", "1e-310", "-q")
    check("subnormal truncation: an error line or a mesh, never a crash",
          (r.returncode == 1 and r.stderr.strip().splitlines()[-1].startswith("sdfcontour: error:")
           and not os.path.exists(p("sub.ply"))) or (r.returncode == 0 and os.path.exists(p("sub.ply"))),
          (r.returncode, r.stderr))

    # Output to a full device is an error, not a lost result with exit 0.
    if os.path.exists("/dev/full"):
        with open("/dev/full", "w") as full:
            r = subprocess.run([CLI, "eval", p("box.obj"), p("box.obj")], stdout=full,
                               stderr=subprocess.PIPE, text=True)
        check("eval > /dev/full fails", r.returncode == 1 and
              r.stderr.strip().splitlines()[-1].startswith("sdfcontour: error:"), (r.returncode, r.stderr))
    else:
        print("SKIP /dev/full: not on this system")

    # The longest name a file may have (255 bytes) is written: the temporary name is its own.
    longest = p("m" * 251 + ".ply")
    r = run("contour", "builtin:sphere@12", "-o", longest, "--method", "mc", "-q")
    check("255-byte output name written", r.returncode == 0 and os.path.exists(longest), r.stderr)
    check("no temporary file left", not [f for f in os.listdir(d) if ".tmp-" in f], os.listdir(d))

    # Degenerate inputs give an error, not an empty or speck mesh with exit 0.
    header = ("ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
              "property float z\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n")
    with open(p("coincident.ply"), "w") as f:
        f.write(header % 6 + "0.5 0.5 0.5 1 0 0\n" * 6)
    expect_error("poisson from coincident points", ["poisson", p("coincident.ply"), "-o", p("co.ply")],
                 "one place", [p("co.ply")])
    with open(p("one.ply"), "w") as f:
        f.write(header % 1 + "0.5 0.5 0.5 1 0 0\n")
    expect_error("poisson from one point", ["poisson", p("one.ply"), "-o", p("one_mesh.ply")],
                 "no surface", [p("one_mesh.ply")])
    with open(p("none.ply"), "w") as f:
        f.write(header % 0)
    expect_error("eval-points with no points", ["eval-points", p("none.ply"), p("box.obj")], "no points")

    # An input .npy cut short while it is read (mapped): one error line and exit 1, or a mesh if
    # the read was done first; never SIGBUS.
    import numpy as np
    import time
    np.save(p("big.npy"), np.random.default_rng(1).uniform(-1, 1, (200, 200, 200)))
    header = 128
    proc = subprocess.Popen([CLI, "contour", p("big.npy"), "-o", p("big.ply"), "--method", "mc", "-q"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(0.2)
    os.truncate(p("big.npy"), header + 8 * 1000)
    out, err = proc.communicate(timeout=300)
    lines = err.strip().splitlines()
    check("input cut short: exit 1 with one error line, or a mesh",
          (proc.returncode == 1 and lines and lines[-1].startswith("sdfcontour: error:") and
           not os.path.exists(p("big.ply"))) or (proc.returncode == 0 and os.path.exists(p("big.ply"))),
          (proc.returncode, err))
    check("no temporary file left after a cut input", not [f for f in os.listdir(d) if ".tmp-" in f],
          os.listdir(d))

    # The command line by levels: --help lists what a user decides, on one screen; --help-all the
    # tuning knobs too, which are accepted either way.
    r = run("contour", "--help")
    check("contour --help fits a screen", r.returncode == 0 and len(r.stdout.splitlines()) <= 40 and
          "--projection-radius" not in r.stdout and "--help-all" in r.stdout, r.stdout)
    r = run("contour", "--help-all")
    check("contour --help-all lists the tuning options", r.returncode == 0 and
          "--projection-radius" in r.stdout and "--local-reach" in r.stdout and "--depth" in r.stdout, r.stdout)
    r = run("contour", "builtin:sphere@12", "-o", p("k.ply"), "--gradient", "knn", "--knn", "6",
            "--reconstruction", "poisson", "-q")
    check("a tuning option is still accepted", r.returncode == 0 and os.path.exists(p("k.ply")), r.stderr)

finish()

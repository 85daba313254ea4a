"""Command-line behaviour of `sdfcontour`: every bad input gets one clear error line and a
non-zero exit with no output file left behind; good input gives the same bytes whatever the
thread count.

Usage: test_cli.py PATH_TO_SDFCONTOUR
"""
import json
import os
import subprocess
import tempfile

import numpy as np

from cli_checks import CLI, check, expect_error, finish, run


with tempfile.TemporaryDirectory() as d:
    p = lambda name: os.path.join(d, name)
    out = p("out.ply")
    x = np.linspace(-1, 1, 8)
    X, Y, Z = np.meshgrid(x, x, x, indexing="ij")
    sphere = np.sqrt(X**2 + Y**2 + Z**2) - 0.5
    np.save(p("good.npy"), sphere)

    # Unreadable, truncated and corrupt files.
    expect_error("missing file", ["contour", p("nope.npy"), "-o", out, "--method", "mc"], "cannot read", [out])
    os.mkdir(p("adir.npy"))
    expect_error("directory", ["contour", p("adir.npy"), "-o", out, "--method", "mc"], "cannot read", [out])
    raw = open(p("good.npy"), "rb").read()
    open(p("truncated.npy"), "wb").write(raw[: len(raw) // 2])
    expect_error("truncated npy", ["contour", p("truncated.npy"), "-o", out, "--method", "mc"], "truncated", [out])
    open(p("corrupt.npy"), "wb").write(b"\x00" * 200)
    expect_error("corrupt npy", ["contour", p("corrupt.npy"), "-o", out, "--method", "mc"], "not a .npy", [out])
    # Wrong shape or dtype.
    np.save(p("shape.npy"), np.zeros((10, 3)))
    expect_error("wrong shape", ["contour", p("shape.npy"), "-o", out, "--method", "mt-dt"], "neither a grid", [out])
    np.save(p("int.npy"), np.zeros((4, 4, 4), dtype=np.int64))
    expect_error("wrong dtype", ["contour", p("int.npy"), "-o", out, "--method", "mc"], "dtype", [out])
    np.save(p("fortran.npy"), np.asfortranarray(sphere))
    expect_error("fortran order", ["contour", p("fortran.npy"), "-o", out, "--method", "mc"], "Fortran", [out])
    # NaN and infinite values.
    bad = sphere.copy()
    bad[3, 3, 3] = np.nan
    np.save(p("nan.npy"), bad)
    expect_error("nan", ["contour", p("nan.npy"), "-o", out, "--method", "mc"], "NaN", [out])
    bad[3, 3, 3] = np.inf
    np.save(p("inf.npy"), bad.astype(np.float32))
    expect_error("inf", ["contour", p("inf.npy"), "-o", out, "--method", "mc"], "infinite", [out])
    # Too few samples, coplanar samples, no surface.
    np.save(p("three.npy"), np.array([[0, 0, 0, -1], [1, 0, 0, 1], [0, 1, 0, 1.0]]))
    expect_error("three samples", ["contour", p("three.npy"), "-o", out, "--method", "mt-dt"], "at least 4", [out])
    flat = np.random.default_rng(1).uniform(-1, 1, (50, 4))
    flat[:, 2] = 0.25
    np.save(p("flat.npy"), flat)
    expect_error("coplanar", ["contour", p("flat.npy"), "-o", out, "--method", "mt-rt"], "coplanar", [out])
    np.save(p("positive.npy"), np.abs(sphere) + 0.1)
    expect_error("no sign change", ["contour", p("positive.npy"), "-o", out, "--method", "mc"], "no surface", [out])
    np.save(p("empty.npy"), np.zeros((0, 0, 0)))
    expect_error("empty grid", ["contour", p("empty.npy"), "-o", out, "--method", "mc"], "at least 2", [out])
    # Bad options.
    expect_error("bounds min >= max", ["contour", p("good.npy"), "-o", out, "--method", "mc", "--bounds", "1,-1"],
                 "min must be less than max", [out])
    expect_error("unknown method", ["contour", p("good.npy"), "-o", out, "--method", "marching"], "unknown method", [out])
    expect_error("unknown builtin", ["contour", "builtin:teapot@32", "-o", out, "--method", "mc"], "teapot", [out])
    expect_error("mc on scattered", ["contour", "builtin:sphere@random:500", "-o", out, "--method", "mc"], "grid", [out])
    expect_error("unwritable output", ["contour", p("good.npy"), "-o", p("no/such/dir/out.ply"), "--method", "mc"],
                 "cannot write")

    # Outputs appear together or not at all: a bad second output path fails before any work, and
    # A terminating signal at any moment leaves neither outputs nor temporary files.
    expect_error("bad points path", ["contour", p("good.npy"), "-o", out, "--points", p("no/dir/cp.ply")],
                 "cannot write", [out])
    expect_error("stats is a folder", ["contour", p("good.npy"), "-o", out, "--stats", d], "directory", [out])
    import signal
    import time as _time
    sig_dir = p("signals")
    os.mkdir(sig_dir)
    # Every terminating signal alike: a closed terminal (SIGHUP), a closed pipe (SIGPIPE).
    for delay, sig in [(0.3, signal.SIGINT), (0.8, signal.SIGTERM), (1.5, signal.SIGINT), (0.8, signal.SIGHUP),
                       (1.2, signal.SIGPIPE), (0.6, signal.SIGALRM)]:
        proc = subprocess.Popen([CLI, "contour", "builtin:torus@72", "-o", os.path.join(sig_dir, "m.ply"), "--points",
                                 os.path.join(sig_dir, "cp.ply"), "--depth", "7", "-q"],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        _time.sleep(delay)
        proc.send_signal(sig)
        code = proc.wait(timeout=120)
        left = os.listdir(sig_dir)
        check(f"signal {sig} after {delay}s leaves nothing partial",
              (code != 0 and not left) or (code == 0 and sorted(left) == ["cp.ply", "m.ply"]), (code, left))
        for f in left:
            os.remove(os.path.join(sig_dir, f))

    # Options out of range end in an error, never a garbage mesh with exit 0.
    for opt, value in [("--solver-tolerance", "nan"), ("--alpha", "1e300"), ("--alpha", "-1"), ("--scale", "1e300"),
                       ("--full-depth", "30"), ("--depth", "0"), ("--threads", "-1"), ("--samples-per-node", "0"),
                       ("--tie-tolerance", "inf"), ("--knn", "1"), ("--bounds=-1e308,1e308", None),
                       ("--projection", "maybe"), ("--projection-radius", "0"), ("--projection-residual", "nan"),
                       ("--projection-variance", "0.5"), ("--refine-dilation", "0"),
                       ("--refine-dilation", "5"), ("--refine-dilation", "1.5"), ("--zero-set", "maybe"),
                       ("--thin-parts", "maybe"),
                       ("--zero-set-mismatch", "nan"), ("--zero-set-mismatch", "-1")]:
        depth = [] if opt in ("--depth", "--full-depth") else ["--depth", "5"]
        args = ["contour", "builtin:sphere@12", "-o", out, *depth] + ([opt, value] if value else [opt])
        expect_error(f"{opt} {value}", args, opt.split("=")[0], [out])
    # Values that are no exact distances (a torus distance times a factor in [0.8, 1.2]): found,
    # said in the stats, and contoured onto their zero set, closer to the torus than MC (at 48^3;
    # at 40^3 too few crossings are smooth to judge, and GCP falls back to MC).
    x = np.linspace(-1, 1, 48)
    X, Y, Z = np.meshgrid(x, x, x, indexing="ij")
    torus = np.sqrt((np.sqrt(X ** 2 + Y ** 2) - 0.5) ** 2 + Z ** 2) - 0.2
    np.save(p("slope.npy"), torus * (1 + 0.2 * np.sin(2 * X + 1) * np.cos(3 * Y)))
    r = run("contour", p("slope.npy"), "-o", p("slope.ply"), "--stats", p("slope.json"), "-q")
    s = json.load(open(p("slope.json"))) if r.returncode == 0 else {}
    check("no exact distances found", s.get("approximate_distances") is True and s["reconstruction"] == "local",
          r.stderr + str(s))
    r2 = run("contour", p("slope.npy"), "-o", p("slope_mc.ply"), "--method", "mc", "-q")
    r3 = run("contour", p("slope.npy"), "-o", p("slope_off.ply"), "--zero-set", "off", "-q")
    check("slope meshes", r2.returncode == 0 and r3.returncode == 0, r2.stderr + r3.stderr)

    def torus_error(path):
        data = open(path, "rb").read()
        head = data[:data.index(b"end_header\n") + len(b"end_header\n")].decode()
        n = int(head.split("element vertex ")[1].split()[0])
        double = "property double x" in head
        V = np.frombuffer(data[len(head):], dtype="<f8" if double else "<f4", count=3 * n).reshape(n, 3)
        return np.abs(np.sqrt((np.sqrt(V[:, 0] ** 2 + V[:, 1] ** 2) - 0.5) ** 2 + V[:, 2] ** 2) - 0.2).mean()
    errors = [torus_error(p(f)) for f in ("slope.ply", "slope_mc.ply", "slope_off.ply")]
    check("onto the zero set", 4 * errors[0] < errors[1] and errors[0] < errors[2], errors)
    open(p("one.ply"), "w").write("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                 "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
                                 "end_header\n0 0 0 0 0 1\n")
    expect_error("poisson one point", ["poisson", p("one.ply"), "-o", out], "no surface", [out])

    # The band, truncation and bricks: bad values, and a band without a surface.
    for opt, value, needle in [("--band", "0", "--band"), ("--band", "wide", "--band"), ("--band", "nan", "--band"),
                               ("--truncation", "-1", "--truncation"), ("--truncation", "maybe", "--truncation"),
                               ("--brick-size", "-1", "--brick-size"), ("--brick-halo", "-2", "halo"),
                               ("--brick-halo", "inf", "halo"), ("--split-sag", "-1", "--split-sag"),
                               ("--split-sag", "2", "--split-sag")]:
        expect_error(f"{opt} {value}", ["contour", "builtin:torus@24", "-o", out, "--points", p("bp.ply"), opt, value],
                     needle, [out, p("bp.ply")])
    expect_error("band without samples", ["contour", "builtin:torus@24", "-o", out, "--band", "1e-6", "--margin", "0"],
                 "band", [out])

    # A truncated grid (values clamped at 3h, as a TSDF stores them) is detected, and gives the same
    # contact points as the exact grid cut to the band it leaves; bricks give the same bytes as one
    # triangulation.
    x = np.linspace(-1, 1, 39)
    X, Y, Z = np.meshgrid(x, x, x, indexing="ij")
    torus = np.sqrt((np.sqrt(X**2 + Y**2) - 0.55) ** 2 + Z**2) - 0.25
    h = 2 / 38
    np.save(p("torus.npy"), torus)
    np.save(p("torus_tsdf.npy"), np.clip(torus, -3 * h, 3 * h))
    r = run("contour", p("torus_tsdf.npy"), "--points", p("tsdf_cp.ply"), "--band", "all", "--stats", p("t.json"), "-q")
    check("tsdf runs", r.returncode == 0, r.stderr)
    check("tsdf detected", json.load(open(p("t.json")))["band"]["truncation_detected"], open(p("t.json")).read())
    assert not np.any((np.abs(torus) > 2.999 * h) & (np.abs(torus) < 3 * h))
    assert not np.any((np.abs(torus) > 1.999 * h) & (np.abs(torus) <= 2 * h))
    r = run("contour", p("torus.npy"), "--points", p("exact_cp.ply"), "--band", "1.999", "-q")
    check("tsdf = exact in band", open(p("tsdf_cp.ply"), "rb").read() == open(p("exact_cp.ply"), "rb").read())
    for size in ("0", "8"):
        r = run("contour", p("torus.npy"), "--points", p(f"brick{size}.ply"), "--brick-size", size, "-q")
        check(f"brick size {size} runs", r.returncode == 0, r.stderr)
    check("bricks = one triangulation", open(p("brick0.ply"), "rb").read() == open(p("brick8.ply"), "rb").read())

    # Good input: same bytes with 1 and 2 threads, for every mesh method and the contact points.
    for method, source in [("mc", "builtin:csg@32"), ("mt-rt", "builtin:torus@28"), ("mt-dt", "builtin:box@random:20000")]:
        outputs = []
        for threads in ("1", "2"):
            mesh, pts, stats = p(f"{method}{threads}.ply"), p(f"{method}{threads}_cp.ply"), p(f"{method}{threads}.json")
            r = run("contour", source, "-o", mesh, "--points", pts, "--method", method, "--threads", threads,
                    "--stats", stats, "--quiet")
            check(f"{method} runs", r.returncode == 0, r.stderr)
            check(f"{method} quiet", r.stderr == "", r.stderr)
            outputs.append((open(mesh, "rb").read(), open(pts, "rb").read()))
            s = json.load(open(stats))
            header = outputs[-1][0][:400].decode("latin-1")
            check(f"{method} ply header", f"element vertex {s['mesh']['vertices']}" in header, header)
            check(f"{method} binary ply", "binary_little_endian" in header, header)
        check(f"{method} deterministic mesh", outputs[0][0] == outputs[1][0])
        check(f"{method} deterministic points", outputs[0][1] == outputs[1][1])

    # GCP's stage seconds add up to the total (the untangling runs twice and is summed).
    def seconds_add_up(name, r, s):
        check(name, r.returncode == 0 and
              abs(sum(s["seconds"].values()) - s["seconds_total"]) <= 1e-6 * s["seconds_total"], s["seconds"])

    r = run("contour", "builtin:torus@24", "-o", p("gcp_t.ply"), "--stats", p("gcp_t.json"), "-q")
    seconds_add_up("gcp stage seconds sum to the total", r, json.load(open(p("gcp_t.json"))))

    # Poisson options on a grid, whose default is the local reconstruction: said, even with -q.
    r = run("contour", "builtin:torus@24", "-o", p("gcp_d.ply"), "-q", "--depth", "7")
    check("poisson option on the local default warned", r.returncode == 0 and "--depth" in r.stderr and
          "--reconstruction poisson" in r.stderr, r.stderr)
    r = run("contour", "builtin:torus@24", "-o", p("gcp_d.ply"), "-q", "--depth", "7",
            "--reconstruction", "poisson")
    check("poisson option on poisson not warned", r.returncode == 0 and "warning" not in r.stderr, r.stderr)
    # So are the Poisson path's sign constraints on the local reconstruction, and the local
    # reconstruction's options on the Poisson path; neither on the path that reads them.
    r = run("contour", "builtin:torus@24", "-o", p("gcp_d.ply"), "-q", "--sign-band", "3")
    check("sign option on the local default warned", r.returncode == 0 and "--sign-band" in r.stderr and
          "--reconstruction poisson" in r.stderr, r.stderr)
    r = run("contour", "builtin:torus@24", "-o", p("gcp_d.ply"), "-q", "--reconstruction", "poisson",
            "--subdivisions", "1", "--thin-parts", "off")
    check("local options on poisson warned", r.returncode == 0 and "--subdivisions, --thin-parts" in r.stderr
          and "--reconstruction local" in r.stderr, r.stderr)
    r = run("contour", "builtin:torus@24", "-o", p("gcp_d.ply"), "-q", "--subdivisions", "1")
    check("local option on local not warned", r.returncode == 0 and "warning" not in r.stderr, r.stderr)

    # The Poisson path's side repair runs with carving's triangle rounds (below 128 samples per
    # axis) and reports in --stats; --no-side-repair skips it.
    r = run("contour", "builtin:torus@24", "-o", p("gcp_p.ply"), "--stats", p("gcp_p.json"), "-q",
            "--reconstruction", "poisson")
    s = json.load(open(p("gcp_p.json")))
    seconds_add_up("poisson stage seconds sum to the total", r, s)
    check("side repair in stats", "side_repair" in s and s["side_repair"]["left"] <= s["side_repair"]["wrong_side"],
          s.get("side_repair"))
    r = run("contour", "builtin:torus@24", "-o", p("gcp_n.ply"), "--stats", p("gcp_n.json"), "-q", "--no-side-repair",
            "--reconstruction", "poisson")
    s = json.load(open(p("gcp_n.json")))
    check("--no-side-repair", r.returncode == 0 and "side_repair" not in s, r.stderr)

    # Scattered samples from a file, OBJ output, ASCII contact points.
    rng = np.random.default_rng(3)
    pts = rng.uniform(-1, 1, (4000, 3))
    np.save(p("scattered.npy"), np.hstack([pts, (np.linalg.norm(pts, axis=1) - 0.6)[:, None]]))
    r = run("contour", p("scattered.npy"), "-o", p("s.obj"), "--method", "mt-dt", "--points", p("s_cp.ply"), "--ascii")
    check("scattered obj", r.returncode == 0 and open(p("s.obj")).read().startswith("#"), r.stderr)
    cp = np.loadtxt(p("s_cp.ply"), skiprows=12)
    check("ascii points", cp.shape[1] == 6 and np.allclose(np.linalg.norm(cp[:, 3:], axis=1), 1), cp.shape)
    check("scattered points near sphere", np.median(np.abs(np.linalg.norm(cp[:, :3], axis=1) - 0.6)) < 0.01)
    check("progress on stderr", "[sdfcontour]" in r.stderr, r.stderr)

    # Poisson: GCP and GTCP meshes, the poisson subcommand on a point cloud, and its bad input.
    for method in ("gcp", "gtcp"):
        outputs = []
        for threads in ("1", "2"):
            mesh = p(f"{method}{threads}.ply")
            r = run("contour", "builtin:torus@20", "-o", mesh, "--method", method, "--depth", "6", "--threads", threads, "-q")
            check(f"{method} mesh", r.returncode == 0, r.stderr)
            outputs.append(open(mesh, "rb").read())
        check(f"{method} deterministic mesh", outputs[0] == outputs[1])
        # The heap (the CLI's own malloc settings, or huge pages a user asks glibc for) changes
        # where bytes live, not the mesh.
        mesh = p(f"{method}_huge_pages.ply")
        r = subprocess.run([CLI, "contour", "builtin:torus@20", "-o", mesh, "--method", method, "--depth", "6", "-q"],
                           capture_output=True, text=True, timeout=300,
                           env={**os.environ, "GLIBC_TUNABLES": "glibc.malloc.hugetlb=1"})
        check(f"{method} mesh with huge pages", r.returncode == 0 and open(mesh, "rb").read() == outputs[0],
              r.stderr)
    r = run("contour", "builtin:sphere@24", "--points", p("cp.ply"), "-q")
    check("gcp points", r.returncode == 0, r.stderr)
    r = run("poisson", p("cp.ply"), "-o", p("poisson.obj"), "--depth", "6", "--alpha", "4", "--boundary", "dirichlet",
            "--densities", p("density.npy"), "--stats", p("poisson.json"), "-q")
    check("poisson runs", r.returncode == 0, r.stderr)
    verts = [line for line in open(p("poisson.obj")) if line.startswith("v ")]
    density = np.load(p("density.npy"))
    check("poisson densities", len(density) == len(verts) and np.all(density > 0), (len(density), len(verts)))
    radii = np.linalg.norm(np.array([[float(x) for x in v.split()[1:]] for v in verts]), axis=1)
    check("poisson sphere radius", abs(np.median(radii) - 0.6) < 0.01, np.median(radii))
    s = json.load(open(p("poisson.json")))
    check("poisson stats", s["options"]["alpha"] == 4 and s["levels"][-1]["depth"] <= 6, s["options"])
    open(p("empty.ply"), "w").write("ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
                                   "property float z\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n")
    expect_error("poisson no points", ["poisson", p("empty.ply"), "-o", out], "no points", [out])
    open(p("zero.ply"), "w").write("ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                                  "property float z\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n"
                                  "0 0 0 0 0 1\n1 0 0 0 0 0\n")
    expect_error("poisson zero normal", ["poisson", p("zero.ply"), "-o", out], "zero normal", [out])
    open(p("nan.ply"), "w").write("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                 "property float z\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n"
                                 "nan 0 0 0 0 1\n")
    expect_error("poisson nan text", ["poisson", p("nan.ply"), "-o", out], "cannot parse", [out])
    body = np.array([[0, 0, 0, 0, 0, 1], [np.nan, 0, 0, 0, 0, 1]], dtype="<f8").tobytes()
    header = ("ply\nformat binary_little_endian 1.0\nelement vertex 2\n" +
              "".join(f"property double {c}\n" for c in ("x", "y", "z", "nx", "ny", "nz")) + "end_header\n")
    open(p("nan_binary.ply"), "wb").write(header.encode() + body)
    expect_error("poisson nan", ["poisson", p("nan_binary.ply"), "-o", out], "NaN", [out])
    expect_error("poisson missing", ["poisson", p("none.ply"), "-o", out], "cannot read", [out])
    expect_error("poisson boundary", ["poisson", p("cp.ply"), "-o", out, "--boundary", "robin"], "boundary", [out])
    for boundary in ("neumann", "free"):
        r = run("poisson", p("cp.ply"), "-o", p(f"{boundary}.ply"), "--depth", "6", "--boundary", boundary, "-q")
        check(f"poisson {boundary}", r.returncode == 0, r.stderr)
    check("poisson free = neumann (degree 1)", open(p("free.ply"), "rb").read() == open(p("neumann.ply"), "rb").read())
    for boundary in ("neumann", "free"):
        r = run("poisson", p("cp.ply"), "-o", p(f"{boundary}2.ply"), "--depth", "6", "--boundary", boundary,
                "--degree", "2", "-q")
        check(f"poisson degree 2 {boundary}", r.returncode == 0, r.stderr)
    check("poisson free != neumann (degree 2)", open(p("free2.ply"), "rb").read() != open(p("neumann2.ply"), "rb").read())
    for bad in ("0", "3", "1.5"):
        expect_error(f"poisson degree {bad}", ["poisson", p("cp.ply"), "-o", out, "--degree", bad], "degree", [out])

    # sample / eval / eval-points on a shared mesh, and their bad input.
    meshes = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "data", "meshes")
    if not os.path.isdir(meshes):
        print(f"SKIP the shared-mesh checks: no meshes at {meshes}")
        meshes = None
    if meshes:
        prefix = p("spot")
        r = run("sample", os.path.join(meshes, "spot.obj"), "--res", "24", "-o", prefix, "-q")
        check("sample runs", r.returncode == 0, r.stderr)
        grid = np.load(prefix + ".npy")
        check("sample grid", grid.shape == (24, 24, 24) and (grid < 0).any() and (grid > 0).any(), grid.shape)
        # The sword's blade is thinner than a spacing at 8^3: no sample inside.
        expect_error("sample too coarse", ["sample", os.path.join(meshes, "sword.obj"), "--res", "8", "-o", p("sword")],
                     "thinner than a spacing", [p("sword.npy"), p("sword_gtcp.ply"), p("sword_mesh.ply")])
        r = run("sample", os.path.join(meshes, "spot.obj"), "--random", "3000", "--seed", "2", "-o", p("spot_random"), "-q")
        check("sample random", r.returncode == 0 and np.load(p("spot_random.npy")).shape == (3000, 4), r.stderr)
        r = run("contour", prefix + ".npy", "-o", p("spot_mc.ply"), "--method", "mc", "-q")
        check("contour sampled grid", r.returncode == 0, r.stderr)
        r = run("eval", p("spot_mc.ply"), prefix + "_mesh.ply", "--samples", "20000")
        check("eval runs", r.returncode == 0, r.stderr)
        e = json.loads(r.stdout)
        h = 2 / 23
        check("eval values", 0 < e["L1"] < 0.1 * h and e["L1"] <= e["L2"] <= e["L_inf"] < h, e)
        check("eval topology", e["recon_mesh"]["closed"] and e["recon_mesh"]["genus"] == 0, e["recon_mesh"])
        r = run("eval-points", prefix + "_gtcp.ply", prefix + "_mesh.ply")
        e = json.loads(r.stdout)
        check("eval-points gtcp exact", r.returncode == 0 and e["abs_value"]["p95"] < 1e-9 and e["count"] == 24**3, e)
        lines = open(os.path.join(meshes, "cube.obj")).read().splitlines()
        faces = [i for i, line in enumerate(lines) if line.startswith("f ")]
        open(p("open.obj"), "w").write("\n".join(line for i, line in enumerate(lines) if i != faces[-1]) + "\n")
        expect_error("sample open mesh", ["sample", p("open.obj"), "--res", "8", "-o", p("o")], "not closed", [p("o.npy")])
        expect_error("sample no mesh", ["sample", p("none.obj"), "--res", "8", "-o", p("o")], "cannot read", [p("o.npy")])
        expect_error("sample both", ["sample", os.path.join(meshes, "cube.obj"), "--res", "8", "--random", "9", "-o", p("o")],
                     "exactly one", [p("o.npy")])
        # OpenVDB: sample to a level set, contour it sparse, and its bad input.
        r = run("sample", os.path.join(meshes, "spot.obj"), "--res", "40", "-o", p("spot.vdb"), "-q")
        check("sample vdb", r.returncode == 0 and os.path.exists(p("spot.vdb")) and os.path.exists(p("spot_mesh.ply")),
              r.stderr)
        r = run("contour", p("spot.vdb"), "-o", p("spot_vdb.ply"), "--reconstruction", "poisson", "--depth", "7",
                "--stats", p("vdb.json"), "-q")
        check("contour vdb", r.returncode == 0, r.stderr)
        s = json.load(open(p("vdb.json")))
        check("vdb sparse", s["samples"] < 40**3 / 4 and abs(s["band"]["spacing"] - 2 / 39) < 1e-9, s)
        r = run("eval", p("spot_vdb.ply"), p("spot_mesh.ply"), "--samples", "20000")
        check("vdb mesh accurate", r.returncode == 0 and json.loads(r.stdout)["L1"] < 0.05 * 2 / 39, r.stdout)
        poisson_l1 = json.loads(r.stdout)["L1"]
        # By default GCP's local reconstruction, read box by box on the voxels' grid (the active
        # voxels' box grown by one): closed, and closer than the Poisson mesh of the same file.
        r = run("contour", p("spot.vdb"), "-o", p("spot_vdb_local.ply"), "--stats", p("vdb_local.json"), "-q")
        check("contour vdb local", r.returncode == 0 and r.stderr == "", r.stderr)
        s = json.load(open(p("vdb_local.json")))
        check("vdb local by boxes", s.get("reconstruction") == "local" and s["local_bricks"]["bricks"] == 1 and
              s["samples"] == s["grid"][0] * s["grid"][1] * s["grid"][2], s)
        r = run("eval", p("spot_vdb_local.ply"), p("spot_mesh.ply"), "--samples", "20000")
        e = json.loads(r.stdout)
        check("vdb local accurate", r.returncode == 0 and e["L1"] < poisson_l1 and e["recon_mesh"]["closed"] and
              e["recon_mesh"]["manifold"] and e["recon_mesh"]["self_intersections"] == 0, r.stdout)
        r = run("contour", p("spot.vdb"), "-o", p("spot_vdb_local2.ply"), "--depth", "7", "-q")
        check("vdb local warns of Poisson options", r.returncode == 0 and "--depth set the Poisson" in r.stderr,
              r.stderr)
        expect_error("vdb local knn", ["contour", p("spot.vdb"), "-o", out, "--reconstruction", "local",
                                       "--gradient", "knn"], "regular or lattice gradients", [out])
        # Marching cubes reads it box by box too: closed, and farther than GCP's local mesh.
        r = run("contour", p("spot.vdb"), "-o", p("spot_vdb_mc.ply"), "--method", "mc", "-q")
        check("contour vdb mc", r.returncode == 0 and r.stderr == "", r.stderr)
        r = run("eval", p("spot_vdb_mc.ply"), p("spot_mesh.ply"), "--samples", "20000")
        m = json.loads(r.stdout)
        check("vdb mc closed, farther than local", r.returncode == 0 and m["recon_mesh"]["closed"] and
              e["L1"] < m["L1"] < 0.5 * 2 / 39, r.stdout)
        expect_error("vdb grid name", ["contour", p("spot.vdb"), "-o", out, "--grid", "density"], "no float grid named",
                     [out])
        open(p("junk.vdb"), "w").write("not a vdb")
        expect_error("vdb junk", ["contour", p("junk.vdb"), "-o", out], "not a .vdb", [out])
        expect_error("vdb random", ["sample", os.path.join(meshes, "cube.obj"), "--random", "100", "-o", p("c.vdb")],
                     "grid", [p("c.vdb")])
        # OpenVDB is a module loaded on first use: one that does not load is an error, not a crash.
        broken = dict(os.environ, SDFCONTOUR_OPENVDB_MODULE=p("junk.vdb"))
        expect_error("vdb module broken, read", ["contour", p("spot.vdb"), "-o", out], "cannot load the OpenVDB module",
                     [out], env=broken)
        expect_error("vdb module broken, write", ["sample", os.path.join(meshes, "cube.obj"), "--res", "8", "-o",
                                                  p("c2.vdb")], "cannot load the OpenVDB module",
                     [p("c2.vdb"), p("c2_mesh.ply"), p("c2_gtcp.ply")], env=broken)
        expect_error("eval unreadable", ["eval", p("none.ply"), prefix + "_mesh.ply"], "cannot read")
        open(p("empty.off"), "w").write("OFF\n0 0 0\n")
        expect_error("eval empty mesh", ["eval", p("empty.off"), prefix + "_mesh.ply"], "")
        expect_error("eval samples -1", ["eval", p("spot_mc.ply"), prefix + "_mesh.ply", "--samples", "-1"], "--samples")
        expect_error("sample scale inf", ["sample", os.path.join(meshes, "cube.obj"), "--res", "8", "--scale", "inf", "-o",
                                          p("o")], "--scale", [p("o.npy")])

finish()

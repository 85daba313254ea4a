"""Resident memory over a run of the CLI, and a picture of runs side by side.

`record` runs a command (the CLI: it re-executes itself in place, so its process id stays) and
polls /proc/PID/status every --every seconds: one line per poll, "seconds rss_gb file_gb" (VmRSS
and its file-mapped part, RssFile, in GB as the docs' tables give /usr/bin/time's peaks: its KB
over 1e6), then the peak (VmHWM) on stderr. `plot` draws
such traces against time.

Usage:
    /usr/bin/python3 bench/memory_trace.py record trace.tsv -- build/sdfcontour contour \
        bunny_1024.npy -o b.ply --quiet
    /usr/bin/python3 bench/memory_trace.py plot --png docs/img/memory_1024.png \
        "session 11=docs/notes/results/memory_1024_session11.tsv" "session 12=trace.tsv"
"""
import argparse
import subprocess
import sys
import time

FIELDS = ("VmRSS", "RssFile", "VmHWM")


def status(pid):
    """The FIELDS of /proc/PID/status in KB / 1e6, or None once the process is gone."""
    try:
        with open(f"/proc/{pid}/status") as f:
            values = {}
            for line in f:
                name, _, rest = line.partition(":")
                if name in FIELDS:
                    values[name] = int(rest.split()[0]) / 1e6
            return values if len(values) == len(FIELDS) else None
    except OSError:
        return None


def record(out, command, every):
    start = time.monotonic()
    process = subprocess.Popen(command)
    peak = 0.0
    with open(out, "w") as f:
        f.write("# seconds rss_gb file_gb\n")
        while process.poll() is None:
            s = status(process.pid)
            if s:
                peak = max(peak, s["VmHWM"])
                f.write(f"{time.monotonic() - start:.2f} {s['VmRSS']:.4f} {s['RssFile']:.4f}\n")
            time.sleep(every)
    print(f"exit {process.returncode}, {time.monotonic() - start:.1f} s, peak {peak:.3f} GB "
          f"(VmHWM at the last poll)", file=sys.stderr)
    return process.returncode


def read_trace(path):
    rows = [line.split() for line in open(path) if line.strip() and not line.startswith("#")]
    return [float(r[0]) for r in rows], [float(r[1]) for r in rows], [float(r[2]) for r in rows]


def plot(png, traces, limit):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(11, 4))
    for i, spec in enumerate(traces):
        label, _, path = spec.partition("=")
        t, rss, file_gb = read_trace(path)
        ax.plot(t, rss, color=f"C{i}", label=f"{label}: peak {max(rss):.2f} GB")
        ax.plot(t, file_gb, color=f"C{i}", ls=":", lw=1, label=f"{label}: of it the mapped grid")
    if limit:
        ax.axhline(limit, color="k", lw=0.8, ls="--", label=f"{limit:g} GB")
    ax.set_xlabel("seconds")
    ax.set_ylabel("resident memory (GB)")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1))
    fig.tight_layout()
    fig.savefig(png, dpi=110)


def main():
    ap = argparse.ArgumentParser()
    sub = ap.add_subparsers(dest="what", required=True)
    r = sub.add_parser("record")
    r.add_argument("out")
    r.add_argument("--every", type=float, default=0.5)
    r.add_argument("command", nargs=argparse.REMAINDER)
    p = sub.add_parser("plot")
    p.add_argument("--png", required=True)
    p.add_argument("--limit", type=float, default=4.0, help="a line at this many GB (0: none)")
    p.add_argument("traces", nargs="+", help="LABEL=trace.tsv")
    a = ap.parse_args()
    if a.what == "record":
        command = a.command[1:] if a.command[:1] == ["--"] else a.command
        if not command:
            ap.error("record needs a command after --")
        sys.exit(record(a.out, command, a.every))
    plot(a.png, a.traces, a.limit)


if __name__ == "__main__":
    main()

"""What the command-line tests share: running the tool and counting checks.

expect_error asserts the project's error format: a non-zero exit, one `sdfcontour: error:` line
(the last), the expected words in it, and no output or temporary file left behind."""
import os
import subprocess
import sys

CLI = sys.argv[1]
counts = {"passed": 0, "failed": 0}


def run(*args, env=None, timeout=300):
    return subprocess.run([CLI, *args], capture_output=True, text=True, timeout=timeout, env=env)


def check(name, condition, detail=""):
    if condition:
        counts["passed"] += 1
    else:
        counts["failed"] += 1
        print(f"FAIL {name}: {detail}")


def expect_error(name, args, needle, out_files=(), env=None, exit_code=None):
    r = run(*args, env=env)
    lines = r.stderr.strip().splitlines()
    errors = [line for line in lines if line.startswith("sdfcontour: error:")]
    check(name + " exit code", r.returncode != 0 if exit_code is None else r.returncode == exit_code,
          f"exit {r.returncode}")
    check(name + " one error line, last", len(errors) == 1 and lines[-1] == errors[0], repr(r.stderr))
    check(name + " message", bool(lines) and lines[-1].startswith("sdfcontour: error:") and needle in lines[-1],
          repr(r.stderr))
    for f in out_files:
        check(name + " no output", not os.path.exists(f), f)
        leftovers = [p for p in os.listdir(os.path.dirname(f)) if ".tmp-" in p]
        check(name + " no temporary files", not leftovers, leftovers)
    return r


def finish():
    print(f"{counts['passed']} passed, {counts['failed']} failed")
    sys.exit(1 if counts["failed"] else 0)

"""The `sdfcontour` command that pip installs: runs the C++ program carried inside the package."""
import os
import sys


def main():
    program = os.path.join(os.path.dirname(os.path.abspath(__file__)), "_bin", "sdfcontour")
    if not os.access(program, os.X_OK):
        sys.exit(f"sdfcontour: error: the program is not installed at {program}; reinstall the "
                 f"package (pip install .)")
    os.execv(program, ["sdfcontour"] + sys.argv[1:])

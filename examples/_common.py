"""Shared plumbing of the real-data examples: find the repository and the built ctid
package, read the shipped CSV files, choose the output folder, write the numeric summary.

The examples import ctid from the build tree (build/python, or $CTID_BUILD_DIR/python) so
that they run straight after ``scripts/demo.sh`` without installing anything.
"""

import argparse
import json
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DATA = os.path.join(ROOT, "data")


def import_ctid():
    """Import ctid and ctid.plotting, adding the build tree to sys.path when needed."""
    candidates = [os.environ.get("CTID_BUILD_DIR", ""), os.path.join(ROOT, "build")]
    for build in candidates:
        path = os.path.join(build, "python") if build else ""
        if path and os.path.isdir(os.path.join(path, "ctid")) and path not in sys.path:
            sys.path.insert(0, path)
            break
    import ctid  # noqa: F401
    import ctid.plotting  # noqa: F401

    return ctid


def read_csv(relative_path):
    """(column names, float array) of a CSV under data/ with one header line."""
    import numpy as np

    path = os.path.join(DATA, relative_path)
    with open(path) as f:
        names = f.readline().strip().split(",")
    return names, np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


def arguments(name, description):
    """--out DIR (default $CTID_OUT_DIR/examples/<name>, else out/examples/<name>)."""
    parser = argparse.ArgumentParser(description=description)
    base = os.environ.get("CTID_OUT_DIR", os.path.join(ROOT, "out"))
    parser.add_argument("--out", default=os.path.join(base, "examples", name),
                        help="folder for the figures and summary.json")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    return args


def write_summary(out, summary):
    """Write summary.json in `out` and return its path."""
    path = os.path.join(out, "summary.json")
    with open(path, "w") as f:
        json.dump(summary, f, indent=2, sort_keys=False)
        f.write("\n")
    return path

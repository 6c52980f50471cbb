"""``python3 -m ctid ARGS``: the ctid command line without the ``ctid`` binary.

The package's extension holds the same commands as the binary (decision 0052), so this runs
``ctid ARGS`` exactly: same flags, files, messages and exit status.
"""

import os
import sys


def main(argv=None):
    from ._ctid import _command_line

    args = sys.argv[1:] if argv is None else list(argv)
    # The processes the command line starts (the records of `ctid batch`, `--plot`'s
    # python3 -m ctid.plot) find this package: it is first on their path.
    package_parent = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    os.environ.setdefault("CTID_PYTHONPATH", package_parent)
    os.environ["PYTHONPATH"] = os.pathsep.join(
        [package_parent] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p])
    sys.stdout.flush()
    return _command_line([os.fsencode(arg) for arg in args], [sys.executable, "-m", "ctid"])


if __name__ == "__main__":
    sys.exit(main())

"""``python3 -m ctid ARGS``: the ctid command line without the ``ctid`` binary.

The package's extension holds the same commands as the binary (decision 0052), so this runs
``ctid ARGS`` exactly: same flags, files, messages and exit status.
"""

import os
import sys


def main(argv=None):
    from ._ctid import _command_line

    args = sys.argv[1:] if argv is None else list(argv)
    sys.stdout.flush()
    return _command_line([os.fsencode(arg) for arg in args])


if __name__ == "__main__":
    sys.exit(main())

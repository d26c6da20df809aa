"""``python -m duet_robot ...``: the command line, as ``python app.py ...``."""

from __future__ import annotations

import sys

from duet_robot import main

if __name__ == "__main__":
    sys.argv[0] = "python -m duet_robot"  # what --help names the program
    raise SystemExit(main())

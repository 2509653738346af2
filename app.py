"""``python app.py``: the swimmer chases the point you click on the water, in a real-time 3-D window.

A shim: the app is the ``app`` command (``layered_swim/commands/app.py``; also ``layered-swim
app``), run here as a program of its own. ``--help`` for the options, H in the window for the keys."""
from __future__ import annotations

import sys

from layered_swim.cli import main as _main

PROG = "app.py"


def main(argv: list[str] | None = None) -> int:
    return _main(argv, prog=PROG, command="app")


if __name__ == "__main__":
    sys.exit(main())

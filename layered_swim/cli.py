"""``layered-swim``: headless runs, target following, calibration, benchmarks, rendering and the app.

The commands live in ``layered_swim/commands/``, one module each (``add_parser``, ``run``); this
module puts their parsers together and runs the one asked for. Heavy modules (PyBullet, torch)
must not be imported before ``main`` has moved C-level stdout out of the way (see
``_guard_stdout``): the command modules import them inside ``run``, and keep their top-level
imports light, which also keeps ``--help`` fast.
"""
from __future__ import annotations

import argparse
import os
import re
import signal
import sys

from layered_swim.commands import (
    PROG,
    analyze,
    app,
    bench,
    calibrate,
    compare,
    experiment,
    export,
    fit_stroke,
    follow,
    goal,
    render,
    run,
    soak,
    strokes,
    train,
    validate,
)

# In the order `layered-swim --help` lists them; a module's name with '-' for '_' is its command's.
COMMANDS = {module.__name__.rpartition(".")[2].replace("_", "-"): module
            for module in (run, strokes, validate, calibrate, fit_stroke, follow, goal, render, export, analyze,
                           compare, experiment, train, soak, bench, app)}


class OneLineParser(argparse.ArgumentParser):
    """argparse with one-line errors, values like ``-5,0,5`` taken as values, not options, and no
    abbreviated options (``follow --seed 3`` would have run ``--seeds 3``: three swims)."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(r"^-\.?\d")

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


def _guard_stdout() -> None:
    """PyBullet's C code printf's (importer notes; its build time in some builds) into C's stdio
    buffer, which a piped stdout flushes at exit, after our output: it would corrupt ``--json``.
    Point fd 1 at /dev/null for C and keep Python's ``sys.stdout`` on a duplicate of the real one."""
    sys.stdout.flush()
    real = os.dup(1)
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.close(devnull)
    sys.stdout = open(real, "w", buffering=1, closefd=True)


def _parser(prog: str = PROG, command: str | None = None) -> argparse.ArgumentParser:
    """The full parser, every command a sub-parser; with ``command`` (one that has
    ``add_arguments``: app), that command's options alone, as a program of its own (``app.py``)."""
    if command is not None:
        module = COMMANDS[command]
        p = OneLineParser(prog=prog, description=module.DESCRIPTION)
        module.add_arguments(p)
        p.set_defaults(command=command)
        return p
    p = OneLineParser(prog=prog, description="A physically simulated human swimmer.")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for module in COMMANDS.values():
        module.add_parser(sub)
    return p


def main(argv: list[str] | None = None, prog: str = PROG, command: str | None = None) -> int:
    """Entry point: ``layered-swim COMMAND ...``, or with ``command`` that one command as a
    program of its own (app.py: ``main(argv, "app.py", "app")``). Redirects fd 1 for the rest of
    the process (see ``_guard_stdout``): call it in a subprocess, not inside a test runner that
    captures output."""
    _guard_stdout()
    # A shell script's background job starts with SIGINT ignored; `kill -INT` must still stop a
    # run (keeping its log), so take Ctrl-C's handler back.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    args = _parser(prog, command).parse_args(argv)
    return report_errors(prog, lambda: COMMANDS[args.command].run(args))


def report_errors(prog: str, action) -> int:
    """Run ``action``; bad input or a blown-up simulation is one line on stderr and exit code 2,
    Ctrl-C is 130 (every command, app.py too, ends this way)."""
    from layered_swim.config import ConfigError
    from layered_swim.fluid.backend import FluidError
    from layered_swim.sim.simulation import SimulationDiverged  # imports PyBullet quietly (sim/world.py)

    try:
        action()
    except (ConfigError, SimulationDiverged, FluidError, OSError) as err:
        print(f"{prog}: error: {_one_line(err)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        return 130
    return 0


def _one_line(err: Exception) -> str:
    text = str(err) if not isinstance(err, OSError) or not err.filename else f"{err.filename}: {err.strerror}"
    return " ".join(text.split())


if __name__ == "__main__":
    sys.exit(main())

"""Faults keep what was done: a full disk or a dead SPH solver ends a run in one line naming
where its files are, and nothing logged before the fault is lost."""
import errno
import json
import os
import subprocess
import sys
from contextlib import contextmanager
from importlib.util import find_spec
from pathlib import Path

import pytest
from test_cli import REPO

from layered_swim import outputs, recorder
from layered_swim.cli import report_errors
from layered_swim.recorder import SPOOL_DIR, read_log
from layered_swim.runs import run_swim
from layered_swim.spec import SwimSpec

CHUNK_ROWS = 6      # a 0.5 s run at 60 Hz: five chunks in the spool, not one per 10 s


def _full_disk_at(name: str):
    """``atomic_path`` whose file ``name`` fails as a write on a full disk does: at its last
    flush, naming no file, its temporary file left to be deleted."""
    real = outputs.atomic_path

    @contextmanager
    def atomic_path(path):
        with real(path) as tmp:
            yield tmp
            if Path(path).name == name:
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    return atomic_path


@pytest.mark.parametrize("name, kept, rows", [
    ("chunk-000002.npz", SPOOL_DIR, 12),      # mid-run: the two chunks before it stay
    ("chunk-000000.npz", None, 0),            # mid-run, before any chunk: no spool holding only names
    ("log.npz", SPOOL_DIR, 30),               # at the save: the spool stays until the log is whole
    ("summary.json", "log.npz", 30),
])
def test_a_full_disk_is_one_line_naming_the_file_and_keeps_the_log(tmp_path, monkeypatch, capsys, name, kept, rows):
    monkeypatch.setattr(recorder, "CHUNK_ROWS", CHUNK_ROWS)
    monkeypatch.setattr(recorder, "atomic_path", _full_disk_at(name))
    monkeypatch.setattr(outputs, "atomic_path", _full_disk_at(name))
    out = tmp_path / "run"
    assert report_errors("layered-swim", lambda: run_swim(SwimSpec(stroke="breaststroke", seconds=0.5), out)) == 2
    failed = out / SPOOL_DIR / name if name.startswith("chunk") else out / name
    where = f"the log so far is kept in {out / kept}" if kept else "no log is kept"
    assert capsys.readouterr().err.splitlines() == [f"layered-swim: error: {failed}: No space left on device; {where}"]
    if kept:
        log = read_log(out)
        assert log["partial"] == (kept == SPOOL_DIR) and len(log["time_s"]) == rows
    else:
        assert not (out / SPOOL_DIR).exists() and not (out / "log.npz").exists()
    assert not list(out.rglob(".*.tmp*"))         # no half-written file beside


# The worker killed (SIGKILL) as soon as it has been sent the pool to build, before it can
# answer: deterministic, and quick (the pool is never built).
KILL_DURING_START = """
import sys
from layered_swim import cli
from layered_swim.fluid.sph.worker import SphWorker

request = SphWorker.request

def killed_during_start(self, command, payload=None):
    if command == "start":
        send = self._conn.send
        self._conn.send = lambda message: (send(message), self._process.kill())
    return request(self, command, payload)

SphWorker.request = killed_during_start
sys.exit(cli.main(sys.argv[1:]))
"""


# Looked up, not imported: importing SPlisHSPlasH beside PyBullet crashes the process (why it runs
# in a worker).
@pytest.mark.skipif(find_spec("pysplishsplash") is None, reason="the sph extra is not installed")
def test_an_sph_worker_killed_during_start_leaves_a_partial_summary_in_one_line(tmp_path):
    out = tmp_path / "run"
    done = subprocess.run([sys.executable, "-W", "always::RuntimeWarning", "-c", KILL_DURING_START, "run", "--stroke",
                           "breaststroke", "--seconds", "2", "--backend", "sph", "--particle-radius", "0.05",
                           "--deterministic", "--out", str(out)], cwd=REPO, capture_output=True, text=True, timeout=60)
    assert done.returncode == 2 and done.stdout == "" and "RuntimeWarning" not in done.stderr
    [line] = done.stderr.splitlines()       # the tail of the solver's log between, not its deleted path
    assert line.startswith("layered-swim: error: the SPH solver process died during 'start' (exit code -9): ")
    assert line.endswith(f"; the run so far is saved in {out}")
    partial = json.loads((out / "summary.json").read_text())["partial"]
    assert partial["stopped_at_s"] == 0.0 and partial["reason"].startswith("the SPH solver process died during 'start'")
    assert not (out / SPOOL_DIR).exists() and (out / "config.json").exists()

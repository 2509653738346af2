"""Where commands write: an output folder is checked before any work, claimed only after every
argument and file has been checked, and every file appears whole or not at all.

A folder is fit for a command when it is empty (or not there yet), or holds an earlier output
of the same command, which the new files replace (a sweep's cache in it is reused). A folder
holds our output when it has our marker file (``.layered-swim-output``, written by the command
that claimed it; folders of older versions are recognised by their ``config.json``). Anything
else — a home folder, a folder of someone's files, a symbolic link — is refused in one line.
``overwrite`` lets a command replace another command's output: the old files are moved aside
into ``.previous/`` inside the folder (the one before them is dropped), never deleted outright.
One command writes into a folder at a time: claiming it takes a lock (``fcntl.flock`` on a
file inside it), which the system drops when the process ends, however it ends.
"""
from __future__ import annotations

import fcntl
import json
import os
import shutil
import sys
import time
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from layered_swim.config import ConfigError, load_json

COMMAND_KEY = "command"     # config.json's field naming the command that wrote the folder
MARKER = ".layered-swim-output"
LOCK = ".layered-swim.lock"
PREVIOUS = ".previous"
OURS = (MARKER, LOCK, PREVIOUS)

_held: dict[Path, int] = {}     # folders this process has claimed: their lock files' descriptors


@dataclass(frozen=True)
class OutputFolder:
    """A checked output folder, not yet touched: ``claim`` creates, locks and marks it."""

    path: Path
    command: str
    overwrite: bool = False


def check_out_dir(path: str | Path, command: str, overwrite: bool = False) -> OutputFolder:
    """``path`` checked for ``command`` by the module's rules, without touching the disk."""
    if not str(path).strip():
        raise ConfigError("--out is empty; name a folder")
    out = Path(path)
    if out.is_symlink():
        raise ConfigError(f"{out}: is a symbolic link; give the folder it points to, if it is meant")
    if out.exists() and not out.is_dir():
        raise ConfigError(f"{out}: exists and is not a folder")
    _refuse_busy(out)        # first: a command at work there has half-written files about
    if out.is_dir() and _has_files(out):
        earlier = _command_of(out)
        if earlier is None:
            raise ConfigError(f"{out}: holds files that are not a layered-swim output; refusing to touch them, "
                              "choose another --out")
        if earlier != command and not overwrite:
            raise ConfigError(f"{out}: holds the output of `{earlier}`; choose another --out or add --overwrite "
                              f"to replace it (the old files move to {PREVIOUS}/)")
        if overwrite:
            _refuse_protected(out)
    return OutputFolder(out, command, overwrite)


def claim(out: OutputFolder | str | Path) -> Path:
    """The folder, created, locked for this process, earlier output set aside where asked, and
    marked as ours. A plain path is the caller's own folder: only created."""
    if not isinstance(out, OutputFolder):
        path = Path(out)
        path.mkdir(parents=True, exist_ok=True)
        return path
    out = check_out_dir(out.path, out.command, out.overwrite)     # again: time has passed since the check
    path = out.path
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise ConfigError(f"{path}: cannot create it ({err.strerror})") from None
    _lock(path)
    if out.overwrite and _has_files(path):
        _set_aside(path)
    marker = {COMMAND_KEY: out.command, "argv": sys.argv, "pid": os.getpid(),
              "started": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
    try:
        write_json(path / MARKER, marker)
    except OSError as err:
        raise ConfigError(f"{path}: cannot write there ({err.strerror})") from None
    return path


def release(path: str | Path) -> None:
    """Drop this process's lock on ``path`` (the end of the process drops it too)."""
    fd = _held.pop(Path(path).resolve(), None)
    if fd is not None:
        os.close(fd)


def folder_path(out: OutputFolder | str | Path) -> Path:
    return out.path if isinstance(out, OutputFolder) else Path(out)


def _has_files(folder: Path) -> bool:
    return any(entry.name not in (LOCK, MARKER) for entry in folder.iterdir())


def _refuse_busy(path: Path) -> None:
    """One line if another process holds ``path``'s lock; only looks (a shared lock, let go)."""
    if Path(path).resolve() in _held or not (path / LOCK).is_file():
        return
    try:
        fd = os.open(path / LOCK, os.O_RDONLY)
    except OSError:
        return            # unreadable: claiming it will say why
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except OSError:
        _busy(path, fd)
    os.close(fd)


def _busy(path: Path, fd: int):
    holder = os.read(fd, 64).decode(errors="replace").strip() or "?"
    os.close(fd)
    raise ConfigError(f"{path}: another layered-swim command (pid {holder}) is writing there; wait for it "
                      "or choose another --out")


def _lock(path: Path) -> None:
    key = path.resolve()
    if key in _held:
        return
    try:
        fd = os.open(path / LOCK, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError as err:
        raise ConfigError(f"{path}: cannot write there ({err.strerror})") from None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        _busy(path, fd)
    # The lock file of a run that was killed is still there, but its lock went with the process:
    # taking it above is how a stale lock is told from a live one.
    os.ftruncate(fd, 0)
    os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
    _held[key] = fd


def _command_of(folder: Path) -> str | None:
    """The command whose output ``folder`` holds, by our marker or (older versions) config.json."""
    for name in (MARKER, "config.json"):
        try:
            data = load_json(folder / name)
        except ConfigError:        # none, or not ours
            continue
        command = data.get(COMMAND_KEY) if isinstance(data, dict) else None
        if isinstance(command, str):
            return command
    return None


def _refuse_protected(folder: Path) -> None:
    """Folders never replaced, whatever marker they hold."""
    resolved = folder.resolve()
    here = Path.cwd().resolve()
    if (resolved == here or resolved in here.parents or resolved == Path.home().resolve()
            or resolved in Path.home().resolve().parents or (folder / ".git").exists()):
        raise ConfigError(f"{folder}: refusing to replace the working folder, a home folder, one above them "
                          "or a repository")


def _set_aside(folder: Path) -> None:
    """Move the folder's earlier output into PREVIOUS (dropping the one before it)."""
    previous = folder / PREVIOUS
    if previous.is_symlink() or previous.is_file():
        previous.unlink()
    elif previous.is_dir():
        shutil.rmtree(previous)
    previous.mkdir()
    for entry in folder.iterdir():
        if entry.name not in OURS:
            entry.rename(previous / entry.name)


@contextmanager
def atomic_path(path: str | Path):
    """Yields a temporary path beside ``path``; moved onto ``path`` when the block ends
    normally, deleted when it raises: a reader never sees half a file. A write that fails (a
    full disk) is an OSError naming ``path``, not the temporary file, nor nothing (a failed
    write() names no file)."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp{path.suffix}")
    try:
        yield tmp
        os.replace(tmp, path)
    except OSError as err:
        raise OSError(err.errno, err.strerror, str(path)) from None
    finally:
        tmp.unlink(missing_ok=True)


def write_text(path: str | Path, text: str) -> None:
    with atomic_path(path) as tmp:
        tmp.write_text(text)


def write_json(path: str | Path, data) -> None:
    write_text(path, json.dumps(data, indent=2, allow_nan=False) + "\n")


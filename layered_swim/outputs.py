"""Where commands write: the output folder is checked before any work, and every file appears
whole or not at all.

A folder is fit for a command when it can be created and written, and is empty or holds an
earlier output of the same command (its ``config.json`` names the command; the new files
replace the old ones, and a sweep's cache in it is reused). Anything else is refused in one
line unless ``overwrite`` is given, which empties the folder first: one folder never mixes the
files of two commands.
"""
from __future__ import annotations

import json
import os
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path

from layered_swim.config import ConfigError, load_json

COMMAND_KEY = "command"     # config.json's field naming the command that wrote the folder


def prepare_out_dir(path: str | Path, command: str, overwrite: bool = False) -> Path:
    """``path`` created, writable and ready for ``command`` (see the module's rules)."""
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise ConfigError(f"{out}: exists and is not a folder")
    if out.is_dir() and any(out.iterdir()):
        earlier = _command_of(out)
        if overwrite:
            _empty(out)
        elif earlier != command:
            what = f"the output of `{earlier}`" if earlier else "files that are not a layered-swim output"
            raise ConfigError(f"{out}: holds {what}; choose another --out or add --overwrite to replace them")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise ConfigError(f"{out}: cannot create it ({err.strerror})") from None
    try:
        with tempfile.NamedTemporaryFile(dir=out, prefix=".write-check-"):
            pass
    except OSError as err:
        raise ConfigError(f"{out}: cannot write there ({err.strerror})") from None
    return out


def _command_of(folder: Path) -> str | None:
    try:
        config = load_json(folder / "config.json")
    except ConfigError:        # none, or not ours: the caller says so
        return None
    command = config.get(COMMAND_KEY) if isinstance(config, dict) else None
    return command if isinstance(command, str) else None


def _empty(folder: Path) -> None:
    here = Path.cwd().resolve()
    resolved = folder.resolve()
    if resolved == here or resolved in here.parents or (folder / ".git").exists():
        raise ConfigError(f"{folder}: refusing to empty the working folder, one above it or a repository")
    for entry in folder.iterdir():
        if entry.is_dir() and not entry.is_symlink():
            shutil.rmtree(entry)
        else:
            entry.unlink()


@contextmanager
def atomic_path(path: str | Path):
    """Yields a temporary path beside ``path``; moved onto ``path`` when the block ends
    normally, deleted when it raises: a reader never sees half a file."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp{path.suffix}")
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def write_text(path: str | Path, text: str) -> None:
    with atomic_path(path) as tmp:
        tmp.write_text(text)


def write_json(path: str | Path, data) -> None:
    write_text(path, json.dumps(data, indent=2, allow_nan=False) + "\n")

"""Loading and validating the YAML files people edit.

Every error becomes a one-line ``ConfigError`` that names the file, the field and what was
expected, so the CLI can print it and exit non-zero instead of showing a traceback.
"""
from __future__ import annotations

import json
import stat
from pathlib import Path
from typing import Annotated, Any, TypeVar

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError


class ConfigError(Exception):
    """A file people edit is missing, malformed or out of range."""


class Strict(BaseModel):
    """Base for file schemas: unknown fields, NaN and infinities are errors."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


def between(low: float, high: float, above: bool = False):
    """A float people edit with its physical bounds: ``low`` (excluded with ``above``) to ``high``.
    Every number in a file people edit has both, so a typo like 1e308 is an error, not a run."""
    return Annotated[float, Field(gt=low, le=high) if above else Field(ge=low, le=high)]


Degrees = between(-360.0, 360.0)
Coordinate_m = between(-1e4, 1e4)        # anywhere in a 20 km square


class Point2(Strict):
    """A horizontal point in a file (a curve's centre, a vortex's), metres."""
    x: Coordinate_m
    y: Coordinate_m


class Vec3(Strict):
    """A body-scale vector (axes, offsets, sizes in m)."""

    x: between(-10.0, 10.0)
    y: between(-10.0, 10.0)
    z: between(-10.0, 10.0)

    def as_tuple(self) -> tuple[float, float, float]:
        return (self.x, self.y, self.z)


Model = TypeVar("Model", bound=BaseModel)


MAX_TEXT_BYTES = 16 * 2**20      # a stroke, trajectory, config or summary file is kilobytes


def check_regular_file(path: str | Path, max_bytes: int) -> Path:
    """``path`` if it is a regular file of at most ``max_bytes``; else one ConfigError. Checked
    with stat before any open: opening a FIFO blocks, and /dev/zero never ends."""
    path = Path(path)
    try:
        info = path.stat()
    except FileNotFoundError:
        raise ConfigError(f"{path}: file not found") from None
    except OSError as err:
        raise ConfigError(f"{path}: cannot read ({err.strerror})") from None
    if stat.S_ISDIR(info.st_mode):
        raise ConfigError(f"{path}: is a folder, not a file")
    if not stat.S_ISREG(info.st_mode):
        raise ConfigError(f"{path}: not a regular file (a pipe, device or socket); refusing to read it")
    if info.st_size > max_bytes:
        raise ConfigError(f"{path}: {info.st_size} bytes, more than the {max_bytes} this file may have")
    return path


def read_bytes(path: str | Path, max_bytes: int = MAX_TEXT_BYTES) -> bytes:
    """A regular file's bytes, at most ``max_bytes`` (see ``check_regular_file``)."""
    path = check_regular_file(path, max_bytes)
    try:
        with open(path, "rb") as f:
            data = f.read(max_bytes + 1)     # the file may have grown since the stat
    except OSError as err:
        raise ConfigError(f"{path}: cannot read ({err.strerror})") from None
    if len(data) > max_bytes:
        raise ConfigError(f"{path}: more than the {max_bytes} bytes this file may have")
    return data


def read_text(path: str | Path, max_bytes: int = MAX_TEXT_BYTES) -> str:
    """A text file people edit or a run wrote, as UTF-8; any failure is one ConfigError."""
    data = read_bytes(path, max_bytes)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise ConfigError(f"{path}: not UTF-8 text (byte {err.start})") from None


def load_json(path: str | Path) -> Any:
    text = read_text(path)
    try:
        return json.loads(text)
    except ValueError as err:
        raise ConfigError(f"{path}: not valid JSON ({err.msg if hasattr(err, 'msg') else err})") from None


def load_yaml(path: str | Path) -> Any:
    path = Path(path)
    text = read_text(path)
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f" line {mark.line + 1}" if mark is not None else ""
        problem = getattr(err, "problem", None) or "invalid YAML"
        raise ConfigError(f"{path}:{where}: {problem}") from None


def parse(model: type[Model], data: Any, source: str | Path) -> Model:
    """Validate ``data`` against ``model``; the first problem becomes a one-line ConfigError."""
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: expected a mapping at the top level, got {type(data).__name__}")
    try:
        return model.model_validate(data)
    except ValidationError as err:
        first = err.errors()[0]
        field = ".".join(str(part) for part in first["loc"]) or "(top level)"
        raise ConfigError(f"{source}: field '{field}': {first['msg']}") from None


def load(model: type[Model], path: str | Path) -> Model:
    return parse(model, load_yaml(path), path)


SHIPPED_DIR = Path(__file__).resolve().parent / "shipped"     # the package's strokes/, trajectories/, waters/


def search_dirs(kind: str) -> tuple[Path, ...]:
    """Where a bare ``kind`` name (``strokes``, ``trajectories``) is looked up: the working
    folder's own ``kind/`` first (a user's files), then the ones shipped with the package."""
    own, shipped = Path(kind), SHIPPED_DIR / kind
    return (shipped,) if not own.is_dir() or own.resolve() == shipped.resolve() else (own, shipped)


def available_files(directories: Path | tuple[Path, ...]) -> list[str]:
    """The bare names of the YAML files in ``directories``."""
    directories = (directories,) if isinstance(directories, Path) else directories
    return sorted({p.stem for directory in directories for p in directory.glob("*.yaml")})


def file_path(name_or_path: str | Path, directories: Path | tuple[Path, ...], kind: str) -> Path:
    """A ``kind`` file (stroke, trajectory) by path (anything ending in .yaml/.yml) or by bare
    name in the first of ``directories`` that has it; an unknown name is an error listing the
    known ones."""
    candidate = Path(name_or_path)
    if candidate.suffix in (".yaml", ".yml"):
        return candidate
    directories = (directories,) if isinstance(directories, Path) else directories
    for directory in directories:
        path = directory / f"{name_or_path}.yaml"
        if path.exists():
            return path
    raise ConfigError(f"unknown {kind} '{name_or_path}' (available: {', '.join(available_files(directories))})")

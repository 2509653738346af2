"""Reading files of tensors someone may have handed over (policies, checkpoints): torch's safe
unpickler only, after a regular-file and size check, and every value checked against what it
must be before use. Each failure is one ConfigError line naming the file."""
from __future__ import annotations

import math
from pathlib import Path

import torch

from layered_swim.config import ConfigError, check_regular_file


def read_weights(path: str | Path, max_bytes: int, refusal: str):
    """``path`` through torch's safe unpickler (tensors, containers, numbers, strings: a file
    someone hands over cannot run their code), after ``check_regular_file`` (a pipe or /dev/zero
    is refused, not read forever). Any failure is one line: ``refusal`` with ``{kind}``, the
    error's name, filled in."""
    check_regular_file(path, max_bytes)
    try:
        return torch.load(path, map_location="cpu", weights_only=True)
    except Exception as err:      # noqa: BLE001  a damaged or foreign file: one line
        raise ConfigError(f"{path}: " + refusal.format(kind=type(err).__name__)) from None


def check_keys(data, keys, what: str, source) -> dict:
    """``data`` if it is a mapping of exactly ``keys`` (names of ours: safe to print)."""
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: {what} must be a mapping")
    missing = [k for k in keys if k not in data]
    if missing:
        raise ConfigError(f"{source}: {what} lacks {', '.join(missing)}")
    unknown = len(set(data) - set(keys))
    if unknown:
        raise ConfigError(f"{source}: {what} has {unknown} unknown entries")
    return data


def is_number(value) -> bool:
    """A finite float, or an int a float holds (not a bool, not 10**400)."""
    return (type(value) is float and math.isfinite(value)) or (type(value) is int and abs(value) <= 2**53)


def is_count(value, low: int, high: int) -> bool:
    return type(value) is int and low <= value <= high


def check_tensors(state, like: dict[str, torch.Tensor], what: str, source) -> dict:
    """``state`` if it holds exactly ``like``'s names, each a dense float tensor of the same
    shape whose values stay finite in ``like``'s dtype (float64 weights may overflow float32)."""
    check_keys(state, like, what, source)
    for name, ref in like.items():
        value = state[name]
        if not (isinstance(value, torch.Tensor) and value.layout == torch.strided and value.dtype.is_floating_point):
            raise ConfigError(f"{source}: {what} {name} must be a float tensor")
        if value.shape != ref.shape:
            raise ConfigError(f"{source}: {what} {name} has shape {list(value.shape)}, expected {list(ref.shape)}")
        if not torch.isfinite(value.detach().to(ref.dtype)).all():
            raise ConfigError(f"{source}: {what} {name} holds NaN or infinite values")
    return state


def check_normaliser(state, size: int, source) -> dict:
    """``state`` if it is a ``Normaliser``'s for ``size`` observations: finite means, variances
    not below 0, a positive count."""
    check_keys(state, ("mean", "var", "count"), "normaliser", source)
    for name in ("mean", "var"):
        values = state[name]
        if not (isinstance(values, list) and len(values) == size and all(is_number(v) for v in values)):
            raise ConfigError(f"{source}: normaliser {name} must be {size} finite numbers")
    if min(state["var"]) < 0 or not (is_number(state["count"]) and state["count"] > 0):
        raise ConfigError(f"{source}: normaliser variances must be at least 0 and its count positive")
    return state

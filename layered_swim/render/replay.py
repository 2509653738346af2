"""Frames from a finished headless run: its ``log.npz`` (and ``track.npz`` for a ``follow`` run)
read back as a ``Scene`` at any time."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from layered_swim.body.model import load_body
from layered_swim.config import ConfigError, check_regular_file, load_json
from layered_swim.recorder import MAX_LOG_BYTES, UNREADABLE_ARCHIVE, read_log
from layered_swim.render.scene import Scene

TRAIL_SECONDS = 60.0


class LogReplay:
    def __init__(self, run_dir: str | Path):
        run_dir = Path(run_dir)
        log = read_log(run_dir)
        self.time_s = log["time_s"]
        self.segment_pos_m = log["segment_pos_m"]
        self.segment_quat_xyzw = log["segment_quat_xyzw"]
        self.fluid_force_n = np.nan_to_num(log["fluid_force_n"])     # a blow-up's last row: draw no arrows
        self.com_pos_m = log["com_pos_m"]
        self.partial = bool(log["partial"])
        names = tuple(str(n) for n in log["segment_names"])
        body = load_body()
        if names != tuple(body.segment_names):
            raise ConfigError(f"{run_dir}: its log's segments {names} are not this body's {tuple(body.segment_names)}")
        self.segment_names, self.half_extents_m = names, body.half_extents_m
        self.target_time_s = self.target_m = None
        track_path = run_dir / "track.npz"
        if track_path.exists():
            self.target_time_s, self.target_m = _track(track_path)
        self.current_m_s = _current(run_dir / "config.json")

    @property
    def duration_s(self) -> float:
        return float(self.time_s[-1])

    def scene(self, time_s: float) -> Scene:
        i = max(0, int(np.searchsorted(self.time_s, time_s, side="right")) - 1)
        first = int(np.searchsorted(self.time_s, self.time_s[i] - TRAIL_SECONDS))
        stride = max(1, int(round(0.1 / max(1e-9, self.time_s[1] - self.time_s[0])))) if len(self.time_s) > 1 else 1
        target = None
        if self.target_m is not None:
            j = max(0, int(np.searchsorted(self.target_time_s, time_s, side="right")) - 1)
            target = self.target_m[j]
        return Scene(self.segment_names, self.half_extents_m, self.segment_pos_m[i], self.segment_quat_xyzw[i],
                     target, None, self.com_pos_m[first:i + 1:stride], self.fluid_force_n[i], self.current_m_s)


def _track(path: Path) -> tuple[np.ndarray, np.ndarray]:
    check_regular_file(path, MAX_LOG_BYTES)
    try:
        with np.load(path, allow_pickle=False) as track:
            time_s, target_m = track["track_time_s"], track["target_m"]
    except UNREADABLE_ARCHIVE as err:
        raise ConfigError(f"{path}: not a readable target track ({type(err).__name__})") from None
    if time_s.ndim != 1 or target_m.shape != (len(time_s), 3) or not np.isfinite(target_m).all():
        raise ConfigError(f"{path}: expected track_time_s (n,) and finite target_m (n, 3)")
    return time_s, target_m


def _current(config_path: Path) -> np.ndarray:
    """The run's current: ``follow`` writes it at the top level, ``run`` inside its medium."""
    if not config_path.exists():
        return np.zeros(3)
    config = load_json(config_path)
    if not isinstance(config, dict):
        raise ConfigError(f"{config_path}: not a run's configuration (expected a mapping, got {type(config).__name__})")
    medium = config.get("medium")
    current = config.get("current_m_s") or (medium.get("current_m_s") if isinstance(medium, dict) else None) or \
        [0.0, 0.0, 0.0]
    try:
        current = np.asarray(current, float)
    except (TypeError, ValueError):
        current = None
    if current is None or current.shape != (3,) or not np.isfinite(current).all():
        raise ConfigError(f"{config_path}: field 'current_m_s' must be three finite numbers")
    return current

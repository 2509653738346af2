"""Frames from a finished headless run: its ``log.npz`` (and ``track.npz`` for a ``follow`` run)
read back as a ``Scene`` at any time."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from layered_swim.render.scene import Scene
from layered_swim.body.model import load_body
from layered_swim.config import ConfigError

TRAIL_SECONDS = 60.0


class LogReplay:
    def __init__(self, run_dir: str | Path):
        run_dir = Path(run_dir)
        log_path = run_dir / "log.npz"
        if not log_path.exists():
            raise ConfigError(f"{run_dir}: no log.npz (a folder written by `layered-swim run` or `follow --out`)")
        with np.load(log_path) as log:
            self.time_s = log["time_s"]
            self.segment_pos_m = log["segment_pos_m"]
            self.segment_quat_xyzw = log["segment_quat_xyzw"]
            self.fluid_force_n = np.nan_to_num(log["fluid_force_n"])     # sample 0 has none yet
            self.com_pos_m = log["com_pos_m"]
            names = tuple(str(n) for n in log["segment_names"])
        body = load_body()
        if names != tuple(body.segment_names):
            raise ConfigError(f"{log_path}: its segments {names} are not this body's {tuple(body.segment_names)}")
        self.segment_names, self.half_extents_m = names, body.half_extents_m
        self.target_time_s = self.target_m = None
        track_path = run_dir / "track.npz"
        if track_path.exists():
            with np.load(track_path) as track:
                self.target_time_s, self.target_m = track["track_time_s"], track["target_m"]
        self.current_m_s = np.asarray(_current(run_dir / "config.json"), float)

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


def _current(config_path: Path) -> list[float]:
    """The run's current: ``follow`` writes it at the top level, ``run`` inside its medium."""
    if not config_path.exists():
        return [0.0, 0.0, 0.0]
    config = json.loads(config_path.read_text())
    return config.get("current_m_s") or config.get("medium", {}).get("current_m_s") or [0.0, 0.0, 0.0]

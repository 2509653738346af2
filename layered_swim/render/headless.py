"""``layered-swim render``: a video or PNG frames of a swim, drawn without a display.

The source is either a finished run's folder (its log is replayed) or a trajectory, which is
swum now with the layered controller. Drawing uses pyglet's headless EGL mode, so the caller
must not have imported pyglet with a display first (the CLI imports it only here).
"""
from __future__ import annotations

import math
import os
from pathlib import Path

from layered_swim.render.camera import OrbitCamera
from layered_swim.render.frames import FrameWriter
from layered_swim.config import ConfigError
from layered_swim.control.layered import Layers
from layered_swim.runs import check_path_in_pool
from layered_swim.sim.simulation import SimulationDiverged

MAX_FRAMES = 20_000


def frame_steps(frame: int, physics_hz: int, fps: float) -> int:
    """Physics steps between frame ``frame`` and the next: exact over a whole run at any fps."""
    return round((frame + 1) * physics_hz / fps) - round(frame * physics_hz / fps)


def render(source: str, out: str | Path, seconds: float | None = None, fps: float = 30.0,
           size_px: tuple[int, int] = (960, 540), stroke: str = "breaststroke", layers: Layers = Layers(),
           current_m_s=(0.0, 0.0, 0.0), density_kg_m3: float | None = None, show_forces: bool = False,
           progress: bool = False, backend: str = "plate", fluid_settings=None, overwrite: bool = False) -> dict:
    if not (math.isfinite(fps) and 1 <= fps <= 120):
        raise ConfigError(f"--fps must be between 1 and 120, got {fps}")
    width, height = size_px
    if seconds is not None and not (math.isfinite(seconds) and 0 < seconds <= 3600):
        raise ConfigError(f"--seconds must be in (0, 3600], got {seconds}")
    frames = _frames(source, seconds, fps, stroke, layers, current_m_s, density_kg_m3, backend, fluid_settings)
    count, total = next(frames)      # the source read and checked before anything is written
    os.environ["PYGLET_HEADLESS"] = "1"
    import pyglet
    pyglet.options["headless"] = True
    from layered_swim.render.renderer import Renderer, gl_config, read_pixels

    window = pyglet.window.Window(width, height, visible=False, config=gl_config())
    try:
        writer = FrameWriter(out, fps, overwrite)
    except BaseException:
        window.close()
        frames.close()
        raise
    try:
        renderer = Renderer(count)
        camera = OrbitCamera(distance_m=5.5)
        iterator = range(total)
        if progress:
            from tqdm import tqdm
            iterator = tqdm(iterator, desc="frames", unit="frame", leave=False)
        for _ in iterator:
            scene = next(frames)
            camera.follow(scene.centre_of_segments_m, 1.0 / fps)
            renderer.draw(scene, camera, width, height, show_forces=show_forces)
            writer.add(read_pixels(width, height))
        renderer.delete()
    except BaseException:
        writer.abort()
        raise
    finally:
        window.close()
    path = writer.close()
    return {"out": str(path), "frames": writer.frames, "fps": fps, "video": writer.is_video, "note": writer.note}


def _frames(source, seconds, fps, stroke, layers, current_m_s, density_kg_m3, backend, fluid_settings):
    """Yields (segment names, frame count) first, then one Scene per frame."""
    path = Path(source)
    if path.is_dir():
        from layered_swim.render.replay import LogReplay
        replay = LogReplay(path)
        duration = replay.duration_s if seconds is None else min(seconds, replay.duration_s)
        total = _count(duration, fps)
        yield replay.segment_names, total
        for k in range(total):
            yield replay.scene(k / fps)
        return
    from layered_swim.render.session import SwimSession
    from layered_swim.control.targets import trajectory_path
    try:
        trajectory_path(source)
    except ConfigError as err:
        raise ConfigError(f"{source}: neither a run folder nor a trajectory ({err})") from None
    session = SwimSession(stroke, layers, current_m_s, density_kg_m3, trajectory=source, backend=backend,
                          fluid_settings=fluid_settings)
    duration_s = 20.0 if seconds is None else seconds
    total = _count(duration_s, fps)
    try:
        check_path_in_pool(session.episode, session.target, duration_s)
        yield session.sim.body.segment_names, total
        for k in range(total):
            yield session.scene()
            session.step(frame_steps(k, session.physics_hz, fps))
            if session.diverged:
                raise SimulationDiverged(session.divergence)
    finally:
        session.close()


def _count(duration_s: float, fps: float) -> int:
    total = int(math.floor(duration_s * fps)) + 1
    if total > MAX_FRAMES:
        raise ConfigError(f"{total} frames is more than {MAX_FRAMES}; shorten --seconds or lower --fps")
    return total

"""``layered-swim render``: a video, PNG frames or one still PNG of a swim, drawn without a display.

The source is either a finished run's folder (its log is replayed) or a trajectory, which is
swum now with the layered controller. Drawing uses pyglet's headless EGL mode, so the caller
must not have imported pyglet with a display first (the CLI imports it only here).
"""
from __future__ import annotations

import math
import os
from pathlib import Path

from layered_swim.config import ConfigError
from layered_swim.control.layered import Layers
from layered_swim.render.camera import VIEWS, OrbitCamera
from layered_swim.render.frames import FrameWriter, check_png_out, save_png
from layered_swim.runs import check_path_in_pool
from layered_swim.sim.simulation import SimulationDiverged

MAX_FRAMES = 20_000
MAX_SECONDS = 3600.0


def steps_between(start_s: float, end_s: float, physics_hz: int) -> int:
    """Physics steps from one frame's time to the next: they add up exactly over a whole run."""
    return round(end_s * physics_hz) - round(start_s * physics_hz)


def render(source: str, out: str | Path, seconds: float | None = None, fps: float = 30.0,
           size_px: tuple[int, int] = (960, 540), stroke: str = "breaststroke", layers: Layers = Layers(),
           current_m_s=(0.0, 0.0, 0.0), density_kg_m3: float | None = None, show_forces: bool = False,
           progress: bool = False, backend: str = "plate", fluid_settings=None, overwrite: bool = False,
           camera: str = "follow", show_flow: bool = False, frame_s: float | None = None,
           water: str | None = None) -> dict:
    """Every frame of the swim into ``out``; with ``frame_s``, the one moment ``frame_s`` seconds
    in as a PNG (the camera still eases in over the frames before it, as in the video)."""
    if not (math.isfinite(fps) and 1 <= fps <= 120):
        raise ConfigError(f"--fps must be between 1 and 120, got {fps}")
    width, height = size_px
    if seconds is not None and not (math.isfinite(seconds) and 0 < seconds <= MAX_SECONDS):
        raise ConfigError(f"--seconds must be in (0, {MAX_SECONDS:g}], got {seconds}")
    if camera not in VIEWS:
        raise ConfigError(f"--camera must be one of {', '.join(VIEWS)}, got {camera!r}")
    if frame_s is not None:
        if not (math.isfinite(frame_s) and 0 <= frame_s <= (MAX_SECONDS if seconds is None else seconds)):
            raise ConfigError(f"--frame must be in [0, {MAX_SECONDS if seconds is None else seconds:g}] seconds, "
                              f"got {frame_s}")
        if Path(out).suffix.lower() != ".png":
            raise ConfigError(f"--frame writes one picture: --out must name a .png file, got {out}")
    frames = _frames(source, seconds, fps, frame_s, stroke, layers, current_m_s, density_kg_m3, backend,
                     fluid_settings, water)
    names, times = next(frames)      # the source read and checked before anything is written
    os.environ["PYGLET_HEADLESS"] = "1"
    import pyglet
    pyglet.options["headless"] = True
    from layered_swim.render.renderer import Renderer, gl_config, read_pixels

    window = pyglet.window.Window(width, height, visible=False, config=gl_config())
    try:
        if frame_s is None:
            writer = FrameWriter(out, fps, overwrite)
        else:
            check_png_out(Path(out), overwrite)
    except BaseException:
        window.close()
        frames.close()
        raise
    try:
        renderer = Renderer(names)
        orbit = None
        iterator = times
        if progress:
            from tqdm import tqdm
            iterator = tqdm(iterator, desc="frames", unit="frame", leave=False)
        for k, time_s in enumerate(iterator):
            scene = next(frames)
            if orbit is None:
                orbit = OrbitCamera(focus_m=scene.centre_of_segments_m * [1.0, 1.0, 0.0])
                orbit.set_view(camera)
            orbit.follow(scene.centre_of_segments_m, time_s - times[k - 1] if k else 0.0)
            if frame_s is None or k == len(times) - 1:
                renderer.draw(scene, orbit, width, height, show_forces=show_forces, show_flow=show_flow,
                              time_s=time_s)
                pixels = read_pixels(width, height)
                if frame_s is None:
                    writer.add(pixels)
        renderer.delete()
    except BaseException:
        if frame_s is None:
            writer.abort()
        raise
    finally:
        window.close()
    if frame_s is not None:
        return {"out": str(save_png(pixels, Path(out))), "frames": 1, "fps": fps, "video": False, "note": ""}
    path = writer.close()
    return {"out": str(path), "frames": writer.frames, "fps": fps, "video": writer.is_video, "note": writer.note}


def _times(duration_s: float, fps: float, frame_s: float | None) -> list[float]:
    """Every frame's time; for a still, the frames up to it (for the camera to ease in) and it."""
    if frame_s is None:
        total = int(math.floor(duration_s * fps)) + 1
        if total > MAX_FRAMES:
            raise ConfigError(f"{total} frames is more than {MAX_FRAMES}; shorten --seconds or lower --fps")
        return [k / fps for k in range(total)]
    if frame_s > duration_s:
        raise ConfigError(f"--frame {frame_s:g} s is past the swim's end ({duration_s:g} s)")
    return [k / fps for k in range(math.ceil(frame_s * fps)) if k / fps < frame_s] + [frame_s]


def _frames(source, seconds, fps, frame_s, stroke, layers, current_m_s, density_kg_m3, backend, fluid_settings,
            water=None):
    """Yields (segment names, frame times) first, then one Scene per time."""
    path = Path(source)
    if path.is_dir():
        if water:
            raise ConfigError("--water swims a trajectory: a run folder replays its own log")
        from layered_swim.render.replay import LogReplay
        replay = LogReplay(path)
        times = _times(replay.duration_s if seconds is None else min(seconds, replay.duration_s), fps, frame_s)
        yield replay.segment_names, times
        for time_s in times:
            yield replay.scene(time_s)
        return
    from layered_swim.control.targets import trajectory_path
    from layered_swim.render.session import SwimSession
    try:
        trajectory_path(source)
    except ConfigError as err:
        raise ConfigError(f"{source}: neither a run folder nor a trajectory ({err})") from None
    duration_s = seconds if seconds is not None else frame_s if frame_s is not None else 20.0
    times = _times(duration_s, fps, frame_s)
    session = SwimSession(stroke, layers, current_m_s, density_kg_m3, trajectory=source, backend=backend,
                          fluid_settings=fluid_settings, water=water)
    try:
        check_path_in_pool(session.episode, session.target, duration_s)
        yield session.sim.body.segment_names, times
        for k, time_s in enumerate(times):
            session.step(steps_between(times[k - 1] if k else 0.0, time_s, session.physics_hz))
            if session.diverged:
                raise SimulationDiverged(session.divergence)
            yield session.scene()
    finally:
        session.close()

"""The interactive window (pyglet 2): the swimmer chases the target you click on the water.

Physics runs on its own fixed step inside ``SwimSession.advance``; pyglet's clock only says how
much wall time passed. Import this module only with a display (``app.py`` checks first).
"""
from __future__ import annotations

import math
import time
from collections import deque
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import pyglet
from pyglet.window import key, mouse

from layered_swim.render.camera import OrbitCamera
from layered_swim.render.frames import FrameWriter, save_png
from layered_swim.render.hud import hud_lines
from layered_swim.render.renderer import Renderer, gl_config, read_pixels
from layered_swim.render.session import SwimSession

FRAME_INTERVAL_S = 1.0 / 60.0
VIDEO_FPS = 30.0
HUD_REFRESH_S = 0.2          # re-laying out text is the dear part of a frame: a few times a second is plenty
DEPTH_STEP_M = 0.1
HUD_FONT = ("DejaVu Sans Mono", "Liberation Mono", "Courier New", "monospace")


@dataclass(frozen=True)
class Binding:
    label: str                     # the keys as the help overlay prints them
    description: str
    symbols: tuple[int, ...]
    action: Callable[["SwimWindow", int], None]


def _stroke_by_number(window: "SwimWindow", symbol: int) -> None:
    index = symbol - key._1
    if index < len(window.session.strokes):
        window.session.set_stroke(window.session.strokes[index])


BINDINGS = (
    Binding("H", "show or hide this help", (key.H,), lambda w, s: w.toggle_help()),
    Binding("1-9", "choose the stroke by number (listed below)", tuple(key._1 + i for i in range(9)),
            _stroke_by_number),
    Binding("Tab", "next stroke", (key.TAB,), lambda w, s: w.session.next_stroke()),
    Binding("C", "per-cycle steering layer on/off", (key.C,), lambda w, s: w.session.toggle_layer("cycle")),
    Binding("P", "palm-orientation rule on/off", (key.P,), lambda w, s: w.session.toggle_layer("palm")),
    Binding("A", "arm-reach rule on/off", (key.A,), lambda w, s: w.session.toggle_layer("reach")),
    Binding("U", "next current preset (none, 0.3 m/s cross, 0.5 m/s head-on)", (key.U,),
            lambda w, s: w.session.next_current()),
    Binding("D", "next fluid (fresh water, seawater, light, dense)", (key.D,), lambda w, s: w.session.next_density()),
    Binding("Space", "pause / resume", (key.SPACE,), lambda w, s: w.toggle_pause()),
    Binding("N", "single step (1/60 s) while paused", (key.N,), lambda w, s: w.single_step()),
    Binding("R", "reset the swim", (key.R,), lambda w, s: w.session.reset()),
    Binding("M", "slow motion (quarter speed) on/off", (key.M,), lambda w, s: w.toggle_slow_motion()),
    Binding("F", "fluid-force arrows on/off", (key.F,), lambda w, s: w.toggle_forces()),
    Binding("W", "water flow arrows on/off (the current around, the water at each segment)", (key.W,),
            lambda w, s: w.toggle_flow()),
    Binding("K", "next camera (follow, side at the surface, underwater)", (key.K,), lambda w, s: w.next_camera()),
    Binding("T", "back to the trajectory's target (trajectory mode)", (key.T,), lambda w, s: w.back_to_trajectory()),
    Binding("PgUp/PgDn", "target shallower / deeper (or Shift + wheel)", (key.PAGEUP, key.PAGEDOWN),
            lambda w, s: w.session.change_target_depth(-DEPTH_STEP_M if s == key.PAGEUP else DEPTH_STEP_M)),
    Binding("S", "screenshot (PNG)", (key.S,), lambda w, s: w.request_screenshot()),
    Binding("V", "start / stop video recording (MP4, or PNG frames without an encoder)", (key.V,),
            lambda w, s: w.toggle_recording()),
    Binding("Esc", "quit", (key.ESCAPE,), lambda w, s: w.close()),
)
MOUSE_HELP = ("left click / drag on the water: set the target", "right drag: orbit the camera", "wheel: zoom")


class SwimWindow(pyglet.window.Window):
    def __init__(self, session: SwimSession, width: int = 1280, height: int = 720, capture_dir: Path = Path("captures"),
                 benchmark_frames: int | None = None, visible: bool = True):
        super().__init__(width, height, caption="layered_swim", resizable=True, config=gl_config(), vsync=False,
                         visible=visible)
        self.session = session
        self.capture_dir = Path(capture_dir)
        self.camera = OrbitCamera(focus_m=session.com_m * [1.0, 1.0, 0.0])
        self.renderer = Renderer(session.sim.body.segment_names)
        self.keys = key.KeyStateHandler()
        self.push_handlers(self.keys)
        self.show_help = False
        self.show_forces = False
        self.show_flow = session.flow is not None     # a water file: its flow is what the swim is about
        self._screenshot_pending = False
        self.recorder: FrameWriter | None = None
        self._last_video_frame_s = -math.inf
        self._frame_times: deque = deque()
        self.fps = 0.0
        self.frames = 0
        self.benchmark_frames = benchmark_frames
        self.benchmark: dict | None = None
        self._benchmark_start: tuple[float, float] | None = None
        self._hud_batch = pyglet.graphics.Batch()
        self._hud_box = pyglet.shapes.Rectangle(0, 0, 10, 10, color=(10, 20, 35, 170), batch=self._hud_batch)
        self._hud = pyglet.text.Label("", font_name=HUD_FONT, font_size=11, multiline=True, width=900,
                                      x=12, y=height - 10, anchor_y="top", color=(235, 245, 255, 255),
                                      batch=self._hud_batch)
        self._help_batch = pyglet.graphics.Batch()
        self._help_box = pyglet.shapes.Rectangle(0, 0, 10, 10, color=(10, 20, 35, 215), batch=self._help_batch)
        self._help = pyglet.text.Label(self.help_text(), font_name=HUD_FONT, font_size=11, multiline=True, width=760,
                                       x=width // 2, y=height // 2, anchor_x="center", anchor_y="center",
                                       color=(235, 245, 255, 255), batch=self._help_batch)
        self._hud_updated_s = -math.inf
        self._refresh_hud(force=True)

    # --- the loop ----------------------------------------------------------------------
    def run(self) -> None:
        pyglet.clock.schedule_interval(self.frame, FRAME_INTERVAL_S)
        pyglet.app.run(interval=None)

    def frame(self, dt_s: float) -> None:
        """One frame: advance the physics by the wall time that passed, follow, draw, capture."""
        self.session.advance(dt_s)
        self.camera.follow(self.session.com_m, dt_s)
        now = time.perf_counter()
        self._count_frame(now)
        self._refresh_hud()
        self.switch_to()
        self.draw_frame()
        self._capture(now)
        self.flip()
        if self.benchmark_frames is not None and self.frames >= self.benchmark_frames:
            self._finish_benchmark(now)

    def draw_frame(self) -> None:
        width, height = self.get_framebuffer_size()
        self.renderer.draw(self.session.scene(), self.camera, width, height, show_forces=self.show_forces,
                           show_flow=self.show_flow, time_s=self.session.sim.time_s)
        self._hud_batch.draw()
        if self.show_help:
            self._help_batch.draw()

    def pixels(self):
        """The frame just drawn, (h, w, 3) uint8, top row first."""
        return read_pixels(*self.get_framebuffer_size())

    def _count_frame(self, now: float) -> None:
        self.frames += 1
        if self.frames == 2:      # the first frame carries start-up costs
            self._benchmark_start = (now, self.session.sim.time_s)
        self._frame_times.append(now)
        while len(self._frame_times) > 2 and now - self._frame_times[0] > 1.0:
            self._frame_times.popleft()
        if len(self._frame_times) > 1:
            self.fps = (len(self._frame_times) - 1) / (self._frame_times[-1] - self._frame_times[0])

    def _finish_benchmark(self, now: float) -> None:
        start_s, start_sim_s = self._benchmark_start
        wall_s = max(1e-9, now - start_s)
        self.benchmark = {"frames": self.frames - 2, "mean_fps": (self.frames - 2) / wall_s,
                          "realtime_factor": (self.session.sim.time_s - start_sim_s) / wall_s}
        self.close()
        pyglet.app.exit()

    def _refresh_hud(self, force: bool = False) -> None:
        now = time.perf_counter()
        if not force and now - self._hud_updated_s < HUD_REFRESH_S:
            return
        self._hud_updated_s = now
        recording = f"{self.recorder.frames} frames, {self.recorder.note}" if self.recorder else ""
        self._hud.text = "\n".join(hud_lines(self.session, self.fps, recording))
        self._hud.y = self.height - 10
        self._hud_box.x, self._hud_box.y = 4, self.height - self._hud.content_height - 18
        self._hud_box.width, self._hud_box.height = (min(self.width - 8, self._hud.content_width + 16),
                                                     self._hud.content_height + 14)

    def help_text(self) -> str:
        strokes = ", ".join(f"{i + 1} {name}" for i, name in enumerate(self.session.strokes[:9]))
        lines = [f"{b.label:<10} {b.description}" for b in BINDINGS]
        return "\n".join(["KEYS", *lines, f"{'':<10} strokes: {strokes}", "", "MOUSE", *MOUSE_HELP])

    # --- actions -----------------------------------------------------------------------
    def toggle_help(self) -> None:
        self.show_help = not self.show_help

    def toggle_pause(self) -> None:
        self.session.paused = not self.session.paused

    def toggle_slow_motion(self) -> None:
        self.session.slow_motion = not self.session.slow_motion

    def toggle_forces(self) -> None:
        self.show_forces = not self.show_forces

    def toggle_flow(self) -> None:
        self.show_flow = not self.show_flow

    def next_camera(self) -> None:
        self.session.message = f"camera: {self.camera.next_view()}"

    def single_step(self) -> None:
        if self.session.paused:
            self.session.step(round(self.session.physics_hz * FRAME_INTERVAL_S))

    def back_to_trajectory(self) -> None:
        if self.session.target.trajectory is not None:
            self.session.target.scripted = True

    def request_screenshot(self) -> None:
        self._screenshot_pending = True

    def toggle_recording(self) -> None:
        if self.recorder is None:
            self.recorder = FrameWriter(self.capture_dir / f"swim-{time.strftime('%Y%m%d-%H%M%S')}.mp4", VIDEO_FPS)
            self.session.message = self.recorder.note
        else:
            path = self.recorder.close()
            self.session.message = f"saved {self.recorder.frames} frames to {path}"
            self.recorder = None
        self._refresh_hud(force=True)

    def _capture(self, now: float) -> None:
        want_video = self.recorder is not None and now - self._last_video_frame_s >= 1.0 / VIDEO_FPS - 1e-3
        if not (self._screenshot_pending or want_video):
            return
        pixels = self.pixels()
        if self._screenshot_pending:
            self._screenshot_pending = False
            path = save_png(pixels, self.capture_dir / f"swim-{time.strftime('%Y%m%d-%H%M%S')}-{self.frames}.png")
            self.session.message = f"screenshot saved to {path}"
            self._refresh_hud(force=True)
        if want_video:
            self._last_video_frame_s = now
            self.recorder.add(pixels)

    # --- events ------------------------------------------------------------------------
    def on_key_press(self, symbol: int, modifiers: int) -> bool | None:
        for binding in BINDINGS:
            if symbol in binding.symbols:
                binding.action(self, symbol)
                self._refresh_hud(force=True)
                return pyglet.event.EVENT_HANDLED
        return None

    def on_mouse_press(self, x: int, y: int, button: int, modifiers: int) -> None:
        if button == mouse.LEFT:
            self._target_at(x, y)

    def on_mouse_drag(self, x: int, y: int, dx: int, dy: int, buttons: int, modifiers: int) -> None:
        if buttons & mouse.LEFT:
            self._target_at(x, y)
        elif buttons & mouse.RIGHT:
            self.camera.orbit(dx, dy)

    def on_mouse_scroll(self, x: int, y: int, scroll_x: float, scroll_y: float) -> None:
        if self.keys[key.LSHIFT] or self.keys[key.RSHIFT]:
            self.session.change_target_depth(-DEPTH_STEP_M * scroll_y)
        else:
            self.camera.zoom(scroll_y)

    def _target_at(self, x: int, y: int) -> None:
        point = self.camera.water_point(x, y, self.width, self.height)
        if point is not None:
            self.session.set_target(point)

    def on_resize(self, width: int, height: int) -> None:
        super().on_resize(width, height)
        self._help.x, self._help.y = width // 2, height // 2
        self._help_box.width, self._help_box.height = self._help.width + 30, self._help.content_height + 30
        self._help_box.x = width // 2 - self._help_box.width // 2
        self._help_box.y = height // 2 - self._help_box.height // 2
        self._refresh_hud(force=True)

    def on_draw(self) -> None:
        self.draw_frame()

    def close(self) -> None:
        if self.recorder is not None:
            self.recorder.close()
            self.recorder = None
        pyglet.clock.unschedule(self.frame)
        if self.context is not None:
            self.switch_to()
            self.renderer.delete()
        self.session.close()
        super().close()

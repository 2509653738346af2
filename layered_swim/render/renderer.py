"""Draws a ``Scene`` with OpenGL 3.3 shaders (pyglet 2): the swimmer's boxes, the water (its
surface, what it does to the look of everything under it, its deep floor and grid), the target,
paths, the trail, force and flow arrows. Needs a current GL context (a window, or pyglet's
headless EGL surface); ``read_pixels`` gives the frame back as an array.
"""
from __future__ import annotations

import numpy as np
from pyglet import gl
from pyglet.graphics.shader import Shader, ShaderProgram

from layered_swim.render import scene as sc
from layered_swim.render import shaders
from layered_swim.render.camera import OrbitCamera, gl_matrix

LIGHT_DIR = np.array([0.35, -0.45, 0.82]) / np.linalg.norm([0.35, -0.45, 0.82])
WATER_HALF_SIZE_M = 120.0
# Water takes red first: its first decimetres leave this of each channel, and each metre beyond
# keeps exp(-extinction) (far clearer than a tint alone, so a swimmer metres away stays in sight).
WATER_TINT = (0.5, 0.82, 0.95)
EXTINCTION_PER_M = (0.12, 0.05, 0.035)
FLOOR_BELOW_GRID_M = 0.05      # the grid's lines lie on the floor without fighting it for depth
MAX_LINE_VERTICES = 8192


class Renderer:
    def __init__(self, segment_names: tuple[str, ...]):
        self.program = ShaderProgram(Shader(shaders.VERTEX, "vertex"), Shader(shaders.FRAGMENT, "fragment"))
        n = len(segment_names)
        box_colors = np.repeat(sc.segment_colors(segment_names), sc.BOX_VERTICES, axis=0)
        self._boxes = self._list(n * sc.BOX_VERTICES, gl.GL_TRIANGLES, box_colors)
        self._marker = self._list(sc.MARKER_VERTICES, gl.GL_TRIANGLES,
                                  np.tile(sc.TARGET_COLOR, (sc.MARKER_VERTICES, 1)))
        self._surface = self._list(6, gl.GL_TRIANGLES, np.tile(sc.SURFACE_COLOR, (6, 1)))
        self._floor = self._list(6, gl.GL_TRIANGLES, np.tile(sc.FLOOR_COLOR, (6, 1)))
        self._grid = _Lines(self._list(MAX_LINE_VERTICES, gl.GL_LINES, np.zeros((MAX_LINE_VERTICES, 4))))
        self._guides = _Lines(self._list(MAX_LINE_VERTICES, gl.GL_LINES, np.zeros((MAX_LINE_VERTICES, 4))))
        self._particles = None        # GL_POINTS, sized on the first frame that has water particles

    def _list(self, count: int, mode: int, colors: np.ndarray):
        return self.program.vertex_list(count, mode, position=("f", np.zeros(3 * count).tolist()),
                                        normal=("f", np.tile([0.0, 0.0, 1.0], count).tolist()),
                                        color=("f", np.asarray(colors, float).reshape(-1).tolist()))

    def draw(self, scene: sc.Scene, camera: OrbitCamera, width_px: int, height_px: int,
             show_forces: bool = False, show_current: bool = True, show_flow: bool = False,
             time_s: float = 0.0) -> None:
        eye = camera.eye_m
        gl.glViewport(0, 0, width_px, height_px)
        gl.glClearColor(*(sc.SKY_COLOR if eye[2] >= 0 else sc.DEEP_COLOR))
        gl.glClear(gl.GL_COLOR_BUFFER_BIT | gl.GL_DEPTH_BUFFER_BIT)
        gl.glEnable(gl.GL_DEPTH_TEST)
        gl.glEnable(gl.GL_BLEND)
        gl.glBlendFunc(gl.GL_SRC_ALPHA, gl.GL_ONE_MINUS_SRC_ALPHA)
        p = self.program
        p.use()
        p["view_proj"] = gl_matrix(camera.view_projection(width_px, height_px))
        p["light_dir"] = tuple(LIGHT_DIR)
        p["eye"] = tuple(eye)
        p["sky"] = sc.SKY_COLOR
        p["deep"] = sc.DEEP_COLOR[:3]
        p["tint"] = WATER_TINT
        p["extinction"] = EXTINCTION_PER_M
        p["time_s"] = float(time_s)

        # What is solid first, so the surface after it veils exactly what lies beyond it.
        self._kind(shaders.BODY, lit=1.0)
        vertices, normals = sc.box_triangles(scene.segment_pos_m, scene.segment_quat_xyzw, scene.half_extents_m)
        self._boxes.position[:] = vertices.reshape(-1).tolist()
        self._boxes.normal[:] = normals.reshape(-1).tolist()
        self._boxes.draw(gl.GL_TRIANGLES)
        self._kind(shaders.PLAIN, lit=0.0)
        floor_m = sc.square(camera.focus_m, WATER_HALF_SIZE_M, -sc.GRID_DEPTH_M - FLOOR_BELOW_GRID_M)
        self._floor.position[:] = floor_m.reshape(-1).tolist()
        self._floor.draw(gl.GL_TRIANGLES)
        self._grid.draw([(sc.grid_lines(camera.focus_m), sc.GRID_COLOR)])

        # The surface: alpha stays 1 in the framebuffer so screenshots are not washed out, and
        # depth is not written so what follows draws on top. Edge-on (the side view) it vanishes.
        self._kind(shaders.SURFACE, lit=0.0)
        self._surface.position[:] = sc.square(camera.focus_m, WATER_HALF_SIZE_M, 0.0).reshape(-1).tolist()
        gl.glColorMask(gl.GL_TRUE, gl.GL_TRUE, gl.GL_TRUE, gl.GL_FALSE)
        gl.glDepthMask(gl.GL_FALSE)
        self._surface.draw(gl.GL_TRIANGLES)
        gl.glDepthMask(gl.GL_TRUE)
        gl.glColorMask(gl.GL_TRUE, gl.GL_TRUE, gl.GL_TRUE, gl.GL_TRUE)

        # Guides stay vivid whatever their depth: the particles, the target, its path, the trail,
        # the arrows.
        if scene.particles_m is not None:
            self._draw_particles(scene.particles_m, scene.particle_speed_m_s)
        if scene.target_m is not None:
            self._kind(shaders.GUIDE, lit=1.0)
            vertices, normals = sc.marker_triangles(scene.target_m)
            self._marker.position[:] = vertices.reshape(-1).tolist()
            self._marker.normal[:] = normals.reshape(-1).tolist()
            self._marker.draw(gl.GL_TRIANGLES)
        self._kind(shaders.GUIDE, lit=0.0)
        self._guides.draw(self._guide_lines(scene, show_forces, show_current, show_flow))
        p.stop()
        gl.glDisable(gl.GL_DEPTH_TEST)

    def _kind(self, kind: int, lit: float) -> None:
        self.program["kind"] = kind
        self.program["lit"] = lit

    @staticmethod
    def _guide_lines(scene: sc.Scene, show_forces: bool, show_current: bool, show_flow: bool):
        groups = []
        if scene.path_m is not None:
            groups.append((sc.polyline_lines(scene.path_m), sc.PATH_COLOR))
        if scene.target_m is not None:
            t = scene.target_m
            groups.append((np.array([[t[0], t[1], 0.0], t, t, [t[0], t[1], -sc.GRID_DEPTH_M]]), sc.TARGET_COLOR))
        if scene.trail_m is not None:
            groups.append((sc.polyline_lines(scene.trail_m), sc.TRAIL_COLOR))
        if show_forces and scene.forces_n is not None:
            groups.append((sc.arrow_lines(scene.segment_pos_m, sc.FORCE_SCALE_M_PER_N * scene.forces_n),
                           sc.FORCE_COLOR))
        current = np.zeros(3) if scene.current_m_s is None else np.asarray(scene.current_m_s, float)
        if show_current and np.linalg.norm(current) > 0:
            start = scene.centre_of_segments_m + np.array([0.0, 0.0, 1.2])
            groups.append((sc.arrow_lines(start, sc.CURRENT_SCALE_M_PER_M_S * current), sc.CURRENT_COLOR))
        if show_flow:
            groups.extend(_flow_lines(scene, current))
        return groups

    def _draw_particles(self, positions_m: np.ndarray, speeds_m_s: np.ndarray) -> None:
        """The SPH water as points coloured by speed (still blue to fast white), unlit."""
        count = len(positions_m)
        if self._particles is None or self._particles[1] < count:
            if self._particles is not None:
                self._particles[0].delete()
            self._particles = (self._list(count, gl.GL_POINTS, np.zeros((count, 4))), count)
        points, capacity = self._particles
        positions = np.zeros((capacity, 3))
        positions[:count] = positions_m
        colors = np.zeros((capacity, 4))
        colors[:count] = sc.speed_colors(speeds_m_s)
        points.position[:] = positions.reshape(-1).tolist()
        points.color[:] = colors.reshape(-1).tolist()
        self._kind(shaders.GUIDE, lit=0.0)
        gl.glPointSize(3.0)
        gl.glDepthMask(gl.GL_FALSE)       # translucent: what lies behind still draws
        points.draw(gl.GL_POINTS)
        gl.glDepthMask(gl.GL_TRUE)

    def delete(self) -> None:
        for vertex_list in (self._boxes, self._marker, self._surface, self._floor, self._grid.vertices,
                            self._guides.vertices):
            vertex_list.delete()
        if self._particles is not None:
            self._particles[0].delete()


def _flow_lines(scene: sc.Scene, current_m_s: np.ndarray) -> list:
    """The water's own motion on a lattice around the swimmer (the current, or a water file's flow
    there; a small cross where the water is still), and the water velocity at each segment where
    the fluid reported it (a live swim, not a log)."""
    lattice = sc.flow_lattice(scene.centre_of_segments_m)
    if scene.water_at is not None:
        groups = [(sc.arrow_lines(lattice, sc.FLOW_SCALE_M_PER_M_S * scene.water_at(lattice)), sc.CURRENT_COLOR)]
    elif np.linalg.norm(current_m_s) > 0:
        groups = [(sc.arrow_lines(lattice, np.tile(sc.FLOW_SCALE_M_PER_M_S * current_m_s, (len(lattice), 1))),
                   sc.CURRENT_COLOR)]
    else:
        groups = [(sc.cross_lines(lattice), sc.CURRENT_COLOR)]
    if scene.flow_m_s is not None:
        groups.append((sc.arrow_lines(scene.segment_pos_m, sc.FLOW_SCALE_M_PER_M_S * scene.flow_m_s), sc.FLOW_COLOR))
    return groups


class _Lines:
    """A fixed-capacity GL_LINES vertex list refilled each frame with groups of (endpoints, colour)."""

    def __init__(self, vertices):
        self.vertices = vertices
        self.count = 0

    def draw(self, groups) -> None:
        groups = [(g, c) for g, c in groups if len(g)]
        if not groups:
            return
        positions = np.concatenate([g for g, _ in groups])[:MAX_LINE_VERTICES]
        colors = np.concatenate([np.tile(c, (len(g), 1)) for g, c in groups])[:MAX_LINE_VERTICES]
        count = len(positions)
        self.vertices.position[:3 * count] = positions.reshape(-1).tolist()
        self.vertices.color[:4 * count] = colors.reshape(-1).tolist()
        if count < self.count:     # collapse what the last frame drew beyond this one's lines
            self.vertices.position[3 * count:3 * self.count] = [0.0] * (3 * (self.count - count))
        self.count = count
        self.vertices.draw(gl.GL_LINES)


def read_pixels(width_px: int, height_px: int) -> np.ndarray:
    """The current framebuffer as an (h, w, 3) uint8 array, top row first."""
    buffer = (gl.GLubyte * (width_px * height_px * 3))()
    gl.glPixelStorei(gl.GL_PACK_ALIGNMENT, 1)
    gl.glReadPixels(0, 0, width_px, height_px, gl.GL_RGB, gl.GL_UNSIGNED_BYTE, buffer)
    return np.frombuffer(buffer, np.uint8).reshape(height_px, width_px, 3)[::-1].copy()


def gl_config():
    """8-bit RGBA and a 24-bit depth buffer (EGL's default 16-bit colour bands), GL 3.3."""
    return gl.Config(double_buffer=True, depth_size=24, red_size=8, green_size=8, blue_size=8, alpha_size=8,
                     major_version=3, minor_version=3)


"""Draws a ``Scene`` with OpenGL 3.3 shaders (pyglet 2): the swimmer's boxes, the water, the
open-water grid, the target, paths, the trail and force arrows. Needs a current GL context (a
window, or pyglet's headless EGL surface); ``read_pixels`` gives the frame back as an array.
"""
from __future__ import annotations

import numpy as np
from pyglet import gl
from pyglet.graphics.shader import Shader, ShaderProgram

from layered_swim.render import scene as sc
from layered_swim.render.camera import OrbitCamera, gl_matrix

VERTEX_SHADER = """#version 330 core
in vec3 position;
in vec3 normal;
in vec4 color;
uniform mat4 view_proj;
out vec3 v_normal;
out vec4 v_color;
out vec3 v_world;
void main() {
    gl_Position = view_proj * vec4(position, 1.0);
    v_normal = normal;
    v_color = color;
    v_world = position;
}
"""

FRAGMENT_SHADER = """#version 330 core
in vec3 v_normal;
in vec4 v_color;
in vec3 v_world;
uniform float lit;
uniform vec3 light_dir;
uniform vec3 eye;
uniform vec4 sky;
out vec4 frag;
void main() {
    float diffuse = max(dot(normalize(v_normal), light_dir), 0.0);
    float shade = mix(1.0, 0.4 + 0.6 * diffuse, lit);
    // Far things fade into the sky colour: a horizon instead of a hard grid edge.
    float fog = clamp((distance(v_world, eye) - 25.0) / 60.0, 0.0, 1.0);
    frag = vec4(mix(v_color.rgb * shade, sky.rgb, fog), v_color.a);
}
"""

LIGHT_DIR = np.array([0.35, -0.45, 0.82]) / np.linalg.norm([0.35, -0.45, 0.82])
WATER_HALF_SIZE_M = 120.0
MAX_LINE_VERTICES = 8192


class Renderer:
    def __init__(self, segment_names: tuple[str, ...]):
        self.program = ShaderProgram(Shader(VERTEX_SHADER, "vertex"), Shader(FRAGMENT_SHADER, "fragment"))
        n = len(segment_names)
        box_colors = np.repeat(sc.segment_colors(segment_names), sc.BOX_VERTICES, axis=0)
        self._boxes = self._list(n * sc.BOX_VERTICES, gl.GL_TRIANGLES, box_colors)
        self._marker = self._list(sc.MARKER_VERTICES, gl.GL_TRIANGLES, np.tile(sc.TARGET_COLOR, (sc.MARKER_VERTICES, 1)))
        self._water = self._list(6, gl.GL_TRIANGLES, np.tile(sc.WATER_COLOR, (6, 1)))
        self._water.normal[:] = [0.0, 0.0, 1.0] * 6
        self._grid = _Lines(self._list(MAX_LINE_VERTICES, gl.GL_LINES, np.zeros((MAX_LINE_VERTICES, 4))))
        self._guides = _Lines(self._list(MAX_LINE_VERTICES, gl.GL_LINES, np.zeros((MAX_LINE_VERTICES, 4))))
        self._particles = None        # GL_POINTS, sized on the first frame that has water particles

    def _list(self, count: int, mode: int, colors: np.ndarray):
        return self.program.vertex_list(count, mode, position=("f", np.zeros(3 * count).tolist()),
                                        normal=("f", np.tile([0.0, 0.0, 1.0], count).tolist()),
                                        color=("f", np.asarray(colors, float).reshape(-1).tolist()))

    def draw(self, scene: sc.Scene, camera: OrbitCamera, width_px: int, height_px: int,
             show_forces: bool = False, show_current: bool = True) -> None:
        gl.glViewport(0, 0, width_px, height_px)
        gl.glClearColor(*sc.SKY_COLOR)
        gl.glClear(gl.GL_COLOR_BUFFER_BIT | gl.GL_DEPTH_BUFFER_BIT)
        gl.glEnable(gl.GL_DEPTH_TEST)
        gl.glEnable(gl.GL_BLEND)
        gl.glBlendFunc(gl.GL_SRC_ALPHA, gl.GL_ONE_MINUS_SRC_ALPHA)
        p = self.program
        p.use()
        p["view_proj"] = gl_matrix(camera.view_projection(width_px, height_px))
        p["light_dir"] = tuple(LIGHT_DIR)
        p["eye"] = tuple(camera.eye_m)
        p["sky"] = sc.SKY_COLOR

        p["lit"] = 1.0
        vertices, normals = sc.box_triangles(scene.segment_pos_m, scene.segment_quat_xyzw, scene.half_extents_m)
        self._boxes.position[:] = vertices.reshape(-1).tolist()
        self._boxes.normal[:] = normals.reshape(-1).tolist()
        self._boxes.draw(gl.GL_TRIANGLES)
        p["lit"] = 0.0
        self._grid.draw([(sc.grid_lines(camera.focus_m), sc.GRID_COLOR)])

        # The water over what lies beneath it; alpha stays 1 in the framebuffer so screenshots
        # are not washed out, and depth is not written so what follows draws untinted on top.
        cx, cy = camera.focus_m[:2]
        h = WATER_HALF_SIZE_M
        corners = [(cx - h, cy - h, 0.0), (cx + h, cy - h, 0.0), (cx + h, cy + h, 0.0),
                   (cx - h, cy - h, 0.0), (cx + h, cy + h, 0.0), (cx - h, cy + h, 0.0)]
        self._water.position[:] = [c for corner in corners for c in corner]
        gl.glColorMask(gl.GL_TRUE, gl.GL_TRUE, gl.GL_TRUE, gl.GL_FALSE)
        gl.glDepthMask(gl.GL_FALSE)
        self._water.draw(gl.GL_TRIANGLES)
        gl.glDepthMask(gl.GL_TRUE)
        gl.glColorMask(gl.GL_TRUE, gl.GL_TRUE, gl.GL_TRUE, gl.GL_TRUE)

        if scene.particles_m is not None:
            self._draw_particles(scene.particles_m, scene.particle_speed_m_s)

        # Guides stay vivid whatever their depth: the target, its path, the trail, the arrows.
        if scene.target_m is not None:
            p["lit"] = 1.0
            vertices, normals = sc.marker_triangles(scene.target_m)
            self._marker.position[:] = vertices.reshape(-1).tolist()
            self._marker.normal[:] = normals.reshape(-1).tolist()
            self._marker.draw(gl.GL_TRIANGLES)
        p["lit"] = 0.0
        self._guides.draw(self._guide_lines(scene, show_forces, show_current))
        p.stop()
        gl.glDisable(gl.GL_DEPTH_TEST)

    @staticmethod
    def _guide_lines(scene: sc.Scene, show_forces: bool, show_current: bool):
        groups = []
        if scene.path_m is not None:
            groups.append((sc.polyline_lines(scene.path_m), sc.PATH_COLOR))
        if scene.target_m is not None:
            t = scene.target_m
            groups.append((np.array([[t[0], t[1], 0.0], t, t, [t[0], t[1], -sc.GRID_DEPTH_M]]), sc.TARGET_COLOR))
        if scene.trail_m is not None:
            groups.append((sc.polyline_lines(scene.trail_m), sc.TRAIL_COLOR))
        if show_forces and scene.forces_n is not None:
            groups.append((sc.arrow_lines(scene.segment_pos_m, sc.FORCE_SCALE_M_PER_N * scene.forces_n), sc.FORCE_COLOR))
        if show_current and scene.current_m_s is not None and np.linalg.norm(scene.current_m_s) > 0:
            start = scene.centre_of_segments_m + np.array([0.0, 0.0, 1.2])
            groups.append((sc.arrow_lines(start, sc.CURRENT_SCALE_M_PER_M_S * scene.current_m_s), sc.CURRENT_COLOR))
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
        self.program["lit"] = 0.0
        gl.glPointSize(3.0)
        gl.glDepthMask(gl.GL_FALSE)       # translucent: what lies behind still draws
        points.draw(gl.GL_POINTS)
        gl.glDepthMask(gl.GL_TRUE)

    def delete(self) -> None:
        for vertex_list in (self._boxes, self._marker, self._water, self._grid.vertices, self._guides.vertices):
            vertex_list.delete()
        if self._particles is not None:
            self._particles[0].delete()


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


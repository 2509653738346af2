"""The app's camera: an orbit around a focus point that follows the swimmer, plus mouse picking.

Pure numpy (no OpenGL), so picking a point on the water is testable without a window. Matrices
are 4x4 row-major numpy arrays acting on column vectors; ``gl_matrix`` flattens one the way a
GLSL ``mat4`` uniform wants it (column-major).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

MIN_PITCH_RAD = math.radians(5.0)     # stay above the water: the scene is drawn for a view from the air
MAX_PITCH_RAD = math.radians(85.0)
MIN_DISTANCE_M, MAX_DISTANCE_M = 1.5, 60.0
FOLLOW_TIME_CONSTANT_S = 0.4          # the focus eases after the swimmer instead of jerking with each stroke


def look_at(eye: np.ndarray, focus: np.ndarray, up=(0.0, 0.0, 1.0)) -> np.ndarray:
    forward = focus - eye
    forward = forward / np.linalg.norm(forward)
    side = np.cross(forward, up)
    side = side / np.linalg.norm(side)
    true_up = np.cross(side, forward)
    view = np.eye(4)
    view[0, :3], view[1, :3], view[2, :3] = side, true_up, -forward
    view[:3, 3] = -view[:3, :3] @ eye
    return view


def perspective(fov_y_rad: float, aspect: float, near_m: float, far_m: float) -> np.ndarray:
    f = 1.0 / math.tan(fov_y_rad / 2)
    m = np.zeros((4, 4))
    m[0, 0], m[1, 1] = f / aspect, f
    m[2, 2] = (far_m + near_m) / (near_m - far_m)
    m[2, 3] = 2 * far_m * near_m / (near_m - far_m)
    m[3, 2] = -1.0
    return m


def gl_matrix(m: np.ndarray) -> tuple[float, ...]:
    return tuple(float(v) for v in m.T.reshape(-1))


@dataclass
class OrbitCamera:
    yaw_rad: float = math.radians(-130.0)    # behind and to the right of a swimmer heading +x
    pitch_rad: float = math.radians(30.0)
    distance_m: float = 6.0
    focus_m: np.ndarray = field(default_factory=lambda: np.zeros(3))
    fov_y_rad: float = math.radians(50.0)
    near_m: float = 0.05
    far_m: float = 600.0

    @property
    def eye_m(self) -> np.ndarray:
        cp = math.cos(self.pitch_rad)
        offset = np.array([cp * math.cos(self.yaw_rad), cp * math.sin(self.yaw_rad), math.sin(self.pitch_rad)])
        return self.focus_m + self.distance_m * offset

    def view(self) -> np.ndarray:
        return look_at(self.eye_m, self.focus_m)

    def projection(self, aspect: float) -> np.ndarray:
        return perspective(self.fov_y_rad, aspect, self.near_m, self.far_m)

    def view_projection(self, width_px: int, height_px: int) -> np.ndarray:
        return self.projection(width_px / max(1, height_px)) @ self.view()

    def orbit(self, dx_px: float, dy_px: float) -> None:
        self.yaw_rad -= math.radians(0.3) * dx_px
        self.pitch_rad = min(MAX_PITCH_RAD, max(MIN_PITCH_RAD, self.pitch_rad - math.radians(0.3) * dy_px))

    def zoom(self, clicks: float) -> None:
        self.distance_m = min(MAX_DISTANCE_M, max(MIN_DISTANCE_M, self.distance_m * 0.88 ** clicks))

    def follow(self, point_m: np.ndarray, dt_s: float) -> None:
        """Ease the focus toward ``point_m`` (kept at the water surface's height for a level view)."""
        goal = np.array([point_m[0], point_m[1], 0.0])
        blend = 1.0 - math.exp(-max(0.0, dt_s) / FOLLOW_TIME_CONSTANT_S)
        self.focus_m = self.focus_m + blend * (goal - self.focus_m)

    def ray(self, x_px: float, y_px: float, width_px: int, height_px: int) -> tuple[np.ndarray, np.ndarray]:
        """World-space origin and unit direction of the ray under a pixel (y up from the bottom)."""
        inverse = np.linalg.inv(self.view_projection(width_px, height_px))
        ndc = np.array([2.0 * x_px / width_px - 1.0, 2.0 * y_px / height_px - 1.0])
        near = inverse @ np.array([*ndc, -1.0, 1.0])
        far = inverse @ np.array([*ndc, 1.0, 1.0])
        near, far = near[:3] / near[3], far[:3] / far[3]
        direction = far - near
        return near, direction / np.linalg.norm(direction)

    def water_point(self, x_px: float, y_px: float, width_px: int, height_px: int,
                    surface_z_m: float = 0.0) -> np.ndarray | None:
        """Where the ray under a pixel meets the water surface, or None above the horizon."""
        origin, direction = self.ray(x_px, y_px, width_px, height_px)
        if direction[2] > -1e-6:
            return None
        return origin + (surface_z_m - origin[2]) / direction[2] * direction

    def project(self, point_m: np.ndarray, width_px: int, height_px: int) -> np.ndarray | None:
        """Pixel (x, y from the bottom) of a world point, or None behind the camera."""
        clip = self.view_projection(width_px, height_px) @ np.array([*point_m, 1.0])
        if clip[3] <= 0:
            return None
        ndc = clip[:3] / clip[3]
        return np.array([(ndc[0] + 1) * width_px / 2, (ndc[1] + 1) * height_px / 2])

"""The cameras: an orbit around a focus point that follows the swimmer, in three views (from
above, level with the surface, from under water), plus mouse picking.

Pure numpy (no OpenGL), so picking a point on the water is testable without a window. Matrices
are 4x4 row-major numpy arrays acting on column vectors; ``gl_matrix`` flattens one the way a
GLSL ``mat4`` uniform wants it (column-major).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

MIN_DISTANCE_M = 1.5
FOLLOW_TIME_CONSTANT_S = 0.4          # the focus eases after the swimmer instead of jerking with each stroke
HEADING_TIME_CONSTANT_S = 1.0         # the side views swing round a turn, not with each stroke's sway
HEADING_MIN_LAG_M = 0.05              # slower than ~0.1 m/s the swimmer's direction means little: held


@dataclass(frozen=True)
class View:
    """Where a view puts the eye around the focus, and how far the mouse may move it."""

    yaw_rad: float                    # from the world's +x, or from the swimmer's heading where it turns with it
    pitch_rad: float
    distance_m: float
    pitch_range_rad: tuple[float, float]
    max_distance_m: float
    turns_with_swimmer: bool
    look_below_m: float = 0.0         # aim this far under the focus (which stays on the surface)


VIEWS = {
    # Behind and to the right of a swimmer heading +x, from the air.
    "follow": View(math.radians(-130.0), math.radians(30.0), 6.0, (math.radians(5.0), math.radians(85.0)), 60.0,
                   False),
    # The eye on the surface, square to the swimmer's right: above the horizon air, below it water,
    # like a half-submerged lens; the body's waterline runs across the picture.
    "side": View(math.radians(-90.0), 0.0, 3.8, (0.0, 0.0), 30.0, True, look_below_m=0.4),
    # Below and behind to the right, looking up past the swimmer at the surface.
    "underwater": View(math.radians(-125.0), math.radians(-22.0), 4.0, (math.radians(-50.0), math.radians(-3.0)),
                       6.0, True),
}


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
    yaw_rad: float = VIEWS["follow"].yaw_rad
    pitch_rad: float = VIEWS["follow"].pitch_rad
    distance_m: float = VIEWS["follow"].distance_m
    focus_m: np.ndarray = field(default_factory=lambda: np.zeros(3))
    view_name: str = "follow"
    heading_rad: float = 0.0          # where the swimmer goes, as the focus's lag behind it says
    fov_y_rad: float = math.radians(50.0)
    near_m: float = 0.05
    far_m: float = 600.0

    @property
    def view_spec(self) -> View:
        return VIEWS[self.view_name]

    def set_view(self, name: str) -> None:
        spec = VIEWS[name]
        self.view_name = name
        self.yaw_rad, self.pitch_rad, self.distance_m = spec.yaw_rad, spec.pitch_rad, spec.distance_m

    def next_view(self) -> str:
        names = list(VIEWS)
        self.set_view(names[(names.index(self.view_name) + 1) % len(names)])
        return self.view_name

    @property
    def eye_m(self) -> np.ndarray:
        yaw = self.yaw_rad + (self.heading_rad if self.view_spec.turns_with_swimmer else 0.0)
        cp = math.cos(self.pitch_rad)
        offset = np.array([cp * math.cos(yaw), cp * math.sin(yaw), math.sin(self.pitch_rad)])
        return self.focus_m + self.distance_m * offset

    def view(self) -> np.ndarray:
        return look_at(self.eye_m, self.focus_m - [0.0, 0.0, self.view_spec.look_below_m])

    def projection(self, aspect: float) -> np.ndarray:
        return perspective(self.fov_y_rad, aspect, self.near_m, self.far_m)

    def view_projection(self, width_px: int, height_px: int) -> np.ndarray:
        return self.projection(width_px / max(1, height_px)) @ self.view()

    def orbit(self, dx_px: float, dy_px: float) -> None:
        low, high = self.view_spec.pitch_range_rad
        self.yaw_rad -= math.radians(0.3) * dx_px
        self.pitch_rad = min(high, max(low, self.pitch_rad - math.radians(0.3) * dy_px))

    def zoom(self, clicks: float) -> None:
        self.distance_m = min(self.view_spec.max_distance_m, max(MIN_DISTANCE_M, self.distance_m * 0.88 ** clicks))

    def follow(self, point_m: np.ndarray, dt_s: float) -> None:
        """Ease the focus toward ``point_m`` (kept at the water surface's height for a level view).
        The focus trails the swimmer along its path, so its lag also says where the swimmer heads:
        the side and underwater views turn with that."""
        goal = np.array([point_m[0], point_m[1], 0.0])
        lag = goal - self.focus_m
        blend = 1.0 - math.exp(-max(0.0, dt_s) / FOLLOW_TIME_CONSTANT_S)
        self.focus_m = self.focus_m + blend * lag
        if math.hypot(lag[0], lag[1]) > HEADING_MIN_LAG_M:
            turn = math.remainder(math.atan2(lag[1], lag[0]) - self.heading_rad, math.tau)
            self.heading_rad += (1.0 - math.exp(-max(0.0, dt_s) / HEADING_TIME_CONSTANT_S)) * turn

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
        """Where the ray under a pixel meets the water surface (from above or below), or None where
        it never does (above the horizon, or down into the deep from under water)."""
        origin, direction = self.ray(x_px, y_px, width_px, height_px)
        if abs(direction[2]) < 1e-6:
            return None
        along = (surface_z_m - origin[2]) / direction[2]
        return origin + along * direction if along > 0 else None

    def project(self, point_m: np.ndarray, width_px: int, height_px: int) -> np.ndarray | None:
        """Pixel (x, y from the bottom) of a world point, or None behind the camera."""
        clip = self.view_projection(width_px, height_px) @ np.array([*point_m, 1.0])
        if clip[3] <= 0:
            return None
        ndc = clip[:3] / clip[3]
        return np.array([(ndc[0] + 1) * width_px / 2, (ndc[1] + 1) * height_px / 2])

"""What a frame shows, as plain arrays, and the geometry built from it (pure numpy, no OpenGL).

The live app and the headless renderer both describe a frame as a ``Scene``; ``renderer.py``
turns one into triangles and lines on the GPU.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from layered_swim.geometry import quat_rotate

SKIN = (0.93, 0.72, 0.58)
SUIT = (0.75, 0.12, 0.16)
CAP = (1.0, 0.82, 0.15)
TARGET_COLOR = (1.0, 0.1, 0.85, 1.0)        # magenta: no other thing in the scene has this hue
TRAIL_COLOR = (1.0, 1.0, 1.0, 1.0)
PATH_COLOR = (1.0, 0.55, 0.9, 1.0)
FORCE_COLOR = (0.1, 1.0, 0.3, 1.0)
CURRENT_COLOR = (0.2, 0.95, 1.0, 1.0)
FLOW_COLOR = (1.0, 0.6, 0.1, 1.0)           # the water velocity at the segments: orange on blue
GRID_COLOR = (0.12, 0.22, 0.3, 1.0)
FLOOR_COLOR = (0.42, 0.5, 0.52, 1.0)
SURFACE_COLOR = (0.1, 0.45, 0.66, 0.3)      # seen from above; alpha: how much it veils what is under it
DEEP_COLOR = (0.04, 0.3, 0.45, 1.0)         # what water turns everything toward with distance
SKY_COLOR = (0.66, 0.8, 0.92, 1.0)

FORCE_SCALE_M_PER_N = 0.004     # a 100 N fluid force draws as a 0.4 m arrow
CURRENT_SCALE_M_PER_M_S = 2.0
FLOW_SCALE_M_PER_M_S = 0.8      # the flow lattice's arrows: 0.5 m/s is 0.4 m, well inside a cell
FLOW_SPACING_M = 1.0
FLOW_HALF_POINTS = 3
FLOW_DEPTHS_M = (0.3, 1.0)
STILL_MARK_M = 0.04             # half a still-water cross at a lattice point
MARKER_SIZE_M = 0.22
GRID_DEPTH_M = 3.0               # the open-water grid lies this far below the surface
GRID_SPACING_M = 2.0
GRID_HALF_LINES = 20

# 12 triangles of a unit box: corner sign patterns and each triangle's outward face normal.
_FACES = [  # (normal, four corners counterclockwise seen from outside)
    ((1, 0, 0), [(1, -1, -1), (1, 1, -1), (1, 1, 1), (1, -1, 1)]),
    ((-1, 0, 0), [(-1, 1, -1), (-1, -1, -1), (-1, -1, 1), (-1, 1, 1)]),
    ((0, 1, 0), [(1, 1, -1), (-1, 1, -1), (-1, 1, 1), (1, 1, 1)]),
    ((0, -1, 0), [(-1, -1, -1), (1, -1, -1), (1, -1, 1), (-1, -1, 1)]),
    ((0, 0, 1), [(-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)]),
    ((0, 0, -1), [(-1, 1, -1), (1, 1, -1), (1, -1, -1), (-1, -1, -1)]),
]
BOX_CORNERS = np.array([quad[i] for _, quad in _FACES for i in (0, 1, 2, 0, 2, 3)], dtype=float)   # (36, 3)
BOX_NORMALS = np.array([n for n, _ in _FACES for _ in range(6)], dtype=float)                      # (36, 3)
BOX_VERTICES = len(BOX_CORNERS)

# An octahedron: the target marker.
_OCTA_TIPS = np.array([(1, 0, 0), (0, 1, 0), (-1, 0, 0), (0, -1, 0)], dtype=float)
MARKER_TRIANGLES = np.array([[tip, _OCTA_TIPS[(i + 1) % 4], (0, 0, s)] for s in (1.0, -1.0)
                             for i, tip in enumerate(_OCTA_TIPS)])                                # (8, 3, 3)
MARKER_VERTICES = MARKER_TRIANGLES.shape[0] * 3


@dataclass
class Scene:
    segment_names: tuple[str, ...]
    half_extents_m: np.ndarray        # (n, 3)
    segment_pos_m: np.ndarray         # (n, 3)
    segment_quat_xyzw: np.ndarray     # (n, 4)
    target_m: np.ndarray | None = None
    path_m: np.ndarray | None = None  # the scripted target's whole path
    trail_m: np.ndarray | None = None # the swimmer's recent track
    forces_n: np.ndarray | None = None
    current_m_s: np.ndarray | None = None
    particles_m: np.ndarray | None = None        # (k, 3) water particles (the SPH backend)
    particle_speed_m_s: np.ndarray | None = None  # (k,)
    flow_m_s: np.ndarray | None = None            # (n, 3) water velocity at each segment, as the fluid found it
    # The water's own velocity at (k, 3) points now, where it varies from place to place (a water file).
    water_at: Callable[[np.ndarray], np.ndarray] | None = None

    @property
    def centre_of_segments_m(self) -> np.ndarray:
        return self.segment_pos_m.mean(axis=0)


def segment_colors(names: tuple[str, ...]) -> np.ndarray:
    """RGBA per segment: cap on the head, suit on the trunk, skin on the limbs; the left side a
    shade darker so the roll and the arm phase read at a glance."""
    colors = []
    for name in names:
        rgb = CAP if name == "head" else SUIT if name in ("pelvis", "abdomen", "thorax") else SKIN
        if name in ("thorax", "abdomen"):
            rgb = tuple(0.55 * c + 0.45 * s for c, s in zip(rgb, SKIN))
        shade = 0.8 if name.startswith("left") else 1.0
        colors.append((*(shade * c for c in rgb), 1.0))
    return np.array(colors)


def box_triangles(pos_m: np.ndarray, quat_xyzw: np.ndarray, half_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and normals (n * 36, 3) of every segment's box, in segment order."""
    quat = np.asarray(quat_xyzw, float)[:, None, :]
    vertices = pos_m[:, None, :] + quat_rotate(quat, BOX_CORNERS[None, :, :] * half_m[:, None, :])
    normals = quat_rotate(quat, BOX_NORMALS[None, :, :])
    return vertices.reshape(-1, 3), normals.reshape(-1, 3)


def marker_triangles(centre_m: np.ndarray, size_m: float = MARKER_SIZE_M) -> tuple[np.ndarray, np.ndarray]:
    vertices = centre_m + size_m * MARKER_TRIANGLES.reshape(-1, 3) * np.array([1.0, 1.0, 1.6])
    tri = vertices.reshape(-1, 3, 3)
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    return vertices, np.repeat(normal, 3, axis=0)


def arrow_lines(starts_m: np.ndarray, vectors_m: np.ndarray, head_fraction: float = 0.25) -> np.ndarray:
    """Line-segment endpoints (k * 6, 3) for arrows: a shaft and a two-stroke head each."""
    starts_m, vectors_m = np.atleast_2d(starts_m), np.atleast_2d(vectors_m)
    ends = starts_m + vectors_m
    length = np.linalg.norm(vectors_m, axis=1, keepdims=True)
    direction = vectors_m / np.maximum(length, 1e-9)
    side = np.cross(direction, [0.0, 0.0, 1.0])
    flat = np.linalg.norm(side, axis=1) < 1e-6                 # vertical arrow: any horizontal side
    side[flat] = [1.0, 0.0, 0.0]
    side /= np.linalg.norm(side, axis=1, keepdims=True)
    back = ends - head_fraction * vectors_m
    spread = 0.5 * head_fraction * length * side
    lines = np.stack([starts_m, ends, ends, back + spread, ends, back - spread], axis=1)
    return lines.reshape(-1, 3)


def polyline_lines(points_m: np.ndarray) -> np.ndarray:
    """Line-segment endpoints joining consecutive points."""
    points_m = np.asarray(points_m, float)
    if len(points_m) < 2:
        return np.zeros((0, 3))
    return np.stack([points_m[:-1], points_m[1:]], axis=1).reshape(-1, 3)


def grid_lines(centre_m: np.ndarray, z_m: float = -GRID_DEPTH_M, spacing_m: float = GRID_SPACING_M,
               half_lines: int = GRID_HALF_LINES) -> np.ndarray:
    """A square grid snapped to world multiples of the spacing (so it stays put as the camera
    follows the swimmer)."""
    cx, cy = (np.round(np.asarray(centre_m[:2]) / spacing_m) * spacing_m)
    extent = half_lines * spacing_m
    offsets = np.arange(-half_lines, half_lines + 1) * spacing_m
    along_x = [((cx - extent, cy + o, z_m), (cx + extent, cy + o, z_m)) for o in offsets]
    along_y = [((cx + o, cy - extent, z_m), (cx + o, cy + extent, z_m)) for o in offsets]
    return np.array(along_x + along_y, dtype=float).reshape(-1, 3)


def square(centre_m: np.ndarray, half_m: float, z_m: float) -> np.ndarray:
    """Two triangles (6, 3) of a level square around ``centre_m``'s x, y at height ``z_m``."""
    cx, cy = centre_m[0], centre_m[1]
    corners = np.array([(cx - half_m, cy - half_m), (cx + half_m, cy - half_m), (cx + half_m, cy + half_m),
                        (cx - half_m, cy + half_m)])[[0, 1, 2, 0, 2, 3]]
    return np.column_stack([corners, np.full(6, z_m)])


def flow_lattice(centre_m: np.ndarray, spacing_m: float = FLOW_SPACING_M, half_points: int = FLOW_HALF_POINTS,
                 depths_m=FLOW_DEPTHS_M) -> np.ndarray:
    """Points (k, 3) around the swimmer where the current is drawn, snapped to world multiples of
    the spacing like the grid, so the arrows stand still in the water as the swimmer passes."""
    cx, cy = np.round(np.asarray(centre_m[:2]) / spacing_m) * spacing_m
    offsets = np.arange(-half_points, half_points + 1) * spacing_m
    x, y, z = np.meshgrid(cx + offsets, cy + offsets, -np.asarray(depths_m, float), indexing="ij")
    return np.column_stack([x.ravel(), y.ravel(), z.ravel()])


def cross_lines(points_m: np.ndarray, half_m: float = STILL_MARK_M) -> np.ndarray:
    """Line-segment endpoints (k * 4, 3) of a small level cross at each point: still water."""
    points_m = np.atleast_2d(points_m)
    dx, dy = np.array([half_m, 0.0, 0.0]), np.array([0.0, half_m, 0.0])
    return np.stack([points_m - dx, points_m + dx, points_m - dy, points_m + dy], axis=1).reshape(-1, 3)


SPEED_COLOR_MAX_M_S = 1.5     # water at this speed or faster is drawn white


def speed_colors(speeds_m_s: np.ndarray) -> np.ndarray:
    """RGBA per water particle: deep blue and faint at rest, through cyan to opaque white at
    SPEED_COLOR_MAX_M_S, so the swimmer shows through still water and the wake stands out."""
    t = np.clip(np.asarray(speeds_m_s, dtype=float) / SPEED_COLOR_MAX_M_S, 0.0, 1.0)[:, None]
    still, middle, fast = np.array([0.05, 0.2, 0.6]), np.array([0.1, 0.75, 0.95]), np.array([1.0, 1.0, 1.0])
    rgb = np.where(t < 0.5, still + (middle - still) * (2 * t), middle + (fast - middle) * (2 * t - 1))
    return np.column_stack([rgb, 0.2 + 0.8 * t[:, 0]])

"""SWIM's goal-reaching benchmark (SWIM 2026, sections 3.2.1 and 4): pools, goals, the
on-schedule line and the task metrics Pos, Prog, Dev, Roll and Vel. Pure numpy, no PyBullet.

Axes: world z up, water surface at z = 0; the swimmer starts at the origin heading +x, +y is its
left. SWIM's goals live in the horizontal plane (its goal state is [x_loc, y_loc, |psi_loc|],
eq. 3), so every distance here is horizontal: depth is the stroke's business, not the task's.
``time_s`` is time since the swim started, the schedule's t = 0.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from layered_swim.config import ConfigError

# SWIM Table 3 starts the root at h_init = 0.45 m; read as height above the floor of the 0.5 m
# training pool, that is 0.05 m under the surface. We use that depth in both pools.
START_DEPTH_M = 0.05

# SWIM's theta_tol is "style-specific, informed by the roll angles of elite swimmers" (eq. 14)
# but never given. Front crawl: the low end of elite shoulder roll, 45-60 deg per side
# (Psycharakis & Sanders 2010, layered_swim/reference.md section 3); breaststroke barely rolls.
ROLL_TOLERANCE_DEG = {"front_crawl": 45.0, "breaststroke": 15.0}
SIDE_ROOM_M = 0.5      # a goal off the pool's own three stays this far inside the side walls


@dataclass(frozen=True)
class Pool:
    """A pool of SWIM section 4.1. The start->goal span is centred in the pool's length, so the
    body fits behind the start and the goals sit on the far side short of the wall."""

    name: str
    length_m: float
    width_m: float
    depth_m: float
    horizon_s: float
    goal_distance_m: float                  # along +x, start to goals
    goal_offsets_m: tuple[float, ...]       # lateral (y) offsets of the three goals

    @property
    def x_range_m(self) -> tuple[float, float]:
        back = -(self.length_m - self.goal_distance_m) / 2
        return back, back + self.length_m

    def ending(self, com_m) -> str | None:
        """Why a swim with its centre of mass at ``com_m`` ends here (out past a wall, down on the
        floor), or None while it is inside the pool. Every controller's episode ends the same way."""
        x0, x1 = self.x_range_m
        if not (x0 < com_m[0] < x1 and abs(com_m[1]) < self.width_m / 2):
            return f"left the {self.name} pool (centre of mass at x = {com_m[0]:.2f}, y = {com_m[1]:.2f} m)"
        if com_m[2] < -self.depth_m:
            return f"sank to the floor of the {self.depth_m:g} m deep pool"
        return None

    def holding(self, lateral_m: float, side_room_m: float = SIDE_ROOM_M) -> "Pool":
        """This pool with one goal ``lateral_m`` to the left of straight ahead, widened where needed
        to keep it ``side_room_m`` inside the side walls (SWIM's Fig. 4 sweep; goals drawn in training)."""
        return replace(self, name=f"{self.name} (goal {lateral_m:+.2f} m left)", goal_offsets_m=(float(lateral_m),),
                       width_m=max(self.width_m, 2.0 * (abs(lateral_m) + side_room_m)))


# The paper's numbers, worked back: Fig. 4 puts d_lat = 1.0 m at 18.4 deg and 1.25 m at 22.6 deg
# in the large pool (3.0 m ahead), and the training range d_lat = +-0.375 m at +-14 deg (1.5 m
# ahead in the small pool); 1.5 m in 4 s is SWIM's 0.375 m/s trajectory speed (section 3.2.1).
# The large pool doubles the whole start->goal vector, so its goals keep the +-14 deg.
POOLS = {
    "small": Pool("small", 3.0, 1.5, 0.5, 4.0, 1.5, (0.0, 0.375, -0.375)),
    "large": Pool("large", 5.0, 2.0, 0.7, 8.0, 3.0, (0.0, 0.75, -0.75)),
}


def pool(name: str) -> Pool:
    try:
        return POOLS[name]
    except KeyError:
        raise ConfigError(f"unknown pool {name!r}: expected one of {', '.join(POOLS)}") from None


@dataclass(frozen=True)
class GoalTask:
    """Swim the straight line start->goal at constant speed, arriving at the end of the horizon."""

    pool: Pool
    start_m: tuple[float, float, float]
    goal_m: tuple[float, float, float]
    duration_s: float

    @property
    def length_m(self) -> float:
        return float(np.linalg.norm(np.subtract(self.goal_m, self.start_m)))

    @property
    def direction(self) -> np.ndarray:
        return np.subtract(self.goal_m, self.start_m) / self.length_m

    @property
    def speed_m_s(self) -> float:
        return self.length_m / self.duration_s


def goal_tasks(pool: Pool) -> list[GoalTask]:
    start = (0.0, 0.0, -START_DEPTH_M)
    return [GoalTask(pool, start, (pool.goal_distance_m, y, -START_DEPTH_M), pool.horizon_s)
            for y in pool.goal_offsets_m]


def goal_position(task: GoalTask, t_s) -> np.ndarray:
    """SWIM eq. 1, p_t = (1 - t) p_start + t p_tar with t = t_s / duration in [0, 1]: the
    on-schedule point at time t_s, held at the goal after the horizon. Shape (..., 3)."""
    if isinstance(t_s, float):     # one time, numpy floats too (a controller's target each control step): float sums
        f = t_s / task.duration_s
        f = 1.0 if f >= 1.0 else (f if f > 0.0 else 0.0)
        return np.array([(1.0 - f) * a + f * b for a, b in zip(task.start_m, task.goal_m)])
    fraction = np.clip(np.asarray(t_s, dtype=float) / task.duration_s, 0.0, 1.0)[..., None]
    return (1.0 - fraction) * np.asarray(task.start_m) + fraction * np.asarray(task.goal_m)


def intermediate_goal(task: GoalTask, t_s, dt_s) -> np.ndarray:
    """SWIM eq. 2: the point dt_s ahead on the schedule, "t + dt capped at 1". The paper mixes
    units (t in [0, 1], dt including T_cycle); we read every dt in seconds."""
    return goal_position(task, np.asarray(t_s, dtype=float) + dt_s)


def goal_leads_s(cycle_s: float) -> np.ndarray:
    """SWIM eq. 2's leads of the four intermediate goals: 0.1 s, 0.2 s, T_cycle/2, T_cycle."""
    return np.array([0.1, 0.2, cycle_s / 2, cycle_s])


def intermediate_goals(task: GoalTask, t_s: float, cycle_s: float) -> np.ndarray:
    """SWIM eqs. 2-3: the four goals ``goal_leads_s`` ahead on the schedule. Shape (4, 3)."""
    return intermediate_goal(task, t_s, goal_leads_s(cycle_s))


# --- metrics: each a mean over the logged samples ("computed at every time step and averaged
# over the motion", SWIM section 4.1). The target is the line start + direction * speed * t.

def _along_across(positions_m, start_m, direction) -> tuple[np.ndarray, np.ndarray]:
    """Horizontal distance travelled along the line and signed distance to its left."""
    d = np.asarray(direction, dtype=float)[:2]
    norm = np.linalg.norm(d)
    if norm == 0.0:
        raise ValueError("direction has no horizontal part")
    d = d / norm
    rel = np.asarray(positions_m, dtype=float)[:, :2] - np.asarray(start_m, dtype=float)[:2]
    return rel @ d, d[0] * rel[:, 1] - d[1] * rel[:, 0]


def pos_m(time_s, positions_m, start_m, direction, speed_m_s: float) -> float:
    """"Pos measures the Euclidean distance between the character's position and the
    corresponding intermediate goal position averaged over time": the mean distance to the
    on-schedule point of eq. 1."""
    along, across = _along_across(positions_m, start_m, direction)
    return float(np.mean(np.hypot(along - speed_m_s * np.asarray(time_s, dtype=float), across)))


def prog(time_s, positions_m, start_m, direction, speed_m_s: float) -> float:
    """"Prog measures progress in space and time along the straight line from the initial
    position to the final goal" (1 = on schedule): distance made along the line by the last
    sample over the distance the schedule asks for by then; negative when swimming backwards.
    (Not time-averaged progress over the time-averaged schedule: SWIM's Prog 0.712 would then
    mean lagging 0.29 x 0.75 m = 0.22 m on average, more than its Pos of 0.126 m allows.)"""
    along, _ = _along_across(positions_m, start_m, direction)
    return float(along[-1] / (speed_m_s * float(np.asarray(time_s)[-1])))


def dev_m(positions_m, start_m, direction) -> float:
    """"Dev measures the lateral deviation from the desired path going through the intermediate
    goal positions": the mean distance to the line (eq. 12's ||p - proj_L(p)||)."""
    return float(np.mean(np.abs(_along_across(positions_m, start_m, direction)[1])))


def roll_excess_deg(roll_deg, tolerance_deg: float) -> float:
    """"Roll measures the mean d_t^roll in Eq. 14 over time",
    d_t^roll = max(|theta_t^roll| - theta_tol, 0)."""
    excess = np.abs(np.asarray(roll_deg, dtype=float)) - tolerance_deg
    return float(np.mean(np.maximum(excess, 0.0)))


def vel(joint_vel, ref_joint_vel) -> float:
    """"Vel measures the difference in the joint angular velocity from the reference motion
    averaged over joints and time": mean |qdot - qdot_ref| over (samples, joints)."""
    diff = np.asarray(joint_vel, dtype=float) - np.asarray(ref_joint_vel, dtype=float)
    return float(np.mean(np.abs(diff)))


def straight_line_metrics(time_s, positions, roll_deg, start, direction, speed_m_s: float,
                          tolerance_deg: float, joint_vel=None, ref_joint_vel=None) -> dict:
    """Pos, Prog, Dev, Roll (and Vel when both joint-velocity arrays are given, else None) for a
    target moving along start + direction * speed * t. Arrays per sample: time_s (n,),
    positions (n, 3), roll_deg (n,), joint velocities (n, joints)."""
    time_s, positions = np.asarray(time_s, dtype=float), np.asarray(positions, dtype=float)
    if positions.shape != (len(time_s), 3) or np.shape(roll_deg) != time_s.shape:
        raise ValueError("expected time_s (n,), positions (n, 3) and roll_deg (n,)")
    if time_s[-1] <= 0.0 or speed_m_s <= 0.0:
        raise ValueError("Prog needs a positive speed and a log that ends after t = 0")
    if (joint_vel is None) != (ref_joint_vel is None):
        raise ValueError("Vel needs both joint_vel and ref_joint_vel")
    return {
        "pos_m": pos_m(time_s, positions, start, direction, speed_m_s),
        "prog": prog(time_s, positions, start, direction, speed_m_s),
        "dev_m": dev_m(positions, start, direction),
        "roll_deg": roll_excess_deg(roll_deg, tolerance_deg),
        "vel": None if joint_vel is None else vel(joint_vel, ref_joint_vel),
    }


def held_to(time_s, samples: list, end_s: float, step_s: float) -> tuple[np.ndarray, list]:
    """The samples with their last one held, every ``step_s``, until ``end_s``: an episode that
    ended early (out of the pool, sunk, blown up) is scored over the whole horizon, the swimmer
    staying where it stopped, not over the part it swam. Each of ``samples`` (n, ...) or None."""
    time_s = np.asarray(time_s, dtype=float)
    extra = np.arange(time_s[-1] + step_s, end_s + 1e-9, step_s)
    if not len(extra):
        return time_s, samples

    def hold(values):
        if values is None:
            return None
        values = np.asarray(values, dtype=float)
        return np.concatenate([values, np.repeat(values[-1:], len(extra), axis=0)])

    return np.concatenate([time_s, extra]), [hold(v) for v in samples]


def episode_metrics(task: GoalTask, time_s, positions, roll_deg, tolerance_deg: float,
                    joint_vel=None, ref_joint_vel=None, ended_s: float | None = None,
                    step_s: float | None = None) -> dict:
    """The metrics of one goal-reaching episode. The episode is the task's horizon: samples
    logged after it are left out (so the schedule never needs holding at the goal). One that
    ended at ``ended_s`` is held there to the horizon (``held_to``, every ``step_s``)."""
    time_s = np.asarray(time_s, dtype=float)
    end_s = task.duration_s if ended_s is None else min(ended_s, task.duration_s)
    keep = time_s <= end_s + 1e-9     # the last sample may sit on the horizon, rounded
    samples = [None if v is None else np.asarray(v, dtype=float)[keep]
               for v in (positions, roll_deg, joint_vel, ref_joint_vel)]
    time_s = time_s[keep]
    if ended_s is not None:
        time_s, samples = held_to(time_s, samples, task.duration_s, step_s)
    positions, roll_deg, joint_vel, ref_joint_vel = samples
    return straight_line_metrics(time_s, positions, roll_deg, task.start_m, task.direction, task.speed_m_s,
                                 tolerance_deg, joint_vel, ref_joint_vel)


def _published(pos, prog_, dev) -> dict:
    return {"pos_m": pos, "prog": prog_, "dev_m": dev}


# Freestyle, quiet water, (mean, std) over targets: SWIM 2026 Table 3 ("Cross-method trajectory
# tracking"; its SWIM rows equal Table 2's SmoothFT). "small" = the 3 m static column, "large" =
# 5 m static. No baseline wins every column: M-PPO-3 has the best baseline Dev in both pools
# and Pos in the large one, M-PPO-2 the better Pos and Prog in the small one.
SWIM_PUBLISHED = {
    "source": "SWIM 2026, Table 3: freestyle, static (quiet water), mean and std over targets",
    "small": {
        "SWIM": _published((0.126, 0.030), (0.712, 0.028), (0.037, 0.006)),
        "M-PPO-3": _published((0.177, 0.061), (0.668, 0.061), (0.055, 0.018)),
        "M-PPO-2": _published((0.154, 0.045), (0.746, 0.051), (0.080, 0.031)),
    },
    "large": {
        "SWIM": _published((0.217, 0.053), (0.880, 0.070), (0.144, 0.054)),
        "M-PPO-3": _published((0.349, 0.156), (0.761, 0.099), (0.157, 0.101)),
        "M-PPO-2": _published((0.626, 0.376), (1.102, 0.142), (0.378, 0.470)),
    },
}


# SWIM 2026, Table 3 ("cross-method trajectory tracking", freestyle), all four columns, (mean,
# std) over targets; "dynamic" is SWIM's water with waves, filtered to four flow directions.
SWIM_PUBLISHED_TABLE3 = {
    "3 m static": SWIM_PUBLISHED["small"],
    "3 m dynamic": {"SWIM": _published((0.254, 0.104), (0.675, 0.316), (0.069, 0.048)),
                    "M-PPO-3": _published((0.266, 0.126), (0.646, 0.322), (0.061, 0.031)),
                    "M-PPO-2": _published((0.286, 0.161), (0.696, 0.254), (0.132, 0.148))},
    "5 m static": SWIM_PUBLISHED["large"],
    "5 m dynamic": {"SWIM": _published((0.392, 0.211), (0.850, 0.212), (0.169, 0.089)),
                    "M-PPO-3": _published((0.458, 0.175), (0.774, 0.211), (0.191, 0.149)),
                    "M-PPO-2": _published((0.874, 0.616), (0.874, 0.423), (0.498, 0.501))},
}

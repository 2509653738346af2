"""``layered-swim calibrate``: the per-cycle layer's table by preprocessed simulation (Yang 4.3).

For every perturbation sequence of a stroke, simulate the swimmer in still water at a grid of
weights and tempos (tempo sets the swimming speed): a few basic cycles to settle, then a few
cycles with the sequence at that weight. A yaw sequence's turn is the change of the
cycle-averaged heading per cycle, minus the unperturbed drift; a pitch or roll sequence's is the
offset of the cycle-averaged body pitch or shoulder roll it holds (the water and buoyancy stop
it turning further within a cycle), minus the unperturbed stroke's change. The
unperturbed swims, at more tempos, give the stroke's pace: speed, roll, pitch and depth
(``layered_swim/control/calibration.py`` keeps and reads the table).
"""
from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor

import numpy as np

from layered_swim.config import ConfigError
from layered_swim.control.calibration import SEQUENCE_AXIS, CalibrationTable, Pace
from layered_swim.control.layered import Layers, fixed_weights
from layered_swim.control.steering import attitude_of, wrap_angle
from layered_swim.control.stroke import SEQUENCE_NAMES, Stroke
from layered_swim.episode import Episode

AXIS_INDEX = {"yaw": 0, "pitch": 1, "roll": 2}       # columns of a swim's (yaw, pitch, roll) change
WEIGHT_STEP = 0.25
TEMPOS = (0.7, 1.0)
PACE_TEMPOS = (0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2)     # includes TEMPOS: their drift is measured once
SETTLE_CYCLES = 3
MEASURE_CYCLES = 2


class _CycleAttitude:
    """Observer: per stroke cycle, the unwrapped heading, pitch and roll at every control step,
    and the centre of mass once the perturbation is on (every control step, and as each cycle starts)."""

    def __init__(self, episode: Episode):
        self.controller, self.posture = episode.controller, episode.stroke.start.posture
        self.samples: dict[int, list[tuple[float, float, float]]] = {}
        self.positions: list[np.ndarray] = []
        self.cycle_starts_m: dict[int, np.ndarray] = {}
        self._heading_prev, self._unwrapped = None, 0.0

    def __call__(self, sim) -> None:
        if sim.steps % sim.control_every:
            return
        att = attitude_of(sim.state, self.posture)
        if self._heading_prev is not None:
            self._unwrapped += wrap_angle(att.heading_rad - self._heading_prev)
        self._heading_prev = att.heading_rad
        cycle = self.controller.cycle
        self.samples.setdefault(cycle, []).append((self._unwrapped, att.pitch_rad, att.roll_rad))
        if cycle >= SETTLE_CYCLES:
            self.positions.append(sim.state.com_m)
            self.cycle_starts_m.setdefault(cycle, sim.state.com_m)


def calibration_swim(job: tuple[str, str | None, float, float]) -> tuple:
    """One calibration swim: (angle change per cycle about the sequence's axis, mean speed, the
    last cycle's mean roll and pitch, the final depth of the centre of mass, the distance swum per
    cycle along the track); with no sequence the change is (yaw, pitch, roll). The speed is the
    track's chord over the time (a turn's shortens it); the distance follows the turn, cycle by
    cycle."""
    stroke_name, sequence, weight, tempo = job
    weights = {sequence: weight} if sequence else {}
    episode = Episode(stroke_name, weights=fixed_weights(weights, SETTLE_CYCLES, tempo),
                      layers=Layers(cycle=True, palm=False, reach=False))
    attitude = _CycleAttitude(episode)
    seconds = (SETTLE_CYCLES + MEASURE_CYCLES) * episode.stroke.period_s / tempo
    control_hz = episode.sim.config.control_hz
    try:
        episode.run(seconds + 0.5 / control_hz, observers=[attitude])
    finally:
        episode.close()
    before = np.mean(attitude.samples[SETTLE_CYCLES - 1], axis=0)
    after = np.mean(attitude.samples[SETTLE_CYCLES + MEASURE_CYCLES - 1], axis=0)
    axis = AXIS_INDEX[SEQUENCE_AXIS[sequence][0]] if sequence else 0
    change = (after - before) / MEASURE_CYCLES
    track = np.array(attitude.positions)
    speed = float(np.linalg.norm(track[-1, :2] - track[0, :2]) / (len(track) / control_hz))
    ends = [attitude.cycle_starts_m[c][:2] for c in sorted(attitude.cycle_starts_m)] + [track[-1, :2]]
    per_cycle_m = float(sum(np.linalg.norm(b - a) for a, b in zip(ends, ends[1:]))) / MEASURE_CYCLES
    return ((float(change[axis]) if sequence else change.tolist()), speed, float(after[2]),
            float(after[1]), float(-track[-1, 2]), per_cycle_m)


def weight_grid(max_weight: float) -> tuple[float, ...]:
    """0 to ``max_weight`` (the stroke's ``steering.max_weight``) in steps of ``WEIGHT_STEP``."""
    return tuple(float(w) for w in np.linspace(0.0, max_weight, round(max_weight / WEIGHT_STEP) + 1))


def calibrate(stroke: Stroke, tempos=TEMPOS, pace_tempos=PACE_TEMPOS, workers: int = 2,
              progress: bool = False) -> CalibrationTable:
    """Simulate every sequence at every weight and tempo, and the unperturbed stroke at every
    pace tempo (in parallel), and build the table."""
    weights = weight_grid(stroke.steering.max_weight)
    sequences = [name for name in SEQUENCE_NAMES if name in stroke.perturbations]
    if not sequences:
        raise ConfigError(f"{stroke.source}: the stroke has no perturbation sequences to calibrate")
    if not set(tempos) <= set(pace_tempos):
        raise ValueError("every turn tempo must be a pace tempo (its unperturbed drift comes from there)")
    jobs = [(stroke.source, None, 0.0, tempo) for tempo in pace_tempos]
    jobs += [(stroke.source, seq, w, tempo) for seq in sequences for tempo in tempos for w in weights if w > 0]
    with ProcessPoolExecutor(max_workers=workers) as pool:
        results = pool.map(calibration_swim, jobs)
        if progress:
            from tqdm import tqdm
            results = tqdm(results, total=len(jobs), desc=f"calibrating {stroke.name}", unit="swim")
        results = list(results)
    unperturbed = results[:len(pace_tempos)]
    baseline = {tempo: unperturbed[pace_tempos.index(tempo)][0] for tempo in tempos}   # drift with no perturbation
    pace = Pace(tuple(pace_tempos), *(tuple(r[k] for r in unperturbed) for k in (1, 2, 3, 4)))
    measured = iter(results[len(pace_tempos):])
    turn_rad, attitude_rad = {}, {}
    for seq in sequences:
        axis, sign = SEQUENCE_AXIS[seq]
        k = AXIS_INDEX[axis]
        # Pitch and roll: the offset it holds (all its cycles' change), in the axis's own sense
        # (whichever way the sequence goes).
        scale = sign if axis == "yaw" else MEASURE_CYCLES
        rows = np.array([[0.0] + [scale * (next(measured)[0] - baseline[tempo][k]) for w in weights if w > 0]
                         for tempo in tempos])
        (turn_rad if axis == "yaw" else attitude_rad)[seq] = rows
    return CalibrationTable(stroke.name, stroke.spec_sha256, tuple(weights), tuple(tempos), pace, turn_rad,
                            attitude_rad)

"""Headless runs: build a swimmer from a stroke, run it, measure and write the results.

``run_swim`` is what ``layered-swim run`` calls; ``bench_step`` times one physics step bare
and through the whole simulation loop.
"""
from __future__ import annotations

import json
import math
import platform
import time
from dataclasses import asdict, dataclass
from importlib import metadata
from pathlib import Path

import numpy as np

from layered_swim.analysis.metrics import summary
from layered_swim.body.model import load_body
from layered_swim.config import ConfigError, load
from layered_swim.control.calibration import load_table
from layered_swim.control.layered import Layers, LayeredController, WeightPolicy, fixed_weights
from layered_swim.control.policy import TargetPolicy, TempoControl
from layered_swim.control.pose import joint_layout, unit_vector
from layered_swim.control.rules import arm_indices
from layered_swim.control.steering import SteeringGains
from layered_swim.control.targets import Target
from layered_swim.control.stroke import Stroke, StrokeSpec, available_strokes, build_stroke, stroke_path
from layered_swim.fluid.medium import Medium, preset
from layered_swim.sim.recorder import DEFAULT_LOG_HZ, Recorder
from layered_swim.sim.simulation import SimConfig, Simulation, StrokeController

MAX_SECONDS = 3600.0
MIN_SECONDS = 0.1        # a few log samples, so the metrics have a time span
BENCH_REPEATS = 5       # bare and loop timed in turn, the fastest of each kept: other load only adds time
BENCH_WARMUP_S = 0.5     # compiles (or loads) the numba fluid kernels before timing


@dataclass
class SwimSetup:
    stroke: Stroke
    stroke_spec: StrokeSpec    # the file as validated, defaults filled in (for config.json)
    sim: Simulation
    rng: np.random.Generator   # the run's one random source, for the layers that will need one


def make_medium(fluid: str = "fresh_water", density_kg_m3: float | None = None) -> Medium:
    medium = preset(fluid)
    return medium if density_kg_m3 is None else medium.with_(rho_kg_m3=float(density_kg_m3))


def build_swim(stroke: str, lung_air_l: float | None = None, medium: Medium | None = None,
               physics_hz: int = 480, tempo: float = 1.0, seed: int = 0, target: Target | None = None,
               layers: Layers | None = None, policy: WeightPolicy | None = None,
               tempo_control: TempoControl | None = None) -> SwimSetup:
    """Everything a run needs, reset to the stroke's start (posture, depth, speed).

    With neither ``target`` nor ``policy`` the basic stroke swims alone. With a ``target`` the
    layered controller steers toward it (``layers`` says which layers are on; the per-cycle
    layer needs the stroke's calibration table); a ``policy`` scripts the per-cycle weights."""
    if not isinstance(seed, int) or seed < 0:
        raise ConfigError(f"seed must be a non-negative integer, got {seed!r}")
    body = load_body(lung_air_l=lung_air_l)
    layout = joint_layout(body)
    path = stroke_path(stroke)
    spec = load(StrokeSpec, path)
    parsed = build_stroke(spec, layout, str(path))
    layered = target is not None or policy is not None
    layers = layers or Layers()
    if not layered:
        controller = StrokeController(parsed, tempo)
    else:
        if policy is None:
            steer = parsed.steering
            pace = tempo_control or TempoControl(min_tempo=steer.min_tempo, glide_within_m=steer.glide_within_m)
            gains = SteeringGains(steer.yaw_fraction, steer.pitch_fraction, steer.roll_fraction)
            policy = (TargetPolicy(target, load_table(parsed), parsed.start.posture, body.mass_fraction,
                                   gains=gains, tempo=pace)
                      if layers.cycle else fixed_weights({}, tempo=tempo))
        controller = LayeredController(parsed, layout, arm_indices(body, layout), policy, layers)
    sim = Simulation(body, controller, medium if medium is not None else Medium(), SimConfig(physics_hz=physics_hz), layout=layout,
                     pd_gain_scale=parsed.pd_gain_scale)
    if layered:
        controller.water_velocity = lambda state: sim.fluid.flow_m_s   # found by this step's fluid call
        if target is not None:
            mass_fraction = body.mass_fraction
            controller.desired_direction = lambda state: unit_vector(target.position(state.time_s) - mass_fraction @ state.pos_m)
    start = parsed.start
    sim.reset(start.posture, start.depth_m, start.speed_m_s)
    return SwimSetup(parsed, spec, sim, np.random.default_rng(seed))


def package_version() -> str:
    try:
        return metadata.version("layered-swim")
    except metadata.PackageNotFoundError:
        return "unknown (not installed)"


def resolved_config(setup: SwimSetup, arguments: dict, log_hz: int) -> dict:
    sim = setup.sim
    return {
        "arguments": arguments,
        "stroke_file": setup.stroke.source,
        "stroke": setup.stroke_spec.model_dump(mode="json"),
        "body_file": sim.body.source,
        "lung_air_l": sim.body.lung_air_l,
        "medium": asdict(sim.medium),
        "physics_hz": sim.config.physics_hz,
        "control_hz": sim.config.control_hz,
        "log_hz": log_hz,
        "cycles_per_s": sim.controller.cycles_per_s,
        "versions": versions(),
    }


def versions() -> dict:
    return {"layered_swim": package_version(), "python": platform.python_version(),
            "numpy": np.__version__, "pybullet": metadata.version("pybullet")}


def default_out_dir(stroke: str, root: Path = Path("runs")) -> Path:
    """``runs/<stroke>-<YYYYmmdd-HHMMSS>``, with a counter when that folder already exists."""
    base = root / f"{Path(stroke).stem}-{time.strftime('%Y%m%d-%H%M%S')}"
    path, n = base, 1
    while path.exists():
        path, n = base.with_name(f"{base.name}-{n}"), n + 1
    return path


def run_swim(stroke: str, seconds: float = 30.0, lung_air_l: float | None = None,
             density: float | None = None, out_dir: str | Path | None = None, seed: int = 0,
             physics_hz: int = 480, tempo: float = 1.0, fluid: str = "fresh_water",
             log_hz: int = DEFAULT_LOG_HZ, progress: bool = False) -> dict:
    """Run ``stroke`` for ``seconds`` and write summary.json, log.npz, timeseries.csv and
    config.json into ``out_dir`` (default: ``runs/<stroke>-<timestamp>``); returns the summary."""
    out_dir = Path(out_dir) if out_dir is not None else default_out_dir(stroke)
    arguments = {"stroke": stroke, "seconds": seconds, "lung_air_l": lung_air_l, "density": density,
                 "out_dir": str(out_dir), "seed": seed, "physics_hz": physics_hz, "tempo": tempo,
                 "fluid": fluid, "log_hz": log_hz}
    _check_seconds(seconds)
    setup = build_swim(stroke, lung_air_l, make_medium(fluid, density), physics_hz, tempo, seed)
    sim = setup.sim
    recorder = record(sim, seconds, log_hz, progress)
    out_dir.mkdir(parents=True, exist_ok=True)
    a = recorder.arrays()
    result = summary(a["time_s"], a["com_pos_m"], a["root_pos_m"],
                     a["segment_quat_xyzw"][:, sim.body.index("thorax")], a["head_top_m"],
                     sim.controller.cycles_per_s, setup.stroke.name)
    recorder.save(out_dir)
    _write_json(out_dir / "summary.json", result)
    _write_json(out_dir / "config.json", resolved_config(setup, arguments, log_hz))
    return result


def record(sim: Simulation, seconds: float, log_hz: int = DEFAULT_LOG_HZ, progress: bool = False,
           joint_work: bool = False) -> Recorder:
    """Run ``sim`` for ``seconds`` logging at ``log_hz`` (a progress bar with ``progress``),
    close it, and return the log."""
    try:
        recorder = Recorder(sim, log_hz, joint_work=joint_work)
        if not progress:
            sim.run(seconds, every_step=recorder)
            return recorder
        from tqdm import tqdm

        hz = sim.config.physics_hz
        with tqdm(total=math.floor(seconds), desc="simulated seconds", unit="s", leave=False) as bar:
            def every_step(s: Simulation) -> None:
                recorder(s)
                if s.steps % hz == 0:
                    bar.update(1)
            sim.run(seconds, every_step=every_step)
        return recorder
    finally:
        sim.close()


def _check_seconds(seconds: float) -> None:
    if not (math.isfinite(seconds) and MIN_SECONDS <= seconds <= MAX_SECONDS):
        raise ConfigError(f"seconds must be between {MIN_SECONDS:g} and {MAX_SECONDS:g}, got {seconds}")


def _write_json(path: Path, data) -> None:
    path.write_text(json.dumps(data, indent=2, allow_nan=False) + "\n")


def bench_step(seconds: float = 5.0, physics_hz: int = 480, stroke: str | None = None) -> dict:
    """Microseconds per physics step: (a) the bare PyBullet step of the floating body (no fluid,
    no PD), (b) the whole loop (state read, fluid, wrenches, PD, step). Each is timed
    BENCH_REPEATS times, alternating so that a burst of load elsewhere hits both, and the fastest
    repeat counts (the usual rule for timing: noise never makes code faster)."""
    _check_seconds(seconds)
    if stroke is None:
        stroke = "front_crawl" if "front_crawl" in available_strokes() else "rest"
    setup = build_swim(stroke, physics_hz=physics_hz)
    sim, start = setup.sim, setup.stroke.start
    steps = int(round(seconds * physics_hz))

    def timed(step) -> float:
        sim.reset(start.posture, start.depth_m, start.speed_m_s)
        t0 = time.perf_counter()
        for _ in range(steps):
            step()
        return (time.perf_counter() - t0) / steps * 1e6

    try:
        sim.run(BENCH_WARMUP_S)
        pairs = [(timed(sim.world.step), timed(sim.step)) for _ in range(BENCH_REPEATS)]
        bare_us, loop_us = min(p[0] for p in pairs), min(p[1] for p in pairs)
    finally:
        sim.close()
    return {"stroke": setup.stroke.name, "physics_hz": physics_hz, "steps": steps, "repeats": BENCH_REPEATS,
            "bare_step_us": bare_us, "loop_step_us": loop_us, "loop_to_bare_ratio": loop_us / bare_us,
            "realtime_factor": 1e6 / (loop_us * physics_hz)}

"""Headless runs: a ``SwimSpec``'s episode per command, run, measured and written to a folder.

``run_swim`` is ``layered-swim run`` (free swimming), ``follow_run`` is ``follow`` (a trajectory
file), ``goal_run`` is ``goal`` (SWIM's benchmark: one episode reset onto each goal in turn);
``repeatable`` reads the swim a run folder's ``config.json`` describes; ``bench_step`` times one
physics step bare and through the episode loop.
"""
from __future__ import annotations

import json
import math
import os
import platform
import resource
import shutil
import subprocess
import sys
import time
import warnings
from importlib import metadata
from pathlib import Path

import numpy as np

from layered_swim.config import ConfigError, load_json, parse
from layered_swim.control.stroke import available_strokes
from layered_swim.episode import Episode
from layered_swim.fluid.backend import FluidError
from layered_swim.outputs import COMMAND_KEY, OutputFolder, atomic_path, claim, write_json
from layered_swim.recorder import DEFAULT_LOG_HZ, SPOOL_DIR, Recorder
from layered_swim.sim.simulation import DEFAULT_SIM, SimulationDiverged
from layered_swim.spec import MIN_SECONDS, FollowTask, FreeSwimTask, GoalTask, SwimSpec
from layered_swim.tasks import swim_benchmark as bench
from layered_swim.tasks.goal import GOAL_METRICS

MAX_SECONDS = 3600.0     # a swim analyze or bench measures (run, follow, soak: SwimSpec's bounds)
BENCH_REPEATS = 5       # bare and loop timed in turn, the fastest of each kept: other load only adds time
BENCH_WARMUP_S = 0.5     # compiles (or loads) the numba fluid kernels before timing
SPIKE_BOUND_WEIGHTS = 3.0    # the SPH water's total force on the body (20 ms means) stays under 3 body weights
REPEATABLE = ("run", "follow", "goal")     # the commands `run --config` repeats from their folder


def package_version() -> str:
    try:
        return metadata.version("layered-swim")
    except metadata.PackageNotFoundError:
        return "unknown (not installed)"


def resolved_config(episode: Episode, spec: SwimSpec, command: str, **extra) -> dict:
    """A run folder's ``config.json``: the command, the swim (``spec``: enough to repeat it),
    what it resolved to (files, water, rates) and ``extra`` (the command's own settings)."""
    sim = episode.sim
    return {
        COMMAND_KEY: command,
        "swim": spec.model_dump(mode="json"),
        **extra,
        "stroke_file": episode.stroke.source,
        "stroke": episode.stroke_spec.model_dump(mode="json"),
        "body_file": sim.body.source,
        "lung_air_l": sim.body.lung_air_l,
        "medium": sim.fluid.medium.to_json(),
        "fluid_backend": {"name": sim.fluid.name, "settings": sim.fluid.settings()},
        "gravity_m_s2": sim.config.gravity_m_s2,
        "physics_hz": sim.config.physics_hz,
        "control_hz": sim.config.control_hz,
        "log_hz": spec.log_hz,
        "cycles_per_s": sim.controller.cycles_per_s,
        "task": episode.task.name,
        "seed": episode.seed,
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


def swim(episode: Episode, seconds: float, observers=(), progress: bool = False) -> Episode:
    """Run ``episode`` for ``seconds`` (a progress bar with ``progress``) and close it; its task
    keeps what it observed."""
    try:
        episode.run(seconds, observers=observers, progress=progress)
    finally:
        episode.close()
    return episode


def record(episode: Episode, seconds: float, log_hz: int = DEFAULT_LOG_HZ, progress: bool = False,
           joint_work: bool = False) -> Recorder:
    """``swim`` logging at ``log_hz``; returns the log."""
    try:
        recorder = Recorder(episode.sim, log_hz, joint_work=joint_work)
    except BaseException:
        episode.close()
        raise
    swim(episode, seconds, [recorder], progress)
    return recorder


def run_swim(spec: SwimSpec, out_dir: OutputFolder | str | Path | None = None, progress: bool = False) -> dict:
    """Free swimming: ``spec.seconds`` of its stroke; writes summary.json, log.npz, timeseries.csv
    and config.json into ``out_dir`` (default: ``runs/<stroke>-<timestamp>``; an ``OutputFolder``
    is claimed once everything is checked); returns the summary."""
    _expect(spec, FreeSwimTask, "run")
    if spec.seconds > WARM_UP_AFTER_S:
        warm_compiled_kernels(spec.stroke)
    episode = spec.episode()
    out = _claim(out_dir if out_dir is not None else default_out_dir(spec.stroke), episode)
    write_json(out / "config.json", resolved_config(episode, spec, "run"))
    return logged_swim(episode, spec.seconds, out, spec.log_hz, progress)


def logged_swim(episode: Episode, seconds: float, out_dir: Path, log_hz: int = DEFAULT_LOG_HZ,
                progress: bool = False, extra: dict | None = None, observers=(), report=None) -> dict:
    """``swim`` with its log streamed into ``out_dir`` (flat memory for any length); writes
    ``log.npz``, ``timeseries.csv`` and ``summary.json`` (``extra`` first, then the task's
    metrics, the fluid's report and ``report()``) and returns the summary. A run stopped early
    (Ctrl-C, a blow-up, a dead solver) saves what it logged and its summary, marked ``partial``,
    then stops the caller too, its message naming ``out_dir``. A write that fails (a full disk) is
    one OSError naming the file and where the log so far is kept."""
    spool = out_dir / SPOOL_DIR
    try:
        recorder = Recorder(episode.sim, log_hz, joint_work=True, spool_dir=spool)
    except BaseException:
        episode.close()
        raise
    stopped = None
    try:
        swim(episode, seconds, [recorder, *observers], progress)
    except (KeyboardInterrupt, SimulationDiverged, FluidError) as err:
        stopped = err
    except OSError as err:      # a chunk not written: the ones before it stay in the spool
        raise _unwritten(err, err.filename, _spool_kept(recorder, spool)) from None
    result = {**(extra or {}), **_metrics(episode, stopped), **fluid_report(episode), **(report() if report else {})}
    if stopped is not None:
        interrupted = isinstance(stopped, KeyboardInterrupt)
        reason = "interrupted" if interrupted else " ".join(str(stopped).split())
        result["partial"] = {"stopped_at_s": episode.time_s, "of_s": seconds, "reason": reason}
        if not interrupted:     # the one line the user reads says where the run so far is
            stopped.args = (f"{reason}; the run so far is saved in {out_dir}",)
    _save(recorder, out_dir, result, nothing_logged=stopped is not None and recorder.empty)
    if stopped is not None:
        raise stopped
    return result


def _save(recorder: Recorder, out_dir: Path, result: dict, nothing_logged: bool) -> None:
    """``logged_swim``'s log, then summary.json; with nothing logged, no log and no spool (it
    would hold only the names)."""
    spool, summary = out_dir / SPOOL_DIR, out_dir / "summary.json"
    kept = None
    if nothing_logged:
        shutil.rmtree(spool)
    else:
        try:
            recorder.save(out_dir)
        except OSError as err:      # the spool goes only once log.npz and timeseries.csv are whole
            raise _unwritten(err, err.filename, _spool_kept(recorder, spool)) from None
        kept = out_dir / "log.npz"
    try:
        write_json(summary, result)
    except OSError as err:
        raise _unwritten(err, summary, kept) from None


def _spool_kept(recorder: Recorder, spool: Path) -> Path | None:
    """``spool`` once a chunk has reached it; before that it holds only the names, and goes."""
    if recorder.n_chunks:
        return spool
    shutil.rmtree(spool, ignore_errors=True)    # tidying up must not hide the error being reported
    return None


def _unwritten(err: OSError, path, kept: Path | None) -> OSError:
    """A failed write (a full disk) as one line: the file, and where the log so far is kept."""
    where = f"the log so far is kept in {kept}" if kept else "no log is kept"
    return OSError(err.errno, f"{err.strerror}; {where}", path)


WARM_UP_AFTER_S = 600.0     # runs longer than this have the numba kernels compiled in a child first


def warm_compiled_kernels(stroke: str) -> None:
    """Swim a moment in a child process, where numba compiles the kernels and caches them on disk;
    this process then loads them compiled. A process that compiles keeps LLVM's working memory
    (~100 MB) for the rest of its life, which for a long run is most of its footprint beyond the
    imports. Best effort: if the child fails, this process compiles as before."""
    code = ("from layered_swim.runs import Episode, FreeSwim, Recorder\n"
            f"episode = Episode({stroke!r}, FreeSwim())\n"
            "recorder = Recorder(episode.sim, joint_work=True)\n"
            "episode.run(0.2, observers=[recorder])\n"
            "recorder.arrays(); episode.metrics()\n")
    subprocess.run([sys.executable, "-c", code], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False,
                   timeout=900)


SOAK_SAMPLE_S = 10.0        # simulated seconds between memory samples
SOAK_WARMUP_SHARE = 0.1     # growth is counted from this far in: imports, compiles and first buffers come before


def rss_mb() -> float:
    """This process's resident memory now (Linux's /proc), else its peak so far."""
    try:
        pages = int(Path("/proc/self/statm").read_text().split()[1])
        return pages * os.sysconf("SC_PAGE_SIZE") / 2**20
    except (OSError, ValueError, IndexError):
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def soak(hours: float, stroke: str, out_dir: OutputFolder | Path, progress: bool = False) -> dict:
    """Swim ``hours`` of simulated time with the log streaming into ``out_dir``, sampling memory
    every ``SOAK_SAMPLE_S``; the summary adds RSS at the start of the counted stretch, at the end
    and at peak, the growth over the stretch, and whether everything stayed finite."""
    if not (math.isfinite(hours) and 0.0 < hours <= 24.0):
        raise ConfigError(f"--hours must be in (0, 24], got {hours}")
    spec = SwimSpec(stroke=stroke, seconds=hours * 3600.0)
    warm_compiled_kernels(stroke)
    episode = spec.episode()
    out_dir = _claim(out_dir, episode)
    write_json(out_dir / "config.json", resolved_config(episode, spec, "soak", hours=hours))
    every = int(round(SOAK_SAMPLE_S * episode.sim.config.physics_hz))
    samples = [(0.0, rss_mb())]

    def sample(sim) -> None:
        if sim.steps % every == 0:
            samples.append((sim.time_s, rss_mb()))

    def memory() -> dict:
        times, rss = np.array(samples).T
        counted = rss[times >= SOAK_WARMUP_SHARE * times[-1]]
        growth = float(counted[-1] - counted[0])
        span_h = max(times[-1] * (1.0 - SOAK_WARMUP_SHARE), 1e-9) / 3600.0
        return {"memory": {"samples": len(samples), "rss_start_mb": round(float(counted[0]), 1),
                           "rss_end_mb": round(float(rss[-1]), 1), "rss_peak_mb": round(float(rss.max()), 1),
                           "growth_mb": round(growth, 1), "growth_mb_per_hour": round(growth / span_h, 1),
                           "process_peak_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1)}}

    result = logged_swim(episode, spec.seconds, out_dir, progress=progress, observers=[sample], report=memory)
    numbers = [v for v in result.values() if isinstance(v, float)]
    result["finite"] = bool(np.isfinite(numbers).all())
    write_json(out_dir / "summary.json", result)
    return result


def _metrics(episode: Episode, stopped: BaseException | None) -> dict:
    """The task's metrics; a run stopped too early to have them gets none rather than a second
    error, numpy's warnings about empty data or NaNs that summary.json cannot hold."""
    if stopped is None:
        return episode.metrics()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)     # means of no or one sample: NaN, refused below
            metrics = episode.metrics()
        json.dumps(metrics, allow_nan=False)
    except (ValueError, IndexError, ZeroDivisionError, ConfigError):
        return {}
    return metrics


def follow_run(spec: SwimSpec, out_dir: OutputFolder | str | Path | None = None, steering=None) -> dict:
    """Follow the spec's trajectory for ``spec.seconds``. With ``spec.policy``, ``steering`` (its
    ``learned.steering_for(spec)``) puts the learned residual in charge of its own reference
    controller. Without ``out_dir`` only the summary comes back."""
    _expect(spec, FollowTask, "follow")
    if (spec.policy is None) != (steering is None):
        raise ConfigError("a swim with a policy needs its steering, and only such a swim")
    episode = spec.episode() if steering is None else spec.episode(steering.wrap, steering.layers)
    target = episode.task.target
    check_path_in_pool(episode, target, spec.seconds)
    observers = [] if steering is None else [steering.driver(episode)]
    head = {"trajectory": target.name, "stroke": spec.stroke,
            "layers": (spec.layer_set if steering is None else steering.layers).describe(),
            "current_m_s": list(spec.medium.current_m_s),
            **({"water": spec.medium.flow.name} if spec.medium.flow else {}),
            "seconds": spec.seconds, "seed": spec.seed, **({} if steering is None else steering.summary)}
    if out_dir is None:
        swim(episode, spec.seconds, observers)
        return {**head, **episode.metrics(), **fluid_report(episode)}
    out = _claim(out_dir, episode)
    write_json(out / "config.json", resolved_config(episode, spec, "follow", trajectory_file=str(target.source),
                                                    trajectory=_dump(target.spec)))
    try:
        return logged_swim(episode, spec.seconds, out, spec.log_hz, extra=head, observers=observers)
    finally:
        with atomic_path(out / "track.npz") as tmp:
            np.savez_compressed(tmp, **episode.task.track())


def goal_episode(spec: SwimSpec, wrap=None) -> Episode:
    """An episode of SWIM's goal reaching (``spec.task`` a goal task); ``reset(goal=k)`` picks the
    goal. ``wrap``: a controller around the layered one (a learned residual)."""
    _expect(spec, GoalTask, "goal")
    return spec.episode(wrap)


def reach_goal(episode: Episode, goal: int, observers=()) -> dict:
    """Swim to goal ``goal`` for the pool's horizon, or until the pool's walls or floor end the
    swim: Pos, Prog, Dev and Roll over the whole horizon, and whether it swam to the end."""
    episode.reset(goal=goal)
    episode.run(episode.task.duration_s, observers=observers)
    return episode.metrics()


def goal_run(spec: SwimSpec, out_dir: OutputFolder | str | Path | None = None) -> dict:
    """Every goal of the spec's pool in turn, one episode reset onto each. With ``out_dir``, each
    goal's swim is logged into ``goal-<k>/`` there (a run folder of its own: log.npz,
    timeseries.csv, summary.json), beside config.json and the summary of all."""
    episode = goal_episode(spec)
    out = None if out_dir is None else _claim(out_dir, episode)
    per_goal = []
    try:
        if out is not None:
            write_json(out / "config.json", resolved_config(episode, spec, "goal"))
        for k in range(len(episode.task.goals)):
            if out is None:
                per_goal.append({**reach_goal(episode, k), **fluid_report(episode)})
                continue
            episode.reset(goal=k)
            folder = out / f"goal-{k}"
            folder.mkdir(exist_ok=True)
            recorder = Recorder(episode.sim, spec.log_hz, joint_work=True, spool_dir=folder / SPOOL_DIR)
            episode.run(episode.task.duration_s, observers=[recorder])
            per_goal.append({**episode.metrics(), **fluid_report(episode)})
            recorder.save(folder)
            write_json(folder / "summary.json", per_goal[-1])
    finally:
        episode.close()
    mean = {k: float(np.mean([g[k] for g in per_goal])) for k in GOAL_METRICS}
    mean["success_rate"] = float(np.mean([g["success"] for g in per_goal]))
    pool = spec.task.pool
    result = {"pool": pool, "stroke": spec.stroke, "layers": spec.layer_set.describe(),
              "current_m_s": list(spec.medium.current_m_s), "fluid_backend": spec.backend, **mean, "goals": per_goal,
              "swim_published": bench.SWIM_PUBLISHED.get(pool)}
    if out is not None:
        write_json(out / "summary.json", result)
    return result


def repeatable(config_path: str | Path) -> tuple[str, SwimSpec]:
    """The command and swim a run, follow or goal folder's ``config.json`` describes, checked:
    swum again (``layered-swim run --config``) it logs the same bits."""
    config = load_json(config_path)
    command = config.get(COMMAND_KEY) if isinstance(config, dict) else None
    if command not in REPEATABLE or not isinstance(config.get("swim"), dict):
        raise ConfigError(f"{config_path}: not the config.json of a {', '.join(REPEATABLE)} folder of this version "
                          "(no command and swim)")
    # Folders from before the own integrator were stepped by PyBullet: so they are again.
    return command, parse(SwimSpec, {"integrator": "bullet", **config["swim"]}, f"{config_path}: swim")


def _expect(spec: SwimSpec, task: type, command: str) -> None:
    if not isinstance(spec.task, task):
        raise ConfigError(f"`{command}` swims a {task.model_fields['kind'].default} task, not {spec.task.kind}")


def sph_settings_for(pool_name: str, water_depth_m: float | None = None, **options):
    """SPH settings whose pool is SWIM's pool ``pool_name`` (length, width and, unless given,
    water depth)."""
    from layered_swim.fluid.sph import SphSettings

    pool = bench.pool(pool_name)
    depth = pool.depth_m if water_depth_m is None else water_depth_m
    return SphSettings(pool_size_m=(pool.length_m, pool.width_m, depth), **options)


def fluid_report(episode: Episode) -> dict:
    """What the fluid model says about the swim (the SPH pool, settle, timing; nothing for the
    plates), with its peak total force on the body after the settle against the stated bound."""
    report = episode.sim.fluid.report()
    if not report:
        return {}
    if "peak_total_force_n" in report:
        bound = SPIKE_BOUND_WEIGHTS * episode.body.total_mass_kg * episode.sim.config.gravity_m_s2
        report.update(force_bound_n=bound, within_force_bound=report["peak_total_force_n"] <= bound)
    return {"fluid": report}


def check_path_in_pool(episode: Episode, target, seconds: float) -> None:
    """A bounded fluid must hold the target's path: refuse in one line before swimming."""
    domain = episode.sim.fluid.domain_xy_m(episode.sim.state)
    if domain is None:
        return
    lo, hi = domain
    times = np.linspace(0.0, seconds, max(2, int(seconds * 10)))
    path = np.array([target.position(t)[:2] for t in times])
    outside = ~np.all((path > lo) & (path < hi), axis=1)
    if outside.any():
        t = times[int(np.argmax(outside))]
        raise ConfigError(f"the target leaves the {hi[0] - lo[0]:g} x {hi[1] - lo[1]:g} m SPH pool at t = {t:.1f} s "
                          f"(at x = {path[outside][0][0]:.2f}, y = {path[outside][0][1]:.2f} m); "
                          "use --pool large, fewer --seconds or --backend plate")


def _claim(out: OutputFolder | str | Path, episode: Episode) -> Path:
    """The output folder claimed now that the episode (stroke, files, settings) is built: a
    command refused before this point has touched nothing. The episode is closed if it fails."""
    try:
        return claim(out)
    except BaseException:
        episode.close()
        raise


def check_seconds(seconds: float) -> None:
    if not (math.isfinite(seconds) and MIN_SECONDS <= seconds <= MAX_SECONDS):
        raise ConfigError(f"seconds must be between {MIN_SECONDS:g} and {MAX_SECONDS:g}, got {seconds}")


def _dump(spec):
    return spec.model_dump(mode="json") if spec is not None else None


def bench_sph(seconds: float = 0.5, settings=None, stroke: str = "breaststroke") -> dict:
    """The SPH backend's speed: particles, milliseconds per physics step, wall seconds per
    simulated second, and the share of the step spent outside SPlisHSPlasH's own calls (our
    coupling: PyBullet, the controller, the worker's messages, placing boxes and reading forces).
    The settle is built and timed apart, before the timed swim."""
    check_seconds(seconds)
    episode = Episode(stroke, backend="sph", fluid_settings=settings)
    fluid = episode.sim.fluid
    try:
        episode.run(steps=1)                    # builds the pool and settles it
        solver_before, steps = fluid.solver_s, int(round(seconds * episode.sim.config.physics_hz))
        t0 = time.perf_counter()
        episode.run(steps=steps)
        wall = time.perf_counter() - t0
        solver = fluid.solver_s - solver_before
        report = fluid.report()
    finally:
        episode.close()
    return {"stroke": stroke, "fluid_particles": report["fluid_particles"],
            "boundary_particles": report["boundary_particles"],
            "particle_radius_m": fluid.sph_settings.particle_radius_m,
            "threads": fluid.sph_settings.solver_threads, "steps": steps, "ms_per_step": 1e3 * wall / steps,
            "wall_s_per_simulated_s": wall / seconds, "solver_ms_per_step": 1e3 * solver / steps,
            "outside_solver_share": 1.0 - solver / wall, "settle_wall_s": report["settle_wall_s"],
            "build_s": report["build_s"]}


def bench_step(seconds: float = 5.0, physics_hz: int | None = None, stroke: str | None = None,
               integrator: str = DEFAULT_SIM.integrator) -> dict:
    """Microseconds per physics step: (a) the bare PyBullet step of the floating body (no fluid,
    no PD), (b) the whole loop (state read, fluid, wrenches, PD, step) through the episode runner.
    Each is timed BENCH_REPEATS times, alternating so that a burst of load elsewhere hits both, and
    the fastest repeat counts (the usual rule for timing: noise never makes code faster)."""
    check_seconds(seconds)
    if stroke is None:
        stroke = "front_crawl" if "front_crawl" in available_strokes() else "rest"
    episode = Episode(stroke, integrator=integrator, **({} if physics_hz is None else {"physics_hz": physics_hz}))
    physics_hz = episode.sim.config.physics_hz
    steps = int(round(seconds * physics_hz))
    world = episode.sim.world

    def bare() -> None:
        for _ in range(steps):   # PyBullet's step alone: the reference the loop is measured against
            world.step_bullet()

    def timed(run) -> float:
        episode.reset()
        t0 = time.perf_counter()
        run()
        return (time.perf_counter() - t0) / steps * 1e6

    try:
        episode.run(BENCH_WARMUP_S)
        pairs = [(timed(bare), timed(lambda: episode.run(steps=steps))) for _ in range(BENCH_REPEATS)]
        bare_us, loop_us = min(p[0] for p in pairs), min(p[1] for p in pairs)
    finally:
        episode.close()
    return {"stroke": episode.stroke.name, "physics_hz": physics_hz, "integrator": integrator, "steps": steps,
            "repeats": BENCH_REPEATS,
            "bare_step_us": bare_us, "loop_step_us": loop_us, "loop_to_bare_ratio": loop_us / bare_us,
            "realtime_factor": 1e6 / (loop_us * physics_hz)}

"""``layered-swim fit-stroke``: a search (CMA-ES, the ``cma`` library of the [fit] extra) over a
stroke file's numbers, each candidate swum and measured as ``validate strokes`` measures, and
scored against target ranges.

A fit file (YAML) names the stroke, the ranges to reach (``targets``: any figure of
``validate strokes``, plus ``active_drag_x_narita``) and the numbers the search may move
(``knobs``, each with its range):

- ``period_s``: the cycle's period;
- ``JOINT.AXIS[K]``: the value (degrees) of the channel's key K, counted from 0 in time order,
  e.g. ``shoulder_l.flexion[3]``;
- ``JOINT.AXIS[K]:time``: that key's time, moved within its range (which must stay clear of the
  channel's other keys and their ranges, so the keys keep their order and a stroke the search
  wrote takes the same fit file);
- ``JOINT.AXIS:scale``: every value of the channel pulled towards (< 1) or pushed away from
  (> 1) the channel's mean;
- ``JOINT.AXIS:offset``: degrees added to every value of the channel;
- ``SEQ/JOINT.AXIS[K]`` (and ``:time``, ``:scale``, ``:offset``): the same in perturbation
  sequence SEQ's keys (offsets, degrees; ``:scale`` multiplies them, about 0), e.g.
  ``yaw_left/elbow_l.flexion[1]``; with the targets
  ``yaw_left_deg_per_s``/``yaw_right_deg_per_s`` (each yaw sequence's turn at full weight, as
  ``calibrate`` measures it) the search re-tunes the steering's turns for a changed stroke, and
  with ``yaw_left_radius_m``/``yaw_right_radius_m`` (the radius of the circle it swims there) for
  tighter ones;
- ``rest.JOINT.AXIS``: the rest pose's angle (degrees) of a coordinate no key sets (held all
  cycle: the head's or the back's carriage).

A mirrored joint (``mirror_of``) follows its source: name the source. The score is the sum over
targets of weight x (distance outside the range / scale)^2, 0 when every target holds. Each
generation is appended to ``history.jsonl`` and the best stroke so far written to ``best.yaml``;
``--resume`` replays the history into a fresh search with the same seed (CMA-ES draws the same
candidates, so the replayed search is the one that was stopped) and goes on.
"""
from __future__ import annotations

import copy
import hashlib
import json
import math
import multiprocessing
import re
import tempfile
from concurrent.futures import ProcessPoolExecutor
from functools import lru_cache
from pathlib import Path

import numpy as np
import yaml
from pydantic import Field, model_validator

from layered_swim.analysis.calibrate import AXIS_INDEX, calibration_swim
from layered_swim.analysis.stroke_analysis import analysis_config
from layered_swim.analysis.stroke_validation import BUOY_DRAG_KG_M, QUANTITIES, stroke_figures, swim_measured, vpm
from layered_swim.body.layout import joint_layout
from layered_swim.body.model import load_body
from layered_swim.config import ConfigError, Strict, between, file_path, load_yaml, parse, read_text, search_dirs
from layered_swim.control.calibration import SEQUENCE_AXIS
from layered_swim.control.stroke import stroke_path
from layered_swim.outputs import atomic_path, write_json
from layered_swim.sim.simulation import SimulationDiverged

HISTORY = "history.jsonl"
BEST_STROKE = "best.yaml"
BEST = "best.json"
RESOLVED = "fit.json"
NOT_MEASURED_PENALTY = 100.0        # a candidate that blew up, did not cycle, or lacks a targeted figure
# Each yaw sequence at weight 1, tempo 1: how fast it turns, how tight (the radius of its circle),
# and its speed, pitch and roll there.
TURNS = tuple(f"{sequence}_{figure}" for sequence in ("yaw_left", "yaw_right")
              for figure in ("deg_per_s", "radius_m", "speed_m_s", "pitch_deg", "roll_deg"))
FIGURES = (*QUANTITIES, "active_drag_x_narita", *TURNS)
REST = re.compile(r"^rest\.(?P<joint>\w+)\.(?P<axis>\w+)$")
KNOB = re.compile(r"^(?:(?P<seq>\w+)/)?(?P<joint>\w+)\.(?P<axis>\w+)(?:\[(?P<index>\d+)\])?"
                  r"(?::(?P<kind>time|scale|offset))?$")


class Target(Strict):
    min: between(-1e6, 1e6) | None = None
    max: between(-1e6, 1e6) | None = None
    weight: between(0.0, 1e6, above=True) = 1.0
    scale: between(0.0, 1e6, above=True) | None = None     # the distance outside that counts 1 (default: see below)

    @model_validator(mode="after")
    def _bounds(self):
        if self.min is None and self.max is None:
            raise ValueError("give min, max or both")
        if self.min is not None and self.max is not None and self.min > self.max:
            raise ValueError(f"min {self.min} is above max {self.max}")
        return self

    def unit(self) -> float:
        """The distance outside the range that scores 1: ``scale``, else the range's width, else a
        tenth of its one bound (at least 1e-3)."""
        if self.scale is not None:
            return self.scale
        if self.min is not None and self.max is not None and self.max > self.min:
            return self.max - self.min
        bound = self.max if self.min is None else self.min
        return max(0.1 * abs(bound), 1e-3)

    def miss(self, value: float | None) -> float | None:
        """How far outside the range, in units; None for a figure that could not be had."""
        if value is None or not math.isfinite(value):
            return None
        below = self.min - value if self.min is not None else 0.0
        above = value - self.max if self.max is not None else 0.0
        return max(below, above, 0.0) / self.unit()


class Knob(Strict):
    min: between(-1e4, 1e4)
    max: between(-1e4, 1e4)

    @model_validator(mode="after")
    def _order(self):
        if not self.min < self.max:
            raise ValueError(f"min {self.min} must be below max {self.max}")
        return self


class FitSpec(Strict):
    stroke: str
    seconds: between(6.0, 600.0) = 16.0          # each swim's length
    settle_s: between(0.0, 300.0) = 4.0          # left out at the start of each swim
    buoy_kg_m: between(0.0, 1e3, above=True) = BUOY_DRAG_KG_M
    added_mass: bool = True                      # false: the swims without the plates' added mass
    population: int = Field(12, ge=4, le=512)
    generations: int = Field(60, ge=1, le=100_000)
    sigma: between(0.0, 0.5, above=True) = 0.2   # CMA-ES's first step, a fraction of each knob's range
    seed: int = Field(1, ge=1, le=2**31 - 1)
    targets: dict[str, Target]
    knobs: dict[str, Knob]

    @model_validator(mode="after")
    def _names(self):
        if not self.targets:
            raise ValueError("name at least one target")
        if not self.knobs:
            raise ValueError("name at least one knob")
        for name in self.targets:
            if name not in FIGURES:
                raise ValueError(f"unknown target '{name}' (known: {', '.join(FIGURES)})")
        for name in self.knobs:
            if name != "period_s" and not KNOB.match(name) and not REST.match(name):
                raise ValueError(f"knob '{name}': expected period_s, JOINT.AXIS[K], JOINT.AXIS[K]:time, "
                                 "JOINT.AXIS:scale, JOINT.AXIS:offset or rest.JOINT.AXIS")
        if self.settle_s + 4.0 > self.seconds:
            raise ValueError(f"seconds {self.seconds} leaves under 4 s after settle_s {self.settle_s}")
        return self

    def needs_towing(self) -> bool:
        return any(name in ("active_drag_n", "active_drag_x_narita", "propelling_efficiency") for name in self.targets)

    def needs_turns(self) -> bool:
        return any(name in TURNS for name in self.targets)


def load_fit(path: str | Path, stroke: str | None = None, generations: int | None = None
             ) -> tuple[FitSpec, dict, Path]:
    """The fit file (its ``stroke`` and ``generations`` replaced where given), its stroke file read
    as data and the stroke's path; every knob checked against the stroke (one ConfigError line
    naming the file and the knob)."""
    path = file_path(path, tuple(d / "fit" for d in search_dirs("strokes")), "fit file")
    data = load_yaml(path)
    if isinstance(data, dict):
        data = {**data, **{k: v for k, v in (("stroke", stroke), ("generations", generations)) if v is not None}}
    spec = parse(FitSpec, data, path)
    source = stroke_path(spec.stroke)
    stroke_data = load_yaml(source)
    if not isinstance(stroke_data, dict):
        raise ConfigError(f"{source}: expected a mapping at the top level")
    for name, knob in spec.knobs.items():
        try:
            check_knob(stroke_data, name, knob, spec.knobs)
        except ConfigError as err:
            raise ConfigError(f"{path}: knob '{name}': {err}") from None
    return spec, stroke_data, source


def _keys(stroke: dict, seq: str | None) -> dict:
    """The basic cycle's keys, or perturbation sequence ``seq``'s (offsets)."""
    if seq is None:
        return stroke.get("keys") or {}
    sequence = (stroke.get("perturbations") or {}).get(seq)
    if sequence is None:
        raise ConfigError(f"the stroke has no perturbation sequence '{seq}'")
    if "mirror_of" in sequence:
        raise ConfigError(f"'{seq}' mirrors '{sequence['mirror_of']}': name that sequence")
    return sequence.get("keys") or {}


def _channel(stroke: dict, joint: str, axis: str, seq: str | None = None) -> dict:
    keys = _keys(stroke, seq)
    if joint not in keys:
        raise ConfigError(f"the stroke has no keys for joint '{joint}'")
    entry = keys[joint]
    if "mirror_of" in entry:
        raise ConfigError(f"'{joint}' mirrors '{entry['mirror_of']}': name that joint")
    if axis not in entry or not isinstance(entry[axis], dict):
        raise ConfigError(f"joint '{joint}' has no keys for axis '{axis}'")
    return entry[axis]


def _key_time(channel: dict, index: str) -> float:
    """The time of the channel's key ``index`` (in time order)."""
    times = sorted(channel, key=float)
    if int(index) >= len(times):
        raise ConfigError(f"no key {index}: the channel has {len(times)} (0 to {len(times) - 1})")
    return times[int(index)]


def check_knob(stroke: dict, name: str, knob: Knob, knobs: dict) -> None:
    if name == "period_s":
        if not (0.2 <= knob.min and knob.max <= 10.0):
            raise ConfigError("the period's range must lie within 0.2-10 s")
        return
    rest = REST.match(name)
    if rest:
        if rest["axis"] in ((stroke.get("keys") or {}).get(rest["joint"]) or {}):
            raise ConfigError(f"keys set {rest['joint']}.{rest['axis']} all cycle, so its rest angle does "
                              f"nothing: use {rest['joint']}.{rest['axis']}:offset")
        return
    m = KNOB.match(name)
    channel = _channel(stroke, m["joint"], m["axis"], m["seq"])
    if (m["index"] is None) != (m["kind"] in ("scale", "offset")):
        raise ConfigError("a key knob names its key (JOINT.AXIS[K]); a :scale or :offset knob does not")
    if m["index"] is None:
        return
    _key_time(channel, m["index"])
    if m["kind"] != "time":
        return
    if not (0.0 <= knob.min and knob.max < 1.0):
        raise ConfigError("a key's time must range within [0, 1)")
    for k, other in enumerate(sorted(channel, key=float)):
        if k == int(m["index"]):
            continue
        moved = knobs.get(f"{m['seq'] + '/' if m['seq'] else ''}{m['joint']}.{m['axis']}[{k}]:time")
        low, high = (moved.min, moved.max) if moved else (float(other), float(other))
        if not (high < knob.min or low > knob.max):
            raise ConfigError(f"its range {knob.min:g}-{knob.max:g} meets key {k}'s time ({low:g}-{high:g}): "
                              "keep the keys in order")


def apply_knobs(stroke: dict, values: dict[str, float]) -> dict:
    """A copy of the stroke data with every knob set: key values and times first, then each
    channel's scale, then its offset. Pure."""
    out = copy.deepcopy(stroke)
    if "period_s" in values:
        out["period_s"] = float(values["period_s"])
    later = []
    moves: dict[tuple, dict] = {}
    for name, value in values.items():
        rest = REST.match(name)
        if rest:
            out.setdefault("rest_pose", {}).setdefault(rest["joint"], {})[rest["axis"]] = float(value)
            continue
        m = KNOB.match(name)
        if name == "period_s" or m is None:
            continue
        if m["index"] is None:
            later.append((m["kind"], m["seq"], m["joint"], m["axis"], float(value)))
            continue
        channel = _keys(out, m["seq"])[m["joint"]][m["axis"]]
        t = _key_time(channel, m["index"])
        if m["kind"] == "time":
            moves.setdefault((m["seq"], m["joint"], m["axis"]), {})[t] = float(value)
        else:
            channel[t] = float(value)
    for (seq, joint, axis), moved in moves.items():
        keys = _keys(out, seq)
        keys[joint][axis] = dict(sorted(((round(moved.get(t, t), 4), v) for t, v in keys[joint][axis].items()),
                                        key=lambda item: item[0]))
    for kind in ("scale", "offset"):
        for knob_kind, seq, joint, axis, value in later:
            if knob_kind != kind:
                continue
            channel = _keys(out, seq)[joint][axis]
            mean = float(np.mean(list(channel.values()))) if seq is None else 0.0    # offsets scale about 0
            for t, v in channel.items():
                channel[t] = mean + value * (v - mean) if kind == "scale" else v + value
    return out


def within_reach(stroke: dict, lower_deg: dict[str, float], upper_deg: dict[str, float]) -> dict:
    """The stroke data with every key and rest angle held inside its joint's range of motion
    (``JOINT.AXIS`` -> degrees): a knob that would push a key past it stops at the end, so a
    search step there is a body at its limit, not a stroke file the loader refuses. Pure."""
    out = copy.deepcopy(stroke)
    for section in ("keys", "rest_pose"):
        for joint, axes in (out.get(section) or {}).items():
            for axis, value in axes.items():
                name = f"{joint}.{axis}"
                if name not in lower_deg:
                    continue
                low, high = lower_deg[name], upper_deg[name]
                if isinstance(value, dict):
                    axes[axis] = {t: min(max(float(v), low), high) for t, v in value.items()}
                elif isinstance(value, (int, float)):
                    axes[axis] = min(max(float(value), low), high)
    return out


def score(spec: FitSpec, figures: dict | None) -> tuple[float, dict]:
    """The candidate's score (0: every target holds) and each target's miss in its units."""
    misses = {}
    total = 0.0
    for name, target in spec.targets.items():
        miss = target.miss(None if figures is None else figures.get(name))
        misses[name] = miss
        total += target.weight * (NOT_MEASURED_PENALTY if miss is None else miss**2)
    return total, misses


# --- one candidate, swum in a worker process --------------------------------------------------

def swim_candidate(job: dict) -> dict:
    """The worker's task: write the candidate stroke to a temporary file and swim it freely (and
    towing the buoy where asked); every figure, or the error line."""
    with tempfile.TemporaryDirectory(prefix="fit-stroke-") as tmp:
        path = Path(tmp) / f"{job['stroke']['name']}.yaml"
        path.write_text(yaml.safe_dump(within_reach(job["stroke"], *_ranges_deg()), sort_keys=False))
        try:
            base = analysis_config(str(path), job["seconds"], settle_s=job["settle_s"],
                                   plate=None if job["added_mass"] else {"added_mass": False})
            free = swim_measured({**base, "buoy_kg_m": None})
            towing = swim_measured({**base, "buoy_kg_m": job["buoy_kg_m"]}) if job["towing"] else None
            turns = full_weight_turns(str(path), float(job["stroke"]["period_s"])) if job["turns"] else {}
        except (ConfigError, SimulationDiverged) as err:
            return {"error": str(err)}
    for swum in (free, towing):
        if swum is not None and "error" in swum:
            return {"error": swum["error"]}
    method = vpm(free, towing, job["buoy_kg_m"]) if towing is not None else None
    figures = stroke_figures(free, method)
    figures["active_drag_x_narita"] = method["ratio_to_narita"] if method else None
    return {"figures": {k: _plain(v) for k, v in {**figures, **turns}.items()}}


def full_weight_turns(path: str, period_s: float) -> dict[str, float | None]:
    """How fast each yaw sequence turns the swimmer at full weight and tempo 1, as ``calibrate``
    measures it (its turn per cycle less the unperturbed drift), per second: a slower stroke
    turns less often, and steering needs turns per second; and how tight: the radius of the
    circle it swims (distance per cycle over turn per cycle; None where it turns the other way);
    and how it swims there: its speed along the track and its last cycle's mean pitch and shoulder
    roll (a turn that stands the swimmer up or rolls it over tightens its circle by stalling, and
    steering then takes it for stood up or rolled over)."""
    drift = calibration_swim((path, None, 0.0, 1.0))[0][AXIS_INDEX["yaw"]]
    out = {}
    for sequence in ("yaw_left", "yaw_right"):
        change, _, roll_rad, pitch_rad, _, per_cycle_m = calibration_swim((path, sequence, 1.0, 1.0))
        turn_rad = SEQUENCE_AXIS[sequence][1] * (change - drift)
        out[f"{sequence}_deg_per_s"] = math.degrees(turn_rad) / period_s
        out[f"{sequence}_radius_m"] = per_cycle_m / turn_rad if turn_rad > 0.0 else None
        out[f"{sequence}_speed_m_s"] = per_cycle_m / period_s
        out[f"{sequence}_pitch_deg"] = math.degrees(pitch_rad)
        out[f"{sequence}_roll_deg"] = math.degrees(roll_rad)
    return out


@lru_cache(maxsize=1)
def _ranges_deg() -> tuple[dict[str, float], dict[str, float]]:
    """Every joint coordinate's range of motion in degrees, by ``JOINT.AXIS``."""
    layout = joint_layout(load_body())
    return ({n: math.degrees(v) for n, v in zip(layout.names, layout.lower_rad)},
            {n: math.degrees(v) for n, v in zip(layout.names, layout.upper_rad)})


def _plain(value):
    return float(value) if isinstance(value, (int, float, np.floating)) else value


# --- the search ---------------------------------------------------------------------------------

class Search:
    """CMA-ES over the knobs, normalised to [0, 1] each; ``history`` one dict per generation."""

    def __init__(self, spec: FitSpec, stroke: dict):
        import cma

        self.spec, self.stroke = spec, stroke
        self.names = list(spec.knobs)
        self.low = np.array([spec.knobs[n].min for n in self.names])
        self.high = np.array([spec.knobs[n].max for n in self.names])
        self.start_x = np.clip((self.start_values() - self.low) / (self.high - self.low), 0.0, 1.0)
        self.es = cma.CMAEvolutionStrategy(self.start_x.tolist(), spec.sigma, {
            "bounds": [0.0, 1.0], "popsize": spec.population, "seed": spec.seed, "verbose": -9})
        self.history: list[dict] = []

    def start_values(self) -> np.ndarray:
        values = []
        for name in self.names:
            m, rest = KNOB.match(name), REST.match(name)
            if name == "period_s":
                values.append(float(self.stroke["period_s"]))
            elif rest:
                pose = (self.stroke.get("rest_pose") or {}).get(rest["joint"]) or {}
                values.append(float(pose.get(rest["axis"], 0.0)))
            elif m["kind"] == "scale":
                values.append(1.0)
            elif m["kind"] == "offset":
                values.append(0.0)
            else:
                channel = _keys(self.stroke, m["seq"])[m["joint"]][m["axis"]]
                t = _key_time(channel, m["index"])
                values.append(float(t) if m["kind"] == "time" else float(channel[t]))
        return np.array(values)

    def knob_values(self, x) -> dict[str, float]:
        real = self.low + np.asarray(x) * (self.high - self.low)
        return {name: round(float(v), 4) for name, v in zip(self.names, real)}

    def ask(self) -> list[list[float]]:
        return [list(map(float, x)) for x in self.es.ask()]

    def tell(self, xs: list[list[float]], scores: list[float]) -> None:
        self.es.tell([np.array(x) for x in xs], scores)


def fingerprint(spec: FitSpec, stroke_text: str) -> str:
    """What makes a history replayable: the fit file less its length (--generations may raise it)."""
    text = json.dumps({"fit": spec.model_dump(mode="json", exclude={"generations"}), "stroke": stroke_text},
                      sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def replay(search: Search, out: Path, key: str) -> None:
    """Feed the history in ``out`` to a fresh search: the same candidates must come out."""
    lines = read_text(out / HISTORY).splitlines() if (out / HISTORY).is_file() else []
    for number, line in enumerate(lines, 1):
        try:
            entry = json.loads(line)
        except ValueError:
            if number == len(lines):
                break            # the line being written when the search stopped
            raise ConfigError(f"{out / HISTORY}: line {number} is not JSON") from None
        if entry.get("fit") != key:
            raise ConfigError(f"{out / HISTORY}: written for another fit file or stroke; start over with --overwrite")
        if entry["generation"] == 0:
            search.history.append(entry)
            continue
        xs = search.ask()
        if not np.allclose(xs, entry["x"], atol=1e-9):
            raise ConfigError(f"{out / HISTORY}: generation {entry['generation']} does not replay (another cma "
                              "version?); start over with --overwrite")
        search.tell(xs, entry["scores"])
        search.history.append(entry)


def best_of(history: list[dict]) -> dict | None:
    best = None
    for entry in history:
        for i, s in enumerate(entry["scores"]):
            if best is None or s < best["score"]:
                best = {"generation": entry["generation"], "score": s, "knobs": entry["knobs"][i],
                        "figures": entry["figures"][i], "misses": entry["misses"][i]}
    return best


def fit(spec: FitSpec, stroke: dict, stroke_text: str, out: Path, workers: int = 2, resume: bool = False,
        progress: bool = False, say=None) -> dict:
    """Run (or go on with) the search into ``out``; the best candidate's summary."""
    search = Search(spec, stroke)
    key = fingerprint(spec, stroke_text)
    if resume:
        replay(search, out, key)
    else:
        write_json(out / RESOLVED, {"fit": spec.model_dump(mode="json"), "fingerprint": key})
    from tqdm import tqdm

    def swim_all(candidates: list[dict]) -> list[dict]:
        jobs = [{"stroke": apply_knobs(stroke, knobs), "seconds": spec.seconds, "settle_s": spec.settle_s,
                 "buoy_kg_m": spec.buoy_kg_m, "towing": spec.needs_towing(), "turns": spec.needs_turns(),
                 "added_mass": spec.added_mass}
                for knobs in candidates]
        return list(pool.map(swim_candidate, jobs))

    done = len([e for e in search.history if e["generation"] > 0])
    with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn")) as pool, \
            tqdm(total=spec.generations, initial=done, desc="generations", disable=not progress) as bar:
        if not search.history:      # generation 0: the stroke as it is
            _record(search, out, key, 0, [None], [search.knob_values(search.start_x)], swim_all)
        for generation in range(done + 1, spec.generations + 1):
            xs = search.ask()
            scores = _record(search, out, key, generation, xs, [search.knob_values(x) for x in xs], swim_all)
            search.tell(xs, scores)
            best = best_of(search.history)
            bar.set_postfix(best=f"{best['score']:.3g}")
            bar.update(1)
            if say:
                say(f"generation {generation}: best {min(scores):.4g} (overall {best['score']:.4g})")
    best = best_of(search.history)
    return {"out": str(out), "generations": spec.generations, "start": search.history[0]["scores"][0],
            "best": best, "held": [n for n, m in best["misses"].items() if m == 0.0],
            "missed": [n for n, m in best["misses"].items() if m != 0.0]}


def _record(search: Search, out: Path, key: str, generation: int, xs, knobs: list[dict], swim_all) -> list[float]:
    results = swim_all(knobs)
    scores, misses, figures = [], [], []
    for result in results:
        s, m = score(search.spec, result.get("figures"))
        scores.append(s)
        misses.append(m)
        figures.append(result.get("figures") or {"error": result.get("error")})
    entry = {"fit": key, "generation": generation, "x": xs if generation else None, "knobs": knobs,
             "scores": scores, "misses": misses, "figures": figures}
    with open(out / HISTORY, "a") as history:
        history.write(json.dumps(entry, allow_nan=False) + "\n")
    search.history.append(entry)
    best = best_of(search.history)
    with atomic_path(out / BEST_STROKE) as path:
        Path(path).write_text(_stroke_header(search.spec, best) + yaml.safe_dump(
            within_reach(apply_knobs(search.stroke, best["knobs"]), *_ranges_deg()), sort_keys=False))
    write_json(out / BEST, best)
    return scores


def _stroke_header(spec: FitSpec, best: dict) -> str:
    misses = ", ".join(f"{n} {'held' if m == 0.0 else 'missed'}" for n, m in best["misses"].items())
    return (f"# Written by layered-swim fit-stroke from {spec.stroke} (generation {best['generation']}, "
            f"score {best['score']:.4g}).\n# Targets: {misses}.\n")


def report(result: dict, spec: FitSpec) -> str:
    """The summary printed at the end: each target's range and the best candidate's figure."""
    best = result["best"]
    lines = [f"best of {result['generations']} generations (score {best['score']:.4g}, start "
             f"{result['start']:.4g}): {Path(result['out']) / BEST_STROKE}"]
    for name, target in spec.targets.items():
        value = best["figures"].get(name)
        shown = "n/a" if value is None else f"{value:.3g}"
        wanted = f"{'' if target.min is None else f'{target.min:g}'}..{'' if target.max is None else f'{target.max:g}'}"
        lines.append(f"  {'✔' if best['misses'][name] == 0.0 else '✘'} {name} {shown} (wanted {wanted})")
    return "\n".join(lines)

"""fit-stroke: the knobs set the stroke's numbers as named, the score counts only what misses,
bad fit files are one line, and a short search runs, resumes and repeats."""
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from layered_swim.analysis import stroke_fit
from layered_swim.analysis.calibrate import calibration_swim
from layered_swim.analysis.stroke_fit import FitSpec, Target, apply_knobs, load_fit, score
from layered_swim.config import ConfigError

REPO = Path(__file__).resolve().parents[1]
STROKE = {"name": "s", "period_s": 1.0,
          "keys": {"elbow_l": {"flexion": {0.0: 10, 0.4: 70, 0.7: 40}},
                   "elbow_r": {"mirror_of": "elbow_l", "phase_shift": 0.5}}}


def test_knobs_set_values_times_scale_and_offset():
    out = apply_knobs(STROKE, {"period_s": 1.4, "elbow_l.flexion[1]": 90.0, "elbow_l.flexion[1]:time": 0.5})
    assert out["period_s"] == 1.4
    assert out["keys"]["elbow_l"]["flexion"] == {0.0: 10, 0.5: 90.0, 0.7: 40}
    assert STROKE["keys"]["elbow_l"]["flexion"] == {0.0: 10, 0.4: 70, 0.7: 40}      # the input is left alone
    scaled = apply_knobs(STROKE, {"elbow_l.flexion:scale": 0.5, "elbow_l.flexion:offset": 5.0})
    # mean 40: values pulled half way to it, then 5 added
    assert scaled["keys"]["elbow_l"]["flexion"] == {0.0: 30.0, 0.4: 60.0, 0.7: 45.0}
    assert scaled["keys"]["elbow_r"] == STROKE["keys"]["elbow_r"]                     # the mirror follows its source


def test_perturbation_knobs_set_a_sequence_s_offsets_and_scale_them_about_zero(tmp_path):
    stroke = {**STROKE, "perturbations": {"yaw_left": {"keys": {"elbow_l": {"flexion": {0.0: 0, 0.2: 30, 0.5: -10}}}},
                                          "yaw_right": {"mirror_of": "yaw_left", "phase_shift": 0.5}}}
    out = apply_knobs(stroke, {"yaw_left/elbow_l.flexion[1]": 40.0, "yaw_left/elbow_l.flexion:scale": 2.0})
    assert out["perturbations"]["yaw_left"]["keys"]["elbow_l"]["flexion"] == {0.0: 0.0, 0.2: 80.0, 0.5: -20.0}
    assert out["keys"] == STROKE["keys"] and out["perturbations"]["yaw_right"] == stroke["perturbations"]["yaw_right"]
    with pytest.raises(ConfigError, match="'yaw_right' mirrors 'yaw_left': name that sequence"):
        load_fit(write_fit(tmp_path, knobs={"yaw_right/elbow_l.flexion[1]": {"min": 0, "max": 9}}))
    with pytest.raises(ConfigError, match="no perturbation sequence 'spin'"):
        load_fit(write_fit(tmp_path, knobs={"spin/elbow_l.flexion[1]": {"min": 0, "max": 9}}))
    spec, _, _ = load_fit(write_fit(tmp_path, targets={"yaw_left_deg_per_s": {"min": 30}},
                                    knobs={"yaw_left/elbow_l.flexion[1]": {"min": 0, "max": 60}}))
    assert spec.needs_turns() and not spec.needs_towing()


def test_a_yaw_sequence_s_turning_circle_is_its_distance_a_cycle_over_its_turn_a_cycle():
    """The distance a cycle follows the track cycle by cycle: swimming straight it is the speed
    times the period; turning, the chord of the measured turn (two cycles of it) is shorter than
    its arc by sin(x)/x; the radius is that distance over the turn a cycle."""
    period_s = 1.517                                                 # strokes/breaststroke.yaml
    drift, speed_m_s, *_, straight_m = calibration_swim(("breaststroke", None, 0.0, 1.0))
    assert straight_m == pytest.approx(speed_m_s * period_s, rel=0.01)
    turning = calibration_swim(("breaststroke", "yaw_left", 1.0, 1.0))
    change, chord_speed_m_s, roll_rad, pitch_rad, _, turning_m = turning
    turn_rad = change - drift[0]
    assert turn_rad > 0.3 and turning_m < straight_m                  # a full turn slows it
    assert chord_speed_m_s * period_s == pytest.approx(turning_m * math.sin(turn_rad) / turn_rad, rel=0.02)
    turns = stroke_fit.full_weight_turns("breaststroke", period_s)
    assert turns["yaw_left_radius_m"] == pytest.approx(turning_m / turn_rad)
    assert turns["yaw_left_deg_per_s"] == pytest.approx(math.degrees(turn_rad) / period_s)
    # ... and how fast along the track, and pitched and rolled how far, while it turns
    assert turns["yaw_left_speed_m_s"] == pytest.approx(turning_m / period_s)
    assert turns["yaw_left_pitch_deg"] == pytest.approx(math.degrees(pitch_rad))
    assert turns["yaw_left_roll_deg"] == pytest.approx(math.degrees(roll_rad))
    assert set(turns) == {f"yaw_{side}_{figure}" for side in ("left", "right")
                          for figure in ("deg_per_s", "radius_m", "speed_m_s", "pitch_deg", "roll_deg")}


def test_rest_knobs_set_a_held_angle_only_where_no_key_sets_it(tmp_path):
    out = apply_knobs(STROKE, {"rest.neck.flexion": -30.0})
    assert out["rest_pose"] == {"neck": {"flexion": -30.0}} and "rest_pose" not in STROKE
    with pytest.raises(ConfigError, match="use elbow_l.flexion:offset"):
        load_fit(write_fit(tmp_path, knobs={"rest.elbow_l.flexion": {"min": 0, "max": 9}}, stroke="front_crawl"))


def test_keys_past_the_range_of_motion_stop_at_its_end():
    lower, upper = {"waist.flexion": -15.0, "neck.flexion": -55.0}, {"waist.flexion": 40.0, "neck.flexion": 60.0}
    stroke = {"keys": {"waist": {"flexion": {0.0: 50, 0.5: -30, 0.7: 10}}, "hip_r": {"mirror_of": "hip_l"}},
              "rest_pose": {"neck": {"flexion": -90}}}
    held = stroke_fit.within_reach(stroke, lower, upper)
    assert held["keys"]["waist"]["flexion"] == {0.0: 40.0, 0.5: -15.0, 0.7: 10.0}
    assert held["rest_pose"]["neck"]["flexion"] == -55.0 and held["keys"]["hip_r"] == {"mirror_of": "hip_l"}


def test_targets_score_only_what_misses():
    target = Target(min=1.2, max=1.8)
    assert target.miss(1.5) == 0.0
    assert target.miss(1.0) == pytest.approx(0.2 / 0.6)
    assert Target(max=200).miss(240) == pytest.approx(40 / 20)        # one bound: a tenth of it counts 1
    assert Target(max=200, scale=100).miss(240) == pytest.approx(0.4)
    assert target.miss(None) is None
    spec = FitSpec(stroke="s", targets={"mean_speed_m_s": {"min": 1.2, "max": 1.8},
                                        "peak_hand_force_n": {"max": 200, "weight": 2}},
                   knobs={"period_s": {"min": 0.8, "max": 1.6}})
    total, misses = score(spec, {"mean_speed_m_s": 1.0, "peak_hand_force_n": 150})
    assert total == pytest.approx((0.2 / 0.6) ** 2) and misses["peak_hand_force_n"] == 0.0
    assert score(spec, None)[0] == pytest.approx(3 * stroke_fit.NOT_MEASURED_PENALTY)   # weights 1 + 2


def write_fit(tmp_path, **changes) -> Path:
    data = {"stroke": "front_crawl", "targets": {"mean_speed_m_s": {"min": 1.2}},
            "knobs": {"period_s": {"min": 1.0, "max": 1.5}}, **changes}
    path = tmp_path / "fit.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.mark.parametrize("changes, words", [
    ({"targets": {"speed": {"min": 1}}}, "unknown target 'speed'"),
    ({"targets": {"mean_speed_m_s": {}}}, "give min, max or both"),
    ({"knobs": {"elbow_r.flexion[1]": {"min": 0, "max": 9}}}, "mirrors 'elbow_l': name that joint"),
    ({"knobs": {"elbow_l.flexion[9]": {"min": 0, "max": 9}}}, "no key 9: the channel has 7"),
    ({"knobs": {"elbow_l.flexion[2]:time": {"min": 0.3, "max": 0.6}}}, "meets key"),
    ({"knobs": {"knee_l.extension:scale": {"min": 0, "max": 2}}}, "no keys for axis 'extension'"),
    ({"knobs": {"period_s": {"min": 2, "max": 1}}}, "must be below max"),
    ({"knobs": {"elbow_l": {"min": 0, "max": 1}}}, "expected period_s"),
    ({"seconds": 5}, "field 'seconds'"),
])
def test_bad_fit_files_are_one_line(tmp_path, changes, words):
    with pytest.raises(ConfigError, match=words.replace("(", r"\(")):
        load_fit(write_fit(tmp_path, **changes))


def test_the_shipped_fit_files_load():
    for name in ("front_crawl", "breaststroke", "butterfly", "backstroke", "front_crawl_turns", "breaststroke_turns",
                 "backstroke_turns"):
        spec, stroke, source = load_fit(name)
        assert spec.stroke == name.removesuffix("_turns") and stroke["name"] == spec.stroke and source.is_file()


def cli(*args, cwd):
    env = {**os.environ, "PYTHONPATH": str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    return subprocess.run([sys.executable, "-m", "layered_swim", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=300)


def test_a_short_search_runs_resumes_and_repeats(tmp_path):
    fit = write_fit(tmp_path, seconds=6, settle_s=2, population=4, generations=2, sigma=0.3,
                    targets={"mean_speed_m_s": {"min": 1.2, "max": 1.8}, "peak_hand_force_n": {"max": 200},
                             "active_drag_x_narita": {"min": 0.7, "max": 1.5}},
                    knobs={"period_s": {"min": 1.0, "max": 1.6}, "elbow_l.flexion[2]": {"min": 40, "max": 100}})
    straight = cli("fit-stroke", "--targets", str(fit), "--out", "a", "--no-progress", "--json", cwd=tmp_path)
    assert straight.returncode == 0, straight.stderr
    result = json.loads(straight.stdout)
    assert result["best"]["score"] <= result["start"]
    assert set(result["held"]) | set(result["missed"]) == {"mean_speed_m_s", "peak_hand_force_n",
                                                           "active_drag_x_narita"}
    first = cli("fit-stroke", "--targets", str(fit), "--generations", "1", "--out", "b", "--no-progress", cwd=tmp_path)
    assert first.returncode == 0, first.stderr
    again = cli("fit-stroke", "--targets", str(fit), "--out", "b", "--no-progress", cwd=tmp_path)
    assert again.returncode == 2 and "add --resume" in again.stderr
    resumed = cli("fit-stroke", "--targets", str(fit), "--out", "b", "--resume", "--no-progress", cwd=tmp_path)
    assert resumed.returncode == 0, resumed.stderr
    def lines(out):
        return [json.loads(line) for line in (tmp_path / out / stroke_fit.HISTORY).read_text().splitlines()]
    assert [e["generation"] for e in lines("b")] == [0, 1, 2]
    assert lines("a") == lines("b")                 # stopped and resumed: the same search
    best = yaml.safe_load((tmp_path / "a" / stroke_fit.BEST_STROKE).read_text())
    assert 1.0 <= best["period_s"] <= 1.6 and best["name"] == "front_crawl"
    swum = cli("run", "--stroke", str(tmp_path / "a" / stroke_fit.BEST_STROKE), "--seconds", "2", "--out", "r",
               cwd=tmp_path)
    assert swum.returncode == 0, swum.stderr      # the best stroke is a stroke file the other commands take

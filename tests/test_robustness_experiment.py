"""``experiment robustness``: its cells, its waters and pushes, its recovery measure and its table
(issue 37); one short swim of one cell. The sweep itself is a long command, not a test."""
import math

import numpy as np
import pytest

from layered_swim.analysis.experiments import experiment
from layered_swim.analysis.experiments import robustness as rb


def test_it_is_an_experiment_with_every_stroke_path_and_condition():
    assert experiment("robustness") is rb
    full = rb.configs(False, 0)
    assert len(full) == len(rb.STROKES) * len(rb.PATHS) * len(rb.conditions()) * rb.STARTS
    assert {c["condition"] for c in full} >= {"still", "push", "current_0", "current_315", "density_900",
                                               "density_1500"}
    assert len({c["start"] for c in full}) == rb.STARTS >= 10
    quick = rb.configs(True, 0)
    assert len(quick) == 5 * 2 * 4 * 2 and all(c["seconds"] == 30.0 for c in quick)


def test_a_current_comes_from_the_direction_named_and_a_density_is_the_waters():
    """Coming from 0 deg (+x) it flows toward -x; from 90 deg (+y), toward -y; 0.3 m/s."""
    np.testing.assert_allclose(rb.water_of("current_0")["current_m_s"], (-0.3, 0.0, 0.0), atol=1e-12)
    np.testing.assert_allclose(rb.water_of("current_90")["current_m_s"], (0.0, -0.3, 0.0), atol=1e-12)
    assert rb.water_of("density_1250") == {"density_kg_m3": 1250.0} and rb.water_of("still") == {}


def test_each_start_draws_its_own_push_within_the_asked_range():
    weight_n = 700.0
    pushes = [rb.push_of({"start": k}, weight_n) for k in range(1, 30)]
    for force, start_s, end_s in pushes:
        assert 1.0 * weight_n <= np.linalg.norm(force) <= 3.0 * weight_n
        assert start_s == rb.PUSH_AT_S and 0.05 <= end_s - start_s <= 0.2
    assert len({tuple(np.round(f, 6)) for f, _, _ in pushes}) == len(pushes)
    np.testing.assert_array_equal(rb.push_of({"start": 3}, weight_n)[0], rb.push_of({"start": 3}, weight_n)[0])


def test_back_on_the_path_is_timed_from_the_push_to_the_end_of_the_excursion_it_caused():
    t = np.arange(0.0, 40.0, 0.5)
    off = np.where((t >= 20.5) & (t < 24), 2.0, 0.5)        # pushed 2 m off at 20 s, back at 24 s
    assert rb.back_after(t, off, 20.0, 20.1) == pytest.approx(4.0)
    assert rb.back_after(t, np.full_like(t, 0.5), 20.0, 20.1) == 0.0
    assert rb.back_after(t, np.where(t >= 20, 2.0, 0.5), 20.0, 20.1) is None
    # Out at the push already (a corner): back when that excursion ends.
    assert rb.back_after(t, np.where((t >= 18) & (t < 22), 2.0, 0.5), 20.0, 20.1) == pytest.approx(2.0)
    # A corner overshot 10 s on is the path's doing: the push did not carry it out.
    later = np.where((t >= 30) & (t < 35), 2.0, 0.5)
    assert rb.back_after(t, later, 20.0, 20.1) == 0.0
    assert rb.back_after(t, np.maximum(off, later), 20.0, 20.1) == pytest.approx(4.0)


def test_the_table_holds_a_cell_at_one_metre_and_takes_medians_over_starts():
    configs = [{"stroke": "s", "trajectory": "p", "condition": c, "start": k}
               for c in ("still", "push") for k in (1, 2, 3)]
    results = [{"mean_distance_m": d} for d in (0.5, 0.9, 3.0)] + [
        {"mean_distance_m": d, "back_s": b} for d, b in ((1.2, 2.0), (1.4, None), (0.8, 3.0))]
    numbers = rb.measure(configs, results)
    still, push = numbers["rows"]
    assert still["median_mean_distance_m"] == 0.9 and still["holds"]
    assert push["median_mean_distance_m"] == 1.2 and not push["holds"]
    assert push["median_back_after_push_s"] == 3.0 and push["pushes_not_back"] == 1
    assert numbers["summary"]["held_share"] == {"s": 0.5}
    assert numbers["summary"]["median_back_after_push_s"] == {"s": 3.0}
    assert numbers["summary"]["back_in_time"] == {"s": True}      # 3 s: within the 5 s asked


def test_one_pushed_cell_swims_and_is_measured():
    result = rb.run({"stroke": "breaststroke", "trajectory": "straight_line", "condition": "push", "start": 1,
                     "seconds": 22.0})
    assert math.isfinite(result["mean_distance_m"]) and "back_s" in result

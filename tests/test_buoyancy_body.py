"""Yang's floater / sinker transition with the whole body: lung air decides."""
import numpy as np

from layered_swim.episode import Episode
from layered_swim.runs import record

SECONDS = 6.0


def float_rest(lung_air_l: float) -> dict[str, np.ndarray]:
    return record(Episode("rest", lung_air_l=lung_air_l), SECONDS).arrays()


def test_floater_with_three_litres():
    log = float_rest(3.0)
    assert np.abs(log["head_top_m"]).max() < 0.4
    assert log["root_pos_m"][:, 2].min() > -1.5


def test_sinker_with_empty_lungs():
    log = float_rest(0.0)
    assert log["root_pos_m"][-1, 2] < -2.0

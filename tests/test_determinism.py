"""Same inputs, same bits: every stroke, run twice, logs the same arrays."""
import numpy as np
import pytest

from layered_swim.control.stroke import available_strokes
from layered_swim.recorder import log_hash
from layered_swim.runs import run_swim
from layered_swim.spec import SwimSpec

SECONDS = 1.5


def logged_hash(out_dir, **fields) -> str:
    run_swim(SwimSpec(seconds=SECONDS, **fields), out_dir)
    with np.load(out_dir / "log.npz") as log:
        return log_hash(log)


@pytest.mark.parametrize("stroke", available_strokes())
def test_same_inputs_same_log(tmp_path, stroke):
    assert logged_hash(tmp_path / "a", stroke=stroke) == logged_hash(tmp_path / "b", stroke=stroke)


def test_lung_volume_changes_the_log(tmp_path):
    assert logged_hash(tmp_path / "a", stroke="rest", lung_air_l=3.0) != \
        logged_hash(tmp_path / "b", stroke="rest", lung_air_l=1.0)

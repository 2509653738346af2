"""A short swim goes forward: the strokes, the PD and the fluid together make thrust."""
import pytest

from layered_swim.episode import Episode

SECONDS = 4.0


@pytest.mark.parametrize("stroke", ["breaststroke", "front_crawl"])
def test_short_swim_makes_forward_progress(stroke):
    episode = Episode(stroke)
    sim = episode.sim
    try:
        start_x = sim.state.pos_m[0, 0]
        episode.run(SECONDS)
        travelled_m = sim.state.pos_m[0, 0] - start_x
        depth_m = -sim.state.pos_m[0, 2]
    finally:
        sim.close()
    assert travelled_m > 1.0          # well past the push-off glide (0.5 m/s start speed)
    assert depth_m < 1.0              # swimming, not diving

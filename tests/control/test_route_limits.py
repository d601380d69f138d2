"""The speed limits along a route (control/limits.py): where each lane's limit holds (in SUMO's
distance, each lane its length), and the slowest speed SUMO may hold a bus to on a stretch, a
lower limit just beyond it included."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from sse_cosim.control.limits import RouteLimits
from sse_cosim.world.roadmap import LaneGeometry

DECEL = 2.0


def lane(lane_id: str, length: float, speed: float) -> LaneGeometry:
    """A lane ``length`` m long in SUMO's distance, drawn shorter (its shape does not count)."""
    shape = np.array([[0.0, 0.0], [0.3 * length, 1.0], [0.8 * length, 0.0]])
    return LaneGeometry(lane_id, lane_id, 0, shape, 3.2, length, speed)


# 100 m at 13.89, a 10 m junction lane at 5, 50 m at 8.33 (SUMO's lengths, not the drawn ones)
LIMITS = RouteLimits.of_lanes([lane("a", 100.0, 13.89), lane(":j", 10.0, 5.0),
                               lane("b", 50.0, 8.33)])


def test_each_lane_holds_its_limit_along_its_length_in_sumos_distance():
    assert LIMITS.ends_m.tolist() == [100.0, 110.0, 160.0]
    assert [LIMITS.at(s) for s in (-3.0, 0.0, 99.9, 100.0, 109.9, 110.0, 200.0)] == [
        13.89, 13.89, 13.89, 5.0, 5.0, 8.33, 8.33]


def test_the_least_limit_on_a_stretch_counts_the_lanes_it_touches():
    assert LIMITS.least(0.0, 100.0, DECEL) == 5.0  # the junction lane starts where it ends
    assert LIMITS.least(100.0, 150.0, DECEL) == 5.0
    assert LIMITS.least(110.0, 150.0, DECEL) == 5.0  # at its end the front may be on it
    assert LIMITS.least(110.5, 150.0, DECEL) == 8.33  # the junction lane is behind
    assert LIMITS.least(150.0, 400.0, DECEL) == 8.33  # beyond the route: its last limit


def test_a_lower_limit_beyond_the_stretch_bounds_the_speed_braking_toward_it():
    assert LIMITS.least(0.0, 90.0, DECEL) == pytest.approx(math.sqrt(25.0 + 2 * DECEL * 10.0))
    assert LIMITS.least(0.0, 10.0, DECEL) == 13.89  # too far ahead to brake for yet


@given(st.floats(-50.0, 200.0), st.floats(0.0, 100.0))
def test_the_bound_is_the_least_of_the_braking_envelope_over_the_stretch(start, length):
    """Sampled: no point of the stretch has a lower envelope min_k sqrt(l_k^2 + 2 b gap_k)."""
    samples = np.linspace(start, start + length, 201)

    def envelope(s: float) -> float:
        starts = [-math.inf, 100.0, 110.0]
        return min(math.sqrt(v * v + 2 * DECEL * max(0.0, a - s))
                   for a, e, v in zip(starts, [100.0, 110.0, math.inf],
                                      [13.89, 5.0, 8.33], strict=True) if e >= s)
    assert LIMITS.least(start, start + length, DECEL) <= min(map(envelope, samples)) + 1e-9
    assert LIMITS.least(start, start + length, DECEL) >= min(map(envelope, samples)) - 0.2

"""The drawn route to SUMO's distance along it (control/odometer.py): each lane's drawn extent
maps linearly onto its length, a gap between two lanes' shapes onto no distance, and the map
turns back."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from sse_cosim.control.odometer import RouteOdometer
from sse_cosim.world.roadmap import LaneGeometry


def lane(lane_id: str, xs: list[float], length: float) -> LaneGeometry:
    return LaneGeometry(lane_id, lane_id, 0, np.array([[x, 0.0] for x in xs]), 3.2, length,
                        13.89)


# drawn 0-100 (SUMO: 80 m), a junction lane drawn 102-112 after a 2 m gap (SUMO: 10 m, as
# drawn), then drawn 112-162 (SUMO: 60 m)
ODOMETER = RouteOdometer.of_lanes([lane("a", [0.0, 40.0, 100.0], 80.0),
                                   lane(":j", [102.0, 112.0], 10.0),
                                   lane("b", [112.0, 162.0], 60.0)])


def test_each_lane_maps_its_drawn_extent_onto_its_length():
    assert ODOMETER.drawn_m.tolist() == [0.0, 100.0, 102.0, 112.0, 112.0, 162.0]
    assert ODOMETER.drive_m.tolist() == [0.0, 80.0, 80.0, 90.0, 90.0, 150.0]
    cases = {0.0: 0.0, 50.0: 40.0, 100.0: 80.0, 101.0: 80.0, 107.0: 85.0, 137.0: 120.0,
             162.0: 150.0, -5.0: -5.0, 170.0: 158.0}
    assert {s: ODOMETER.drive(s) for s in cases} == pytest.approx(cases)


def test_the_inverse_takes_a_gap_at_its_far_end():
    assert ODOMETER.drawn(80.0) == pytest.approx(102.0)
    assert [ODOMETER.drawn(d) for d in (40.0, 85.0, 120.0, -5.0, 158.0)] == pytest.approx(
        [50.0, 107.0, 137.0, -5.0, 170.0])


@given(st.lists(st.tuples(st.floats(0.5, 80.0), st.floats(0.2, 3.0), st.floats(0.0, 3.0)),
                min_size=1, max_size=6), st.floats(-20.0, 1.0))
def test_the_map_grows_and_turns_back(spans, where):
    """Random lanes, each drawn ``d`` m with ``d * ratio`` m of SUMO's distance after a gap:
    the map never falls, and outside the gaps the inverse gives the drawn position back."""
    lanes, x = [], 0.0
    for k, (drawn, ratio, gap) in enumerate(spans):
        x += gap if k else 0.0
        lanes.append(lane(f"l{k}", [x, x + drawn], drawn * ratio))
        x += drawn
    odometer = RouteOdometer.of_lanes(lanes)
    s = np.linspace(-10.0, x + 10.0, 301)
    drive = np.array([odometer.drive(p) for p in s])
    assert (np.diff(drive) >= -1e-9).all()
    start = float(where % max(x, 1e-9))
    inside = any(lo <= start < hi
                 for lo, hi in zip(odometer.drawn_m[::2], odometer.drawn_m[1::2], strict=True))
    if inside:
        assert odometer.drawn(odometer.drive(start)) == pytest.approx(start, abs=1e-6)

"""The drawn route to SUMO's distance along it (control/swept.py, ``RoutePath.drive`` and
``point_at``): each lane's drawn extent maps linearly onto its length, a gap between two
lanes' shapes onto no distance, and the map turns back."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from sse_cosim.control.swept import RoutePath


def lane(xs: list[float], length: float) -> tuple[np.ndarray, float]:
    return np.array([[x, 0.0] for x in xs]), length


# drawn 0-100 (SUMO: 80 m), a junction lane drawn 102-112 after a 2 m gap (SUMO: 10 m, as
# drawn), then drawn 112-162 (SUMO: 60 m)
PATH = RoutePath.of_lanes([lane([0.0, 40.0, 100.0], 80.0), lane([102.0, 112.0], 10.0),
                           lane([112.0, 162.0], 60.0)])


def test_each_lane_maps_its_drawn_extent_onto_its_length():
    cases = {0.0: 0.0, 40.0: 32.0, 50.0: 40.0, 100.0: 80.0, 101.0: 80.0, 107.0: 85.0,
             137.0: 120.0, 162.0: 150.0, -5.0: -5.0, 170.0: 158.0}
    assert {s: PATH.drive(s) for s in cases} == pytest.approx(cases)


def test_a_passage_drawn_without_length_runs_its_length_at_one_point():
    """Two lanes meeting at a point with a 0.1 m passage between them (netconvert's junction
    of a point): SUMO's front stands at station 100 for lane positions 80 to 80.1."""
    path = RoutePath.of_lanes([lane([0.0, 100.0], 80.0), lane([100.0, 100.0], 0.1),
                               lane([100.0, 150.0], 50.0)])
    assert path.drive(100.0) == pytest.approx(80.1)  # to have cleared the point: its far end
    assert path.drive_before(100.0) == pytest.approx(80.0)  # to stay before it: its near end
    assert path.drive(125.0) == path.drive_before(125.0) == pytest.approx(105.1)
    assert path.drive(50.0) == path.drive_before(50.0) == pytest.approx(40.0)
    assert path.point_at(80.05)[1] == pytest.approx(100.0)


def test_the_inverse_takes_a_gap_at_its_far_end():
    assert PATH.point_at(80.0)[1] == pytest.approx(102.0)
    assert [PATH.point_at(d)[1] for d in (40.0, 85.0, 120.0)] == pytest.approx(
        [50.0, 107.0, 137.0])
    assert PATH.point_at(85.0)[0] == pytest.approx([107.0, 0.0])


@given(st.lists(st.tuples(st.floats(0.5, 80.0), st.floats(0.2, 3.0), st.floats(0.0, 3.0)),
                min_size=1, max_size=6), st.floats(-20.0, 1.0))
def test_the_map_grows_and_turns_back(spans, where):
    """Random lanes, each drawn ``d`` m with ``d * ratio`` m of SUMO's distance after a gap:
    the map never falls, and outside the gaps the inverse gives the drawn position back."""
    lanes, x, extents = [], 0.0, []
    for k, (drawn, ratio, gap) in enumerate(spans):
        x += gap if k else 0.0
        lanes.append(lane([x, x + drawn], drawn * ratio))
        extents.append((x, x + drawn))
        x += drawn
    path = RoutePath.of_lanes(lanes)
    s = np.linspace(-10.0, x + 10.0, 301)
    drive = np.array([path.drive(p) for p in s])
    assert (np.diff(drive) >= -1e-9).all()
    start = float(where % max(x, 1e-9))
    if any(lo <= start < hi for lo, hi in extents):
        assert path.point_at(path.drive(start))[1] == pytest.approx(start, abs=1e-6)

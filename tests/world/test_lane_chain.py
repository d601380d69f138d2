"""The lanes a route is planned on (world/roadmap.py, ``lane_chain``, ``lane_plan``): on each
edge the rightmost lane from which the rest of the route can be driven lane to lane, with the
internal lane into the next edge; where none can, the fewest lane changes; pure, on hand-made
links."""

from __future__ import annotations

import pytest

from sse_cosim.world.roadmap import NoLanePlan, lane_chain, lane_plan

LANES = {"A": [1, 2], "B": [1, 2], "C": [1]}.__getitem__


def test_the_rightmost_lanes_that_lead_on_straight_ahead() -> None:
    links = {("A", "B"): ((1, 1, ":J_0_0"), (2, 2, ":J_0_1")), ("B", "C"): ((1, 1, ""),)}
    assert lane_chain(["A", "B", "C"], LANES, links) == [(1, ":J_0_0"), (1, ""), (1, "")]


def test_a_turn_taken_from_the_left_lane_starts_there() -> None:
    """Only B's left lane turns into C, and only A's left lane reaches it: the bus departs
    on A's left lane (the right one would need a lane change, which the plan has none of)."""
    links = {("A", "B"): ((1, 1, ":J_0_0"), (2, 2, ":J_0_1")), ("B", "C"): ((2, 1, ":K_1_0"),)}
    assert lane_chain(["A", "B", "C"], LANES, links) == [(2, ":J_0_1"), (2, ":K_1_0"), (1, "")]


def test_of_two_links_from_one_lane_the_rightmost_that_leads_on() -> None:
    links = {("A", "B"): ((1, 1, ":J_0_0"), (1, 2, ":J_0_1")), ("B", "C"): ((2, 1, ""),)}
    assert lane_chain(["A", "B", "C"], LANES, links) == [(1, ":J_0_1"), (2, ""), (1, "")]


def test_a_route_no_lane_leads_along_has_no_chain() -> None:
    assert lane_chain(["A", "C"], LANES, {("A", "B"): ((1, 1, ""),)}) is None
    assert lane_chain(["A"], LANES, {}) == [(1, "")]


def test_a_route_that_lane_to_lane_cannot_be_driven_plans_the_fewest_changes() -> None:
    """A leads onto B's left lane only, and only B's right lane leads into C: the bus departs
    on A's left lane (the one that leads on) and changes from B's left lane to its right."""
    links = {("A", "B"): ((2, 2, ":J_0_1"),), ("B", "C"): ((1, 1, ":K_0_0"),)}
    assert lane_plan(["A", "B", "C"], LANES, links) == [(2, 2, ":J_0_1"), (2, 1, ":K_0_0"),
                                                        (1, 1, "")]


def test_a_route_driven_lane_to_lane_keeps_its_chain() -> None:
    links = {("A", "B"): ((1, 1, ":J_0_0"), (2, 2, ":J_0_1")), ("B", "C"): ((2, 1, ":K_1_0"),)}
    assert lane_plan(["A", "B", "C"], LANES, links) == [
        (index, index, via) for index, via in lane_chain(["A", "B", "C"], LANES, links)]


def test_of_two_plans_with_one_change_the_one_on_the_right() -> None:
    """From A's right lane the bus reaches B's right lane, from its left lane B's left; C
    takes either from B's middle lane only: one change each way, the right one is taken."""
    lanes = {"A": [1, 2], "B": [1, 2, 3], "C": [1]}.__getitem__
    links = {("A", "B"): ((1, 1, ""), (2, 3, "")), ("B", "C"): ((2, 1, ""),)}
    assert lane_plan(["A", "B", "C"], lanes, links) == [(1, 1, ""), (1, 2, ""), (1, 1, "")]


def test_a_change_crosses_no_lane_the_vehicle_may_not_drive() -> None:
    """B's driving lanes are 1 and 3 (2 is another kind): from 1 the bus cannot reach 3, the
    only one that leads into C, so the plan names the pair it breaks at."""
    lanes = {"A": [1], "B": [1, 3], "C": [1]}.__getitem__
    links = {("A", "B"): ((1, 1, ""),), ("B", "C"): ((3, 1, ""),)}
    with pytest.raises(NoLanePlan) as info:
        lane_plan(["A", "B", "C"], lanes, links)
    assert info.value.edges == ("A", "B")
    with pytest.raises(NoLanePlan) as info:
        lane_plan(["A", "B", "C"], LANES, {("A", "B"): ((1, 1, ""),)})
    assert info.value.edges == ("B", "C")

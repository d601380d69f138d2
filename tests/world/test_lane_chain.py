"""The lanes a route is planned on (world/roadmap.py, ``lane_chain``): on each edge the
rightmost lane from which the rest of the route can be driven lane to lane, with the internal
lane into the next edge; pure, on hand-made links."""

from __future__ import annotations

from sse_cosim.world.roadmap import chain_break, lane_chain

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


def test_the_break_named_is_the_pair_where_no_lane_leads_on() -> None:
    """A leads onto B's right lane only, and only B's left lane leads into C: a bus that
    changes no lanes cannot drive it, and the pair to mend is (A, B), not (B, C)."""
    links = {("A", "B"): ((1, 1, ""), (2, 1, "")), ("B", "C"): ((2, 1, ""),)}
    assert lane_chain(["A", "B", "C"], LANES, links) is None
    assert chain_break(["A", "B", "C"], LANES, links) == ("A", "B")
    assert chain_break(["A", "C"], LANES, {}) == ("A", "C")
    assert chain_break(["A", "B"], LANES, links) is None

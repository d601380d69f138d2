"""The pedestrian's walk is planned with a fixed number of graph searches, not one per crossing,
and chooses the walk that trying every crossing chose (the code before, kept here as the
reference), on the paper's road, two zebras and a four-arm junction."""

from __future__ import annotations

import heapq
import itertools
from collections.abc import Sequence
from pathlib import Path

import pytest
import sumolib

from sse_cosim.world import demand
from sse_cosim.world.network import build_network
from sse_cosim.world.walkgraph import WalkGraph

REPO = Path(__file__).resolve().parents[2]
NETWORKS = {
    "paper": REPO / "sumo_net",
    "two_zebras": REPO / "tests" / "networks" / "two_zebras",
    "junction": REPO / "sumo_net" / "junction",
}


def _reference_shortest(graph: dict[str, dict[str, float]], start: str, goal: str,
                        avoid: Sequence[str]) -> tuple[float, list[str]] | None:
    """One Dijkstra search per goal, as the code before this test did."""
    queue: list[tuple[float, str, list[str]]] = [(0.0, start, [start])]
    seen: set[str] = set()
    while queue:
        cost, node, path = heapq.heappop(queue)
        if node == goal:
            return cost, path
        if node in seen:
            continue
        seen.add(node)
        for nxt, weight in graph.get(node, {}).items():
            if nxt not in avoid and nxt not in seen:
                heapq.heappush(queue, (cost + weight, nxt, [*path, nxt]))
    return None


def _reference_path(net: sumolib.net.Net, start: tuple[str, float], end: tuple[str, float],
                    crossings: Sequence[str]) -> list[str] | None:
    """Every crossing in both directions, two searches each (the code before)."""
    graph = WalkGraph(net).adjacency
    best: tuple[float, list[str]] | None = None
    for crossing in crossings:
        ends = [e for e in graph.get(crossing, {})
                if net.getEdge(e).getFunction() == "walkingarea"]
        for a, b in ((ends[0], ends[1]), (ends[1], ends[0])) if len(ends) == 2 else ():
            first = _reference_shortest(graph, start[0], a, avoid=crossings)
            second = _reference_shortest(graph, b, end[0], avoid=crossings)
            if first is None or second is None:
                continue
            path = [*first[1], crossing, *second[1]]
            length = demand.walk_length(net, path, start[1], end[1])
            if best is None or length < best[0]:
                best = (length, path)
    return None if best is None else best[1]


@pytest.fixture(scope="module", params=sorted(NETWORKS))
def net(request: pytest.FixtureRequest) -> sumolib.net.Net:
    path = build_network(NETWORKS[request.param])
    return sumolib.net.readNet(str(path), withInternal=True, withPedestrianConnections=True)


def _sidewalks(net: sumolib.net.Net) -> list[str]:
    return sorted(e.getID() for e in net.getEdges(withInternal=False)
                  if any(lane.allows("pedestrian") for lane in e.getLanes()))


def test_every_walk_is_the_one_trying_every_crossing_gives(net: sumolib.net.Net) -> None:
    graph = WalkGraph(net)
    crossings = graph.crossings
    assert crossings
    compared = 0
    for start, end in itertools.permutations(_sidewalks(net), 2):
        length_s, length_e = net.getEdge(start).getLength(), net.getEdge(end).getLength()
        for start_pos, end_pos in ((0.0, 0.0), (0.5 * length_s, 0.25 * length_e),
                                   (length_s - 1.0, length_e)):
            got = demand.pedestrian_path(net, (start, start_pos), (end, end_pos), crossings,
                                         graph)
            assert got == _reference_path(net, (start, start_pos), (end, end_pos), crossings)
            compared += got is not None
    assert compared > 0


def test_a_walk_over_one_named_crossing_takes_no_other(net: sumolib.net.Net) -> None:
    """A pedestrian whose ``crossing`` names a zebra crosses the road there and nowhere else
    (its walk once reached the named zebra over another one, which the world then took for
    its crossing): every walk over one crossing has exactly that crossing in it."""
    graph = WalkGraph(net)
    walked = 0
    for start, end in itertools.permutations(_sidewalks(net), 2):
        for crossing in graph.crossings:
            path = demand.pedestrian_path(net, (start, 0.0), (end, 0.0), [crossing], graph)
            if path is not None:
                assert [e for e in path if graph.function[e] == "crossing"] == [crossing]
                walked += 1
    assert walked > 0


def test_a_walk_takes_two_searches_and_one_per_crossing_that_can_win(
        net: sumolib.net.Net) -> None:
    graph = WalkGraph(net)
    crossings = graph.crossings
    sidewalks = _sidewalks(net)
    for start, end in itertools.permutations(sidewalks, 2):
        graph.searches = 0
        demand.pedestrian_path(net, (start, 1.0), (end, 1.0), crossings, graph)
        # one search from the start, one towards the end, then at most one per direction of
        # a crossing still in the running (here: every crossing, so the bound is loose)
        assert graph.searches <= 2 + 2 * len(crossings)


def test_a_search_visits_each_edge_once() -> None:
    path = build_network(NETWORKS["junction"])
    net = sumolib.net.readNet(str(path), withInternal=True, withPedestrianConnections=True)
    graph = WalkGraph(net)
    popped: list[str] = []
    real_pop = heapq.heappop

    def counting_pop(queue: list) -> tuple:
        item = real_pop(queue)
        popped.append(item[1])
        return item

    start = _sidewalks(net)[0]
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr("sse_cosim.world.walkgraph.heapq.heappop", counting_pop)
        found = graph.tree(start, frozenset(graph.crossings))
    assert set(found) <= set(graph.adjacency)
    # a node is expanded once; a popped duplicate is dropped at once
    assert len(found) == len(set(popped))
    assert len(popped) <= sum(len(n) for n in graph.adjacency.values()) + 1


def test_the_crossings_beyond_reach_of_the_shortest_walk_get_no_search() -> None:
    """On the four-arm junction a walk over the west arm prices the other arms' crossings
    without a search for each."""
    path = build_network(NETWORKS["junction"])
    net = sumolib.net.readNet(str(path), withInternal=True, withPedestrianConnections=True)
    graph = WalkGraph(net)
    sidewalks = _sidewalks(net)
    searches = []
    for start, end in itertools.permutations(sidewalks, 2):
        graph.searches = 0
        demand.pedestrian_path(net, (start, 1.0), (end, 1.0), graph.crossings, graph)
        searches.append(graph.searches)
    assert min(searches) < 2 + 2 * len(graph.crossings)

"""Where pedestrians can walk, as a graph built once per network, and the searches over it.

The nodes are the edges pedestrians may use (sidewalks, walking areas, crossings); two nodes
are joined where SUMO connects a pedestrian lane of one to a pedestrian lane of the other.
Walking areas and crossings can be walked either way, so every link goes both ways; the
cost of a step is the length of the edge stepped onto (the first edge of a walk costs
nothing). Adjacency dicts in the network's edge order, searched with a binary heap.

A search pops nodes in the order (cost, node id, the walk's list of edge ids), which is also
how it breaks ties between equally long walks: :meth:`WalkGraph.tree` from one source gives,
for every node, exactly the walk that :meth:`WalkGraph.shortest` from that source to that
node gives, in one search instead of one per goal.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Collection
from dataclasses import dataclass

import sumolib

PEDESTRIAN = "pedestrian"


@dataclass(frozen=True)
class _Trail:
    """A walk as a chain back to its first edge (a search copies no lists); compared as the
    list of its edge ids, which only ties of cost and node ever ask for."""

    node: str
    parent: _Trail | None

    def edges(self) -> list[str]:
        out: list[str] = []
        trail: _Trail | None = self
        while trail is not None:
            out.append(trail.node)
            trail = trail.parent
        return out[::-1]

    def __lt__(self, other: _Trail) -> bool:
        return self.edges() < other.edges()


class WalkGraph:
    """The pedestrian graph of ``net`` (see module docstring); ``searches`` counts the searches
    run on it (each visits every node at most once)."""

    def __init__(self, net: sumolib.net.Net) -> None:
        self.adjacency: dict[str, dict[str, float]] = {}
        self.function: dict[str, str] = {}
        self.length: dict[str, float] = {}
        for edge in net.getEdges(withInternal=True):
            self.function[edge.getID()] = edge.getFunction()
            self.length[edge.getID()] = edge.getLength()
            for to_edge, conns in edge.getOutgoing().items():
                if any(c.getFromLane().allows(PEDESTRIAN) and c.getToLane().allows(PEDESTRIAN)
                       for c in conns):
                    a, b = edge.getID(), to_edge.getID()
                    self.adjacency.setdefault(a, {})[b] = to_edge.getLength()
                    self.adjacency.setdefault(b, {})[a] = edge.getLength()
        self.searches = 0

    @property
    def crossings(self) -> list[str]:
        """Every crossing of the network, by id."""
        return sorted(e for e, function in self.function.items() if function == "crossing")

    def walking_areas_of(self, crossing: str) -> list[str]:
        """The walking areas linked to ``crossing`` (one at each end), in adjacency order."""
        return [e for e in self.adjacency.get(crossing, {})
                if self.function.get(e) == "walkingarea"]

    def tree(self, source: str, avoid: Collection[str]) -> dict[str, list[str]]:
        """The shortest walk from ``source`` to every node it reaches without stepping onto
        ``avoid`` (a set), each the walk :meth:`shortest` finds (the same ties)."""
        self.searches += 1
        found: dict[str, list[str]] = {}
        queue: list[tuple[float, str, _Trail]] = [(0.0, source, _Trail(source, None))]
        while queue:
            cost, node, trail = heapq.heappop(queue)
            if node in found:
                continue
            found[node] = trail.edges()
            for nxt, weight in self.adjacency.get(node, {}).items():
                if nxt not in avoid and nxt not in found:
                    heapq.heappush(queue, (cost + weight, nxt, _Trail(nxt, trail)))
        return found

    def costs_to(self, goal: str, avoid: Collection[str]) -> dict[str, float]:
        """For every node that reaches ``goal`` without stepping onto ``avoid``: the cost of
        its shortest walk there (the lengths of the edges after it, ``goal``'s included;
        summed from the goal backwards, so equal to :meth:`shortest`'s cost up to rounding)."""
        self.searches += 1
        costs: dict[str, float] = {}
        queue: list[tuple[float, str]] = [(0.0, goal)]
        while queue:
            cost, node = heapq.heappop(queue)
            if node in costs:
                continue
            costs[node] = cost
            if node in avoid:  # a walk may end on it (goal) but never pass it
                continue
            step = self.length.get(node, math.inf)
            for prev in self.adjacency.get(node, {}):
                if prev not in avoid and prev not in costs:
                    heapq.heappush(queue, (cost + step, prev))
        return costs

    def shortest(self, start: str, goal: str,
                 avoid: Collection[str]) -> tuple[float, list[str]] | None:
        """The shortest walk from ``start`` to ``goal`` without stepping onto ``avoid`` (a
        set), with its cost; None if there is none. Stops once ``goal`` is reached."""
        self.searches += 1
        queue: list[tuple[float, str, _Trail]] = [(0.0, start, _Trail(start, None))]
        seen: set[str] = set()
        while queue:
            cost, node, trail = heapq.heappop(queue)
            if node == goal:
                return cost, trail.edges()
            if node in seen:
                continue
            seen.add(node)
            for nxt, weight in self.adjacency.get(node, {}).items():
                if nxt not in avoid and nxt not in seen:
                    heapq.heappush(queue, (cost + weight, nxt, _Trail(nxt, trail)))
        return None

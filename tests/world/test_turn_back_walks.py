"""Walks that end where they began are not measured (sse_cosim/world/walker_jitter.py,
``passages``; issue: live on real streets, item 4): SUMO re-places a walker turning back on a
walking area far from any path, and one value then served a whole scene. A junction whose
corner ``A`` is joined to corner ``B`` by two crossings (as an island-less split crossing is
drawn) gives the walk from ``B``'s sidewalk over one crossing and back over the other; it is
left out, and every walk that crosses a street is kept."""

from __future__ import annotations

from dataclasses import dataclass, field

from sse_cosim.world import walker_jitter


@dataclass(eq=False)
class Node:
    id: str

    def getID(self) -> str:
        return self.id


@dataclass(eq=False)
class Edge:
    id: str
    function: str
    ends: tuple[Node, Node]
    length: float = 20.0
    incoming: list[Edge] = field(default_factory=list)
    outgoing: list[Edge] = field(default_factory=list)

    def getID(self) -> str:
        return self.id

    def getFunction(self) -> str:
        return self.function

    def getFromNode(self) -> Node:
        return self.ends[0]

    def getToNode(self) -> Node:
        return self.ends[1]

    def getLength(self) -> float:
        return self.length

    def getIncoming(self) -> list[Edge]:
        return self.incoming

    def getOutgoing(self) -> list[Edge]:
        return self.outgoing


class Net:
    def __init__(self, edges: list[Edge]) -> None:
        self.edges = {e.id: e for e in edges}

    def getEdge(self, edge_id: str) -> Edge:
        return self.edges[edge_id]


def _join(a: Edge, b: Edge) -> None:
    """Walkers go from ``a`` to ``b`` and back."""
    a.outgoing.append(b)
    b.incoming.append(a)
    b.outgoing.append(a)
    a.incoming.append(b)


def _junction() -> tuple[Net, list[Edge]]:
    """Junction J: corner A with sidewalks "ja" (to node N) and "jb" (to node S); corner B
    with sidewalk "jc" (to node E); crossings c1 and c2 both from A to B."""
    j, n, s, e = Node("J"), Node("N"), Node("S"), Node("E")
    area_a = Edge(":J_w0", "walkingarea", (j, j), 2.0)
    area_b = Edge(":J_w1", "walkingarea", (j, j), 2.0)
    ja, jb, jc = Edge("ja", "", (j, n)), Edge("jb", "", (j, s)), Edge("jc", "", (j, e))
    c1, c2 = Edge(":J_c1", "crossing", (j, j), 7.0), Edge(":J_c2", "crossing", (j, j), 7.0)
    for side in (ja, jb):
        _join(side, area_a)
    _join(jc, area_b)
    for crossing in (c1, c2):
        _join(area_a, crossing)
        _join(crossing, area_b)
    return Net([area_a, area_b, ja, jb, jc, c1, c2]), [area_a, area_b]


def test_a_walk_back_to_the_sidewalk_it_began_on_is_not_walked() -> None:
    net, areas = _junction()
    walks = {edges for _, edges, _, _ in walker_jitter.passages(net, areas)}
    back = [edges for edges in walks if edges[0] == edges[-1]]
    assert back == []
    # over either crossing, from B's sidewalk to each of A's and back, and along A's corner
    for crossing in (":J_c1", ":J_c2"):
        assert ("jc", ":J_w1", crossing, ":J_w0", "ja") in walks
        assert ("ja", ":J_w0", crossing, ":J_w1", "jc") in walks
    assert ("ja", ":J_w0", "jb") in walks and ("jb", ":J_w0", "ja") in walks
    assert len(walks) == 10

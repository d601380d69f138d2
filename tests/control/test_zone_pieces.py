"""Conflict zones are cut into short pieces along the route (sse_cosim/control/picture.py,
``_swept_walkable``): a long strip of kerb inside the corridor is not one zone the bus must
clear whole, and the pieces still cover every place of it."""

from __future__ import annotations

import math

import shapely

from sse_cosim.control.picture import _CUT_OVERLAP_M, ZONE_PIECE_M, _swept_walkable

ROUTE = shapely.LineString([(0.0, 0.0), (40.0, 0.0), (60.0, 15.0)])  # a bend at 40 m
CORRIDOR = ROUTE.buffer(1.55, cap_style="flat")


def test_a_long_kerb_strip_becomes_short_pieces_that_cover_it() -> None:
    kerb = ROUTE.offset_curve(1.6).buffer(0.2, cap_style="flat")  # 0.15 m inside the corridor
    strip = shapely.intersection(CORRIDOR, kerb)
    pieces = _swept_walkable(ROUTE, CORRIDOR, kerb)
    assert len(pieces) >= (ROUTE.length - 1.0) // ZONE_PIECE_M
    assert all(end - start <= ZONE_PIECE_M + 2 * _CUT_OVERLAP_M + 0.5
               for _, start, end in pieces)
    covered = shapely.union_all([piece for piece, _, _ in pieces])
    assert shapely.difference(strip, covered).area < 1e-9
    assert [start for _, start, _ in pieces] == sorted(start for _, start, _ in pieces)


def test_a_zebra_shorter_than_a_piece_stays_whole() -> None:
    zebra = shapely.box(10.0, -4.0, 13.0, 4.0)
    pieces = _swept_walkable(ROUTE, CORRIDOR, zebra)
    assert len(pieces) == 1
    assert shapely.symmetric_difference(pieces[0][0],
                                        shapely.intersection(CORRIDOR, zebra)).area < 1e-9


def test_a_kerb_along_a_bending_street_is_cut_whatever_wedges_the_cuts_leave() -> None:
    """A street that bends at its vertices by 10 to 40 degrees, as converted OSM streets do
    (line 300 of Bad Hersfeld stood for good before a 256 m strip of sidewalk, one zone): each
    stretch's flat ends leave a wedge outside a bend, and the wedges become pieces of their own;
    the strip is not kept whole."""
    turns = [0.0, 0.2, 0.35, 0.6, 0.7, 0.25, 0.4, 0.5, 0.3, 0.65]
    heading, points = 0.0, [(0.0, 0.0)]
    for k, turn in enumerate(turns * 3):
        heading += turn if k % 7 < 4 else -turn
        x, y = points[-1]
        points.append((x + 9.0 * math.cos(heading), y + 9.0 * math.sin(heading)))
    route = shapely.LineString(points)
    corridor = route.buffer(4.0, cap_style="flat", join_style="mitre")
    kerbs = shapely.union(route.offset_curve(3.4).buffer(0.5, cap_style="flat"),
                          route.offset_curve(-3.4).buffer(0.5, cap_style="flat"))
    strip = shapely.intersection(corridor, kerbs)
    pieces = _swept_walkable(route, corridor, kerbs)
    covered = shapely.union_all([piece for piece, _, _ in pieces])
    assert shapely.difference(strip, covered).area < 1e-9
    assert max(end - start for _, start, end in pieces) < 3 * ZONE_PIECE_M

"""Conflict zones are cut into short pieces along the route (sse_cosim/control/picture.py,
``_swept_walkable``): a long strip of kerb inside the corridor is not one zone the bus must
clear whole, and the pieces still cover every place of it."""

from __future__ import annotations

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

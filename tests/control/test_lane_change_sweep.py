"""The sweep of a route with a lane change (control/swept.py, ``RoutePath.detours``): on a
curved edge with two lanes, the bus may be on either lane while its front is on the edge.
Every footprint on either lane lies in the sweep, and the stretches along which the body
touches a piece of ground, at the route's stations, hold every front station at which a
footprint on either lane touches it: on a curve the other lane's drawn length differs from the
route's, and a detour's stations are mapped through SUMO's distance (``SweepPiece.scale``)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from sse_cosim.control.swept import (
    RoutePath,
    body_sweep,
    chord_footprint,
    swept_region,
    touch_intervals,
)
from sse_cosim.world.roadmap import LaneChange, LaneGeometry

LENGTH_M, WIDTH_M = 12.0, 3.15
RADIUS_M, LANE_M = 40.0, 3.2
EDGE_LENGTH_M = 80.0  # SUMO's length of both lanes (the lanes of an edge are equally long)


def arc(radius: float, start: np.ndarray) -> np.ndarray:
    """A left-turning quarter arc about the origin of ``radius`` after a straight run from
    ``start`` (2,): shape (k, 2)."""
    angles = np.linspace(-math.pi / 2.0, 0.0, 40)
    curve = np.column_stack([radius * np.cos(angles), radius * np.sin(angles)])
    return np.vstack([start, curve])


def lanes() -> tuple[LaneGeometry, LaneGeometry]:
    inner = arc(RADIUS_M, np.array([-30.0, -RADIUS_M]))
    outer = arc(RADIUS_M + LANE_M, np.array([-30.0, -RADIUS_M - LANE_M]))
    return (LaneGeometry("E_1", "E", 1, inner, LANE_M, EDGE_LENGTH_M, 13.89),
            LaneGeometry("E_0", "E", 0, outer, LANE_M, EDGE_LENGTH_M, 13.89))


def test_a_change_on_a_curve_sweeps_both_lanes_at_the_routes_stations() -> None:
    inner, outer = lanes()
    change = LaneChange("E", 0, 1, ((outer,),))
    path = RoutePath.of_route([inner], [change])
    alone = RoutePath.of_route([inner])
    detour = path.detours[0]
    assert (detour.start_m, detour.end_m) == (0.0, EDGE_LENGTH_M)
    pieces = body_sweep(path, LENGTH_M, WIDTH_M)
    region = swept_region(pieces)
    sigmas = np.linspace(0.0, EDGE_LENGTH_M, 801)
    corner = shapely.intersection(  # a sidewalk beyond the outer lane, along the curve
        shapely.Point(0.0, 0.0).buffer(RADIUS_M + LANE_M + 1.5).difference(
            shapely.Point(0.0, 0.0).buffer(RADIUS_M + LANE_M + 0.9)),
        shapely.box(0.0, -60.0, 60.0, 0.0))
    kerb = shapely.box(-12.0, -RADIUS_M - LANE_M - 2.0, -8.0, -RADIUS_M - LANE_M - 1.5)
    for ground in (corner, kerb):  # touched on the curve, and on the straight run
        spans = touch_intervals(pieces, ground, LENGTH_M)
        assert spans
        assert not touch_intervals(body_sweep(alone, LENGTH_M, WIDTH_M), ground, LENGTH_M)
        touched = 0
        for sigma in sigmas:
            for lane_path in (alone, detour.path):
                corners = chord_footprint(lane_path, float(sigma), LENGTH_M, WIDTH_M)
                assert float(shapely.distance(region, shapely.points(corners)).max()) <= 1e-9
                if not shapely.intersects(shapely.Polygon(corners), ground):
                    continue
                touched += 1
                station = path.point_at(float(sigma))[1]
                assert any(first - 1e-9 <= station <= last + LENGTH_M + 1e-9
                           for first, last in spans)
        assert touched > 10
    scales = {round(p.scale, 9) for p in pieces if p.scale != 1.0}
    assert scales and all(s == pytest.approx(alone.station[-1] / detour.path.station[-1])
                          for s in scales)

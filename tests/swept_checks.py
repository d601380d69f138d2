"""Checks shared by the swept-path tests (imported as ``swept_checks``: pytest puts tests/ on
the path for its conftest.py): the bus's footprints as SUMO places them, the model of
control/swept.py against them, and a pedestrian standing where only the body's sweep reaches.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import shapely

from sse_cosim.control.picture import SceneContext, Source, assess
from sse_cosim.control.swept import RoutePath, body_sweep, chord_footprint, swept_region
from sse_cosim.scenario.model import Scenario
from sse_cosim.world.roadmap import RoadMap
from sse_cosim.world.sumo import SumoWorld

TOLERANCE_M = 1e-6
"""How far a footprint SUMO reports may lie from the model's (m): SUMO's positions are
doubles, the model matches them to about 1e-13 m."""


def bus_footprints(scenario: Scenario, run_dir: Path, name: str,
                   vehicle_id: str = "bus") -> tuple[list[np.ndarray], RoadMap]:
    """Every step's footprint corners (4, 2) of ``vehicle_id`` as the world reports it (an
    oriented rectangle from SUMO's front position and angle) over the scenario's duration, and
    the run's road map."""
    with SumoWorld(scenario, run_dir, name) as world:
        corners = []
        for _ in range(round(scenario.simulation.duration_s / scenario.simulation.step_length_s)):
            vehicle = world.step().vehicles.get(vehicle_id)
            if vehicle is not None:
                corners.append(vehicle.footprint.corners())
        return corners, world.roadmap


def assert_in_sweep(corners: Sequence[np.ndarray], path: RoutePath, length: float,
                    width: float) -> None:
    """Every footprint (corners (4, 2) each) lies in the swept region of ``path``, within
    :data:`TOLERANCE_M`."""
    region = swept_region(body_sweep(path, length, width))
    points = shapely.points(np.vstack(corners))
    assert float(shapely.distance(region, points).max()) <= TOLERANCE_M


def assert_placed_as_modelled(corners: Sequence[np.ndarray], line: shapely.LineString,
                              path: RoutePath, length: float, width: float) -> None:
    """Every footprint (corners (4, 2) each) is the model's footprint with the front where
    SUMO's is (projected onto the route's ``line``), within :data:`TOLERANCE_M`."""
    assert abs(line.length - float(path.station[-1])) <= TOLERANCE_M
    for rectangle in corners:
        front = 0.5 * (rectangle[1] + rectangle[2])
        sigma = float(np.interp(line.project(shapely.Point(front)), path.station, path.sigma))
        assert np.abs(chord_footprint(path, sigma, length, width) - rectangle).max() \
            <= TOLERANCE_M


def assert_in_the_way(context: SceneContext, spot: shapely.Point, radius: float,
                      touching_m: Sequence[float], front_m: float) -> None:
    """A pedestrian of ``radius`` (m) standing at ``spot``, which the old zones (walkable
    ground within half the bus width plus ``radius`` of the centre line) leave out and the
    body touches while its front is at the route stations ``touching_m`` (m), is in conflict
    zones whose extents together hold those stations (a long piece of ground is cut into
    overlapping zones, so the spot may lie in more than one), arrives in each at once, and
    leaves the bus (its front at station ``front_m``, at 6 m/s) no pass."""
    old = context.route_line.buffer(0.5 * context.bus.width_m + radius, cap_style="flat")
    assert not old.intersects(spot)
    assert touching_m
    zones = [z for z in context.zones if z.polygon.shape.intersects(spot)]
    assert zones
    for station in touching_m:
        assert any(z.start_m <= station <= z.end_m + context.bus.length_m for z in zones), station
    front = shapely.get_coordinates(context.route_line.interpolate(front_m))[0]
    nothing, here = context.kind.empty(), context.kind.outer(spot.buffer(0.05))
    seen = assess(context, front, 6.0, nothing, Source(nothing), [Source(here)], [Source(here)])
    outlooks = [o for o in seen.zones if any(context.zones[o.index] is z for z in zones)]
    assert outlooks
    assert all(o.arrival_s == 0.0 and o.in_view_arrival_s == 0.0 for o in outlooks)
    assert not seen.path_clear

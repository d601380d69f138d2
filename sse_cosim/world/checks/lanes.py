"""``planned_lanes``: each automated vehicle drives on the lanes its controller plans on.

The controller plans on each route edge's rightmost driving lane that leads on, with a lane
change where the route cannot be driven lane to lane (``RoadMap.route_plan``): its zones,
arrivals and position along the route all assume the body within the ground its sweep covers
there, on either lane while a change is under way (:mod:`sse_cosim.control.swept`, widened by
a pedestrian's radius as the controller's is). SUMO changes none of an automated vehicle's
lanes of its own accord (lane change mode 512) but those the world asks for, so a body
elsewhere means a lane change that came from elsewhere, another departure lane, or a junction
passage drawn otherwise: checked every step, to :data:`OFF_PLAN_TOL_M`, once the body's back
is on the route. Not an assumption a study can list: a break stops the run.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import shapely

from sse_cosim.control.swept import body_sweep, swept_region
from sse_cosim.world.checks.base import Break, CheckSetup, StepFacts, WorldCheck
from sse_cosim.world.snapshot import Snapshot

OFF_PLAN_TOL_M = 1e-6
"""How far (m) a body SUMO reports may lie outside its planned sweep: SUMO's positions are
doubles, the sweep's model matches them to about 1e-13 m (tests/swept_checks.py)."""


@dataclass(frozen=True)
class PlannedSweep:
    """The ground (``ground``, prepared) a body ``length_m`` long sweeps along a vehicle's
    planned lanes, ``width_m`` wide (its width and a pedestrian's radius each side)."""

    ground: shapely.Geometry
    length_m: float
    width_m: float

    def off_m(self, corners: np.ndarray, route_m: float) -> float:
        """How far (m) the body with its footprint ``corners`` (4, 2), counter-clockwise from
        the rear right, widened to the sweep's width, lies outside :attr:`ground`: the largest
        distance of its corners and the middles of its sides (0: on the plan). 0 while its
        back is not yet on the route (``route_m``, SUMO's distance of its front, less than a
        body length): the sweep puts that back at the route's start, where SUMO puts it on
        the lane before the route's first one (turned by up to 2 degrees on the whole
        town)."""
        if route_m < self.length_m:
            return 0.0
        right, left = corners[0] - corners[3], corners[3] - corners[0]
        width = math.hypot(float(left[0]), float(left[1]))
        grow = 0.5 * (self.width_m - width) / width
        wide = corners + grow * np.array([right, right, left, left])  # (4, 2)
        points = np.vstack([wide, 0.5 * (wide + np.roll(wide, -1, axis=0))])  # (8, 2)
        if shapely.contains_xy(self.ground, points[:, 0], points[:, 1]).all():
            return 0.0
        return float(shapely.distance(self.ground, shapely.points(points)).max())


class PlannedLanesCheck(WorldCheck):
    """Each automated vehicle's body lies in its planned sweep (module docstring);
    ``sweeps``: each one's, by vehicle id."""

    name: ClassVar[str] = "planned_lanes"
    summary_key: ClassVar[str] = "lane_breaks"

    def __init__(self, sweeps: dict[str, PlannedSweep]) -> None:
        self.sweeps = sweeps

    @classmethod
    def build(cls, setup: CheckSetup) -> PlannedLanesCheck | None:
        width = 2.0 * setup.scenario.pedestrian_radius_m()
        sweeps = {}
        for vid, path in setup.route_paths.items():
            vehicle = setup.scenario.automated[vid]
            ground = swept_region(body_sweep(path, vehicle.length_m, vehicle.width_m + width))
            shapely.prepare(ground)
            sweeps[vid] = PlannedSweep(ground, vehicle.length_m, vehicle.width_m + width)
        return cls(sweeps) if sweeps else None

    def check(self, snapshot: Snapshot, facts: StepFacts) -> Sequence[Break]:
        found = []
        for vid, sweep in self.sweeps.items():
            vehicle = snapshot.vehicles.get(vid)
            if vehicle is None or vehicle.route_m is None:
                continue
            off = sweep.off_m(vehicle.footprint.corners(), vehicle.route_m)
            if off > OFF_PLAN_TOL_M:
                found.append(self._break(vid, snapshot.time, off))
        return found

    def _break(self, vid: str, time: float, off: float) -> Break:
        return Break(
            f"automated vehicle {vid!r} at t={time:.2f} s has its body {off:.3f} m outside the "
            "lanes its controller plans on (the route's edges, each on its planned driving "
            "lane, either lane of a planned change); the run stops before it decides on a "
            "picture of other lanes",
            "the controller plans on each edge's rightmost driving lane that leads on "
            "(RoadMap.route_plan) and SUMO changes none of its lanes of its own accord, so "
            "SUMO drives it where the planned sweep does not reach (a junction passage drawn "
            "otherwise): route the vehicle over other edges, and report the network with this "
            "line (docs/own_network.md)",
            {"vehicle": vid, "t": time, "off_m": round(off, 6)})

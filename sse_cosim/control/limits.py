"""The speed limits along a vehicle's route: pure data from the road map (no SUMO).

SUMO holds a vehicle to the limit of the lane its front is on, whatever ``vehicle.setSpeed``
asks (speed mode 31), and brakes at the vehicle's deceleration ahead of a lower limit so as
to reach it at the lane's start. The controller's passes therefore hold at most the slowest
speed SUMO may allow on the stretch they drive (:meth:`RouteLimits.least`), and its commands
at most the limit where the front is (:meth:`RouteLimits.at`): docs/controller.md, "Speed
limits". Positions and distances here are SUMO's distance along the route, in which it drives
the vehicle at its speed (:meth:`sse_cosim.control.swept.RoutePath.drive`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from sse_cosim.world.roadmap import LaneChange, LaneGeometry


@dataclass(frozen=True)
class RouteLimits:
    """Piecewise-constant limits along the route: lane k spans ``[ends_m[k-1], ends_m[k])``
    (the first from minus infinity, the last to plus infinity) at ``speeds_mps[k]``; shapes
    (n,) each, ``ends_m`` increasing, in SUMO's distance along the route (each lane's
    ``length``, which SUMO drives at the vehicle's speed, whatever its shape's length)."""

    ends_m: np.ndarray
    speeds_mps: np.ndarray

    @classmethod
    def of_lanes(cls, lanes: Sequence[LaneGeometry],
                 changes: Sequence[LaneChange] = ()) -> RouteLimits:
        """The limits of ``lanes``, the route's lanes in order, with its lane changes
        (``RoadMap.route_plan``): on the edge of a change, the least limit of the lanes the
        vehicle may be on there."""
        least = {}
        for change in changes:
            for route in change.detours:
                least[change.edge_id] = min(least.get(change.edge_id, math.inf),
                                            route[-1].speed_mps)
        return cls(np.cumsum([lane.length for lane in lanes]),
                   np.array([min(lane.speed_mps, least.get(lane.edge_id, math.inf))
                             for lane in lanes]))

    def at(self, s: float) -> float:
        """The limit (m/s) at ``s`` m along the route."""
        k = min(int(np.searchsorted(self.ends_m, s, side="right")), len(self.ends_m) - 1)
        return float(self.speeds_mps[k])

    def least(self, start_m: float, end_m: float, decel_mps2: float) -> float:
        """The fastest speed (m/s) SUMO may hold the front to somewhere on ``[start_m,
        end_m]``: the least limit on it, and, for a lower limit beyond it, the speed from which
        braking at ``decel_mps2`` just reaches that limit where it starts, sqrt(l^2 + 2 b g)
        for a gap g (SUMO brakes ahead of a lower limit at the vehicle's deceleration, and no
        sooner: its speed there stays above this bound, docs/controller.md)."""
        starts = np.r_[-np.inf, self.ends_m[:-1]]  # (n,)
        ahead = np.r_[self.ends_m[:-1], np.inf] >= start_m  # lanes not yet left behind
        gap = np.maximum(0.0, starts[ahead] - end_m)
        return float(np.sqrt(self.speeds_mps[ahead] ** 2 + 2.0 * decel_mps2 * gap).min())

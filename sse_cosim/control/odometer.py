"""Where along its route a vehicle is, as SUMO counts it: pure data from the road map.

SUMO moves a vehicle along a lane by the lane's ``length`` attribute, and draws it on the
lane's shape scaled to that length: at lane position ``p`` the front is at
``shape.positionAtOffset(p * shape_length / length)``. A network may give a lane a length
other than its shape's (on the town's OSM extract 1,007 of 11,605 driving lanes differ by
more than 0.5 m, 211 by more than 5 %), so a bus that SUMO drives at ``v`` moves along the
drawn route at ``v * shape_length / length``. The controller's kinematics (speeds, stopping
and clearing distances, speed limits) are in SUMO's distance, its geometry (zones, the swept
path, the along-route position of the drawn front) in metres of the drawn route; this map
turns the one into the other, lane by lane (docs/controller.md, "SUMO's distance").
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely

from sse_cosim.world.roadmap import LaneGeometry


@dataclass(frozen=True)
class RouteOdometer:
    """A piecewise-linear map from the drawn route (``RoadMap.route_line``, m) to SUMO's
    distance along the route (m, from the start of its first lane; ``depart_pos_m`` plus the
    vehicle's odometer). Knots ``drawn_m`` and ``drive_m``, shapes (2n,) for n lanes: each
    lane's first and last vertex on the drawn route, at the sum of the lengths of the lanes
    before it and that sum plus its own length. Between two lanes whose shapes do not meet
    the drawn route bridges the gap and SUMO's distance stays; before the route and beyond
    it both advance alike."""

    drawn_m: np.ndarray
    drive_m: np.ndarray

    @classmethod
    def of_lanes(cls, lanes: Sequence[LaneGeometry]) -> RouteOdometer:
        """The map of ``lanes``, the route's lanes in order (``RoadMap.route_lanes``, whose
        shapes, joined, are the route line)."""
        coords = np.concatenate([lane.shape for lane in lanes])  # (k, 2)
        # GEOS's segment lengths, as the route line's along-route position measures them
        steps = shapely.length(shapely.linestrings(
            np.stack([coords[:-1], coords[1:]], axis=1)))  # (k - 1,)
        stations = np.r_[0.0, np.cumsum(steps)]  # (k,)
        last = np.cumsum([len(lane.shape) for lane in lanes]) - 1  # (n,)
        first = np.r_[0, last[:-1] + 1]
        lengths = np.array([lane.length for lane in lanes])
        starts = np.r_[0.0, np.cumsum(lengths)[:-1]]
        drawn = np.column_stack([stations[first], stations[last]]).ravel()
        drive = np.column_stack([starts, starts + lengths]).ravel()
        return cls(drawn, drive)

    def drive(self, drawn_m: float) -> float:
        """SUMO's distance (m) at ``drawn_m`` m along the drawn route."""
        if drawn_m <= self.drawn_m[0]:
            return float(self.drive_m[0] + drawn_m - self.drawn_m[0])
        if drawn_m >= self.drawn_m[-1]:
            return float(self.drive_m[-1] + drawn_m - self.drawn_m[-1])
        return float(np.interp(drawn_m, self.drawn_m, self.drive_m))

    def drawn(self, drive_m: float) -> float:
        """The position (m) along the drawn route at SUMO's distance ``drive_m``: the
        inverse of :meth:`drive` (at a gap between lanes, its far end)."""
        if drive_m <= self.drive_m[0]:
            return float(self.drawn_m[0] + drive_m - self.drive_m[0])
        if drive_m >= self.drive_m[-1]:
            return float(self.drawn_m[-1] + drive_m - self.drive_m[-1])
        k = int(np.searchsorted(self.drive_m, drive_m, side="right"))
        low, high = self.drive_m[k - 1], self.drive_m[k]
        return float(self.drawn_m[k - 1] + (drive_m - low) / (high - low) * (
            self.drawn_m[k] - self.drawn_m[k - 1]))

"""``route_odometer``: each automated vehicle's front is where SUMO's odometer puts it on its
route.

The controller reads how far along its route a vehicle is from SUMO's odometer (its
departure position plus ``vehicle.getDistance``, ``VehicleState.route_m``), and stops,
passes and speed limits in that distance, while its zones lie on the drawn route
(docs/controller.md, "SUMO's distance"). The two agree only if SUMO draws the front where the
route's lanes, each its ``length`` stretched over its shape, put that distance
(:meth:`~sse_cosim.control.swept.RoutePath.point_at`; while a lane change is under way, on
either lane, :meth:`~sse_cosim.control.swept.RoutePath.points_at`): checked every step, to
:data:`ODOMETER_TOL_M`. Not an assumption a study can list: a break stops the run.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar

from sse_cosim.control.swept import RoutePath
from sse_cosim.sets import portable
from sse_cosim.world.checks.base import Break, CheckSetup, StepFacts, WorldCheck
from sse_cosim.world.snapshot import Snapshot

ODOMETER_TOL_M = 1e-6
"""How far (m) SUMO's front may lie from where its odometer puts it on the route: SUMO's
positions are doubles, and the map matches them to about 1e-13 m on the town."""


class OdometerCheck(WorldCheck):
    """Each automated vehicle's front lies where its odometer puts it (module docstring);
    ``paths``: each one's route as SUMO drives it, by vehicle id."""

    name: ClassVar[str] = "route_odometer"
    summary_key: ClassVar[str] = "odometer_breaks"

    def __init__(self, paths: dict[str, RoutePath]) -> None:
        self.paths = paths

    @classmethod
    def build(cls, setup: CheckSetup) -> OdometerCheck | None:
        paths = setup.route_paths
        return cls(paths) if paths else None

    def check(self, snapshot: Snapshot, facts: StepFacts) -> Sequence[Break]:
        found = []
        for vid, path in self.paths.items():
            vehicle = snapshot.vehicles.get(vid)
            if vehicle is None or vehicle.route_m is None:
                continue
            front = vehicle.footprint.front.position
            off = min(float(portable.hypot(*(front - expected)))
                      for expected in path.points_at(vehicle.route_m))
            if off > ODOMETER_TOL_M:
                found.append(self._break(vid, snapshot.time, vehicle.route_m, off))
        return found

    def _break(self, vid: str, time: float, route_m: float, off: float) -> Break:
        return Break(
            f"automated vehicle {vid!r} at t={time:.2f} s has driven {route_m:.3f} m along its "
            f"route by SUMO's odometer, but SUMO draws its front {off:.3f} m from where its "
            "route's lanes put that distance; the run stops before its controller decides on "
            "distances SUMO does not drive",
            "the controller reads SUMO's distance along the route's lanes, each its length "
            "drawn along its shape (RoutePath): report the network with this line "
            "(docs/own_network.md)",
            {"vehicle": vid, "t": time, "route_m": round(route_m, 3), "off_m": round(off, 6)})

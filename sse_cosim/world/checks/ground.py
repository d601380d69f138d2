"""``walkable_ground``: every pedestrian's true centre lies on the walkable ground.

The road map's :attr:`~sse_cosim.world.roadmap.RoadMap.walkable` (sidewalks, walking areas and
crossings, the measured patches included), to
:data:`~sse_cosim.world.roadmap.WALKABLE_TOL_M`. A break names the pedestrian, the time, its
lane, how far off it is and the fix.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar

import shapely

from sse_cosim.world.checks.base import Break, CheckSetup, StepFacts, WorldCheck
from sse_cosim.world.checks.motion import lane_name
from sse_cosim.world.roadmap import WALKABLE_TOL_M, RoadMap
from sse_cosim.world.snapshot import Snapshot


class GroundCheck(WorldCheck):
    """The pedestrians stay on ``roadmap.walkable`` (see module docstring)."""

    name: ClassVar[str] = "walkable_ground"
    summary_key: ClassVar[str] = "ground_breaks"

    def __init__(self, roadmap: RoadMap) -> None:
        self.roadmap = roadmap
        shapely.prepare(roadmap.walkable)

    @classmethod
    def build(cls, setup: CheckSetup) -> GroundCheck:
        return cls(setup.roadmap)

    def check(self, snapshot: Snapshot, facts: StepFacts) -> Sequence[Break]:
        walkable = self.roadmap.walkable
        found = []
        for pid, person in snapshot.persons.items():
            x, y = person.position
            if shapely.intersects_xy(walkable, x, y):
                continue
            off_m = float(shapely.distance(walkable, shapely.Point(x, y)))
            if off_m > WALKABLE_TOL_M:  # else on its edge, to the rounding of SUMO's positions
                found.append(self._break(pid, snapshot.time, off_m,
                                         facts.lanes_now.get(pid, "")))
        return found

    def _break(self, pid: str, time: float, off_m: float, lane: str) -> Break:
        return Break(
            f"pedestrian {pid!r} at t={time:.2f} s (lane {lane_name(lane)}) is {off_m:.3f} m "
            "off the walkable ground (sidewalks, walking areas and crossings, and the patches "
            "where SUMO's lone walkers were measured to leave them); the run stops before the "
            "estimator's sets are checked against a truth outside its model",
            "keep the pedestrian's walk (or the route file's person) on sidewalks, walking "
            "areas and crossings -- SUMO's walkers were measured there alone, not in a crowd "
            "or turning back -- or, for walkers that push each other off a walking area, set "
            "estimator.junction_ground_margin_m (now "
            f"{self.roadmap.junction_margin_m:g} m) to at least how far off it was, or list "
            f"'{self.name}' in breaks_assumptions in a study that breaks it on purpose",
            {"pedestrian": pid, "t": time, "off_m": round(off_m, 3), "lane": lane})

"""``pedestrian_lights``: walkers keep to the pedestrian lights, and the lights to their programs.

The controller's earliest arrivals rely on it (docs/controller.md, "Traffic lights"): a walker
who is not on a signalised crossing while its light shows red does not step onto it before
the light can change, so it arrives in a zone on that crossing no sooner than that. Three
statements, each checked every step:

1. every traffic light of the scene for which the network defines programs runs one of them,
   showing its current phase's state (the bound
   :func:`~sse_cosim.world.signals.earliest_release_s` reads the program). A light the
   network defines no program for (a rail signal, whose states SUMO works out as trains come)
   gives no bound (:meth:`~sse_cosim.world.signals.CrossingLights.release_s` is 0 for it at
   every step), so no claim rests on its states and they are not checked;
2. no walker steps onto a crossing while its light shows red (SUMO's walkers wait for their
   green; the snapshot's state is the one SUMO moved the walkers under);
3. a walker on a crossing has its centre within the crossing's area grown by
   :func:`on_crossing_reach_m` (its radius): the controller tells walkers on a crossing from
   walkers off it by their regions meeting that;
4. a walker off a signalised crossing has its centre off the crossing's own ground
   (:attr:`~sse_cosim.world.roadmap.RoadMap.own_grounds`, closed): the controller's rule
   holds for zones on that ground.

A break names the walker or the light, the time and the fix.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar

import numpy as np
import shapely

from sse_cosim.world.checks.base import Break, CheckSetup, StepFacts, WorldCheck
from sse_cosim.world.checks.motion import lane_name
from sse_cosim.world.roadmap import RoadMap
from sse_cosim.world.snapshot import Snapshot

AREA_TOL_M = 1e-6
"""Slack (m) of the statements on areas: the rounding of SUMO's positions along a lane a few
kilometres from the origin is about 1e-12 m."""


def on_crossing_reach_m(radius_m: float) -> float:
    """How far (m) a walker of body radius ``radius_m`` on a crossing may have its centre
    outside the crossing's area: SUMO places a walker by its front, so one stepping onto the
    crossing at an end has its centre up to its radius behind (0.245 m at the end of
    tests/networks/two_lanes/'s crossing), plus :data:`AREA_TOL_M`."""
    return radius_m + AREA_TOL_M


class LightsCheck(WorldCheck):
    """The three statements of the module docstring, on ``roadmap``'s signalised crossings."""

    name: ClassVar[str] = "pedestrian_lights"
    summary_key: ClassVar[str] = "light_breaks"

    def __init__(self, roadmap: RoadMap, radius_m: float) -> None:
        self.roadmap = roadmap
        self.reach_m = on_crossing_reach_m(radius_m)
        self.signalised = {c.id: c for c in roadmap.crossings if c.signals}
        self.lights = {cid: roadmap.crossing_lights(c) for cid, c in self.signalised.items()}
        # a walker off the crossing stays out of its own ground: one tree of them all
        self.own_ids = list(roadmap.own_grounds)
        self.own_tree = shapely.STRtree(list(roadmap.own_grounds.values()))
        self.programmed = {light for light, _ in roadmap.programs}  # statement 1's lights
        self._on: dict[str, str | None] = {}  # walker -> its crossing at the previous step

    @classmethod
    def build(cls, setup: CheckSetup) -> LightsCheck | None:
        return cls(setup.roadmap, setup.scenario.pedestrian_radius_m()) \
            if setup.roadmap.lights else None

    def check(self, snapshot: Snapshot, facts: StepFacts) -> Sequence[Break]:
        found = [*self._programs(snapshot), *self._steps_on(snapshot), *self._areas(snapshot),
                 *self._own_grounds(snapshot, facts)]
        self._on = {pid: person.crossing for pid, person in snapshot.persons.items()}
        return found

    def _programs(self, snapshot: Snapshot) -> list[Break]:
        found = []
        for light, state in snapshot.signals.items():
            if light not in self.programmed:
                continue
            program = self.roadmap.programs.get((light, state.program))
            expected = None if program is None or state.phase >= len(program.phases) \
                else program.phases[state.phase].state
            if expected != state.state:
                found.append(Break(
                    f"traffic light {light!r} at t={snapshot.time:.2f} s runs program "
                    f"{state.program!r}, phase {state.phase}, showing {state.state!r}, which "
                    "is not a phase of the programs the network defines; the controller bounds "
                    "when its walkers may step on from those programs",
                    "run the network's own signal programs (no additional program files, no "
                    f"switching them), or list '{self.name}' in breaks_assumptions",
                    {"light": light, "t": snapshot.time, "program": state.program,
                     "phase": state.phase, "state": state.state}))
        return found

    def _steps_on(self, snapshot: Snapshot) -> list[Break]:
        found = []
        for pid, person in snapshot.persons.items():
            cid = person.crossing
            if cid not in self.signalised or pid not in self._on or self._on[pid] == cid:
                continue
            if self.lights[cid].release_s(snapshot.signals) > 0.0:
                found.append(Break(
                    f"pedestrian {pid!r} stepped onto crossing {cid} at t={snapshot.time:.2f} s "
                    "while its light showed red",
                    "keep SUMO's walkers to their lights (no route file person that ignores "
                    f"them), or list '{self.name}' in breaks_assumptions",
                    {"pedestrian": pid, "t": snapshot.time, "crossing": cid}))
        return found

    def _areas(self, snapshot: Snapshot) -> list[Break]:
        found = []
        for pid, person in snapshot.persons.items():
            crossing = self.signalised.get(person.crossing or "")
            if crossing is None:
                continue
            off_m = float(shapely.distance(crossing.area, shapely.Point(person.position)))
            if off_m > self.reach_m:
                found.append(Break(
                    f"pedestrian {pid!r} on crossing {crossing.id} at t={snapshot.time:.2f} s "
                    f"is {off_m:.3f} m outside the crossing's area (a walker's radius, "
                    f"{self.reach_m:.3f} m, may be)",
                    "report this network to the project (SUMO placed a walker off its "
                    f"crossing's lane), or list '{self.name}' in breaks_assumptions",
                    {"pedestrian": pid, "t": snapshot.time, "crossing": crossing.id,
                     "off_m": round(off_m, 3)}))
        return found

    def _own_grounds(self, snapshot: Snapshot, facts: StepFacts) -> list[Break]:
        """Statement 4, for every walker against every own ground in one query of the tree
        (a whole town has a hundred signalised crossings and its route files' walkers)."""
        persons = list(snapshot.persons.items())
        if not persons or not self.own_ids:
            return []
        points = shapely.points(np.array([person.position for _, person in persons]))  # (k,)
        hits = self.own_tree.query(points, predicate="intersects")  # (2, n): walker, ground
        found = []
        for k, g in sorted(zip(hits[0].tolist(), hits[1].tolist(), strict=True)):
            (pid, person), cid = persons[k], self.own_ids[g]
            if person.crossing == cid:
                continue
            lane = facts.lanes_now.get(pid, "")
            found.append(Break(
                f"pedestrian {pid!r} at t={snapshot.time:.2f} s is on crossing "
                f"{cid}'s own ground (its area less every other walkable ground) "
                f"while SUMO has it on lane {lane_name(lane)}",
                "report this network to the project (SUMO placed a walker of a walking "
                f"area on a crossing), or list '{self.name}' in breaks_assumptions",
                {"pedestrian": pid, "t": snapshot.time, "crossing": cid, "lane": lane}))
        return found

"""``pedestrian_lights``: walkers keep to the pedestrian lights, and the lights to their programs.

The controller's earliest arrivals rely on it (docs/controller.md, "Traffic lights"): a walker
who is not on a signalised crossing while its light shows red does not step onto it before
the light can change, so it arrives in a zone on that crossing no sooner than that. Three
statements, each checked every step:

1. every traffic light of the scene runs a program of the network, showing its current phase's
   state (the bound :func:`~sse_cosim.world.signals.earliest_release_s` reads the program);
2. no walker steps onto a crossing before the release bound its light gave at the previous
   step, while the walker was off it (SUMO's walkers wait for their green);
3. a walker on a crossing has its centre within the crossing's area (to
   :data:`AREA_TOL_M`): the controller tells walkers on a crossing from walkers off it by
   their regions meeting that area.

A break names the walker or the light, the time and the fix.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar

import shapely

from sse_cosim.world.checks.base import Break, CheckSetup, StepFacts, WorldCheck
from sse_cosim.world.roadmap import Crossing, RoadMap
from sse_cosim.world.signals import WALKERS_WAIT, SignalState, earliest_release_s
from sse_cosim.world.snapshot import Snapshot

AREA_TOL_M = 1e-6
"""How far (m) a walker on a crossing may lie outside its area (the rounding of SUMO's
positions along a lane a few kilometres from the origin is about 1e-12 m)."""
TIME_TOL_S = 1e-6
"""Slack of the release bound against SUMO's clock (s)."""


def crossing_release_s(crossing: Crossing, roadmap: RoadMap,
                       signals: dict[str, SignalState]) -> float:
    """A lower bound (s) on how long no walker off ``crossing`` steps onto it: 0 unless every
    light of its links shows red now (:data:`~sse_cosim.world.signals.WALKERS_WAIT`), else the
    least time any of them can change (:func:`~sse_cosim.world.signals.earliest_release_s`,
    the network's program; 0 for a light the snapshot lacks or runs another program)."""
    if not crossing.signals:
        return 0.0
    waits = []
    for light, link in crossing.signals:
        state = signals.get(light)
        program = None if state is None else roadmap.programs.get((light, state.program))
        if state is None or program is None:
            return 0.0
        waits.append(earliest_release_s(program, state, link, WALKERS_WAIT))
    return min(waits)


class LightsCheck(WorldCheck):
    """The three statements of the module docstring, on ``roadmap``'s signalised crossings."""

    name: ClassVar[str] = "pedestrian_lights"
    summary_key: ClassVar[str] = "light_breaks"

    def __init__(self, roadmap: RoadMap) -> None:
        self.roadmap = roadmap
        self.signalised = {c.id: c for c in roadmap.crossings if c.signals}
        self._released_at: dict[str, float] = {}  # crossing -> when its walkers may step on
        self._on: dict[str, str | None] = {}  # walker -> its crossing at the previous step

    @classmethod
    def build(cls, setup: CheckSetup) -> LightsCheck | None:
        return cls(setup.roadmap) if setup.roadmap.lights else None

    def check(self, snapshot: Snapshot, facts: StepFacts) -> Sequence[Break]:
        found = [*self._programs(snapshot), *self._steps_on(snapshot), *self._areas(snapshot)]
        self._on = {pid: person.crossing for pid, person in snapshot.persons.items()}
        self._released_at = {
            cid: snapshot.time + crossing_release_s(crossing, self.roadmap, snapshot.signals)
            for cid, crossing in self.signalised.items()}
        return found

    def _programs(self, snapshot: Snapshot) -> list[Break]:
        found = []
        for light, state in snapshot.signals.items():
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
            released = self._released_at.get(cid, -float("inf"))
            if snapshot.time < released - TIME_TOL_S:
                found.append(Break(
                    f"pedestrian {pid!r} stepped onto crossing {cid} at t={snapshot.time:.2f} s "
                    f"while its light showed red, {released - snapshot.time:.2f} s before it "
                    "could change by the network's signal program",
                    "keep SUMO's walkers to their lights (no route file person that ignores "
                    f"them), or list '{self.name}' in breaks_assumptions",
                    {"pedestrian": pid, "t": snapshot.time, "crossing": cid,
                     "early_s": round(released - snapshot.time, 3)}))
        return found

    def _areas(self, snapshot: Snapshot) -> list[Break]:
        found = []
        for pid, person in snapshot.persons.items():
            crossing = self.signalised.get(person.crossing or "")
            if crossing is None:
                continue
            off_m = float(shapely.distance(crossing.area, shapely.Point(person.position)))
            if off_m > AREA_TOL_M:
                found.append(Break(
                    f"pedestrian {pid!r} on crossing {crossing.id} at t={snapshot.time:.2f} s "
                    f"is {off_m:.3f} m outside the crossing's area",
                    "report this network to the project (SUMO placed a walker off its "
                    f"crossing's lane), or list '{self.name}' in breaks_assumptions",
                    {"pedestrian": pid, "t": snapshot.time, "crossing": crossing.id,
                     "off_m": round(off_m, 3)}))
        return found

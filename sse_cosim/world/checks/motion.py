"""``pedestrian_speed``: every pedestrian's true position keeps the estimator's motion model.

A path with steps of at most ``max_pedestrian_speed_mps`` times the step length, plus a jitter
of at most ``position_jitter_m`` (:mod:`sse_cosim.world.assumptions`); for a model that bounds
the acceleration, one path that also changes its mean velocity by at most
``max_pedestrian_accel_mps2`` times the step length per step
(:mod:`sse_cosim.world.acceleration_assumption`; it keeps the speed bound too). A break names
the pedestrian, the time, its lanes before and after, what it broke and the fix.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar

from sse_cosim.scenario.model import Estimator
from sse_cosim.world.acceleration_assumption import AccelerationBounds, AccelerationCheck
from sse_cosim.world.assumptions import MotionBounds, MotionBreak, PedestrianMotionCheck
from sse_cosim.world.checks.base import Break, CheckSetup, StepFacts, WorldCheck
from sse_cosim.world.snapshot import Snapshot


def lane_name(lane_id: str) -> str:
    """A person's lane id for a message; a person on no lane waits at its start."""
    return repr(lane_id) if lane_id else "(none: waiting at its start)"


class MotionCheck(WorldCheck):
    """The estimator's motion model, its jitter resolved (see module docstring);
    ``accel_mps2``: the model's acceleration bound (None: speed-bounded); ``diagnose``: work
    out what a break needs (the jitter, the bound it broke) for its message."""

    name: ClassVar[str] = "pedestrian_speed"
    summary_key: ClassVar[str] = "assumption_breaks"

    def __init__(self, estimator: Estimator, step_s: float, accel_mps2: float | None,
                 diagnose: bool) -> None:
        assert estimator.position_jitter_m is not None
        self.estimator = estimator
        self.step_s = step_s
        self.accel = accel_mps2
        speed, jitter = estimator.max_pedestrian_speed_mps, estimator.position_jitter_m
        self._walks: PedestrianMotionCheck | AccelerationCheck = (
            PedestrianMotionCheck(MotionBounds(speed, jitter, step_s), needed_jitter=diagnose)
            if accel_mps2 is None else
            AccelerationCheck(AccelerationBounds(speed, accel_mps2, jitter, step_s),
                              diagnose=diagnose))

    @classmethod
    def build(cls, setup: CheckSetup) -> MotionCheck:
        return cls(setup.scenario.estimator, setup.scenario.simulation.step_length_s,
                   setup.accel_mps2, diagnose=not setup.declares(cls.name))

    def check(self, snapshot: Snapshot, facts: StepFacts) -> Sequence[Break]:
        found = self._walks.step(snapshot.time, {pid: person.position
                                                 for pid, person in snapshot.persons.items()})
        return [self._break(brk, facts.lanes_before.get(brk.person, ""),
                            facts.lanes_now.get(brk.person, "")) for brk in found]

    def _break(self, brk: MotionBreak, before: str, after: str) -> Break:
        needed = "" if brk.needed_jitter_m is None else f" to at least {brk.needed_jitter_m:.3f} m"
        return Break(
            f"pedestrian {brk.person!r} at t={brk.time:.2f} s moved {brk.step_m:.3f} m in "
            f"one step{self._velocity_change(brk)} (lane {lane_name(before)} -> "
            f"{lane_name(after)}), to {brk.distance_m:.3f} m from every path point the model "
            f"admits, {brk.beyond_m:.3f} m beyond estimator.position_jitter_m = "
            f"{self.estimator.position_jitter_m:g} m ({self._path_bounds(brk)}); the run stops "
            "before the estimator's sets are checked against a truth outside its model",
            f"raise estimator.position_jitter_m{needed} (what its walk so far needs), "
            f"or list '{self.name}' in breaks_assumptions",
            {"pedestrian": brk.person, "t": brk.time, "distance_m": round(brk.distance_m, 3),
             "beyond_m": round(brk.beyond_m, 3), "step_m": round(brk.step_m, 3),
             "lane_before": before, "lane_after": after})

    @staticmethod
    def _velocity_change(brk: MotionBreak) -> str:
        """How much the walk's mean velocity changed in the break's step, for its message
        (the acceleration's check measures it)."""
        if brk.velocity_change_mps is None:
            return ""
        return f", its mean velocity changing by {brk.velocity_change_mps:.2f} m/s"

    def _path_bounds(self, brk: MotionBreak) -> str:
        """The model's path bounds for a break's message, and which the walk broke."""
        speed = self.estimator.max_pedestrian_speed_mps
        if self.accel is None:
            return f"path steps of at most {speed:g} m/s x {self.step_s:g} s"
        return (f"no path keeps both the speed bound {speed:g} m/s and the acceleration bound "
                f"{self.accel:g} m/s² in steps of {self.step_s:g} s within it: its walk breaks "
                f"{brk.broke}")

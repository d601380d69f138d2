"""A scenario pedestrian's pause: it stops some time after stepping onto its crossing, stands
still a while, then walks on (``pedestrians.<id>.pause_after_s`` and ``pause_for_s``).

A pedestrian who hesitates on the zebra keeps every assumption of the estimator (A1 bounds
its speed, not how it varies: under the bounded-acceleration model the world's speed ramp
keeps the stop and the start within the acceleration bound), so the falsifier may search
when and how long it stops. Pure timing: the world (:mod:`sse_cosim.world.sumo`) knows when
the pedestrian stepped onto its crossing and sets the speed this gives.
"""

from __future__ import annotations

from dataclasses import dataclass

from sse_cosim.scenario.model import Pedestrian

TIME_EPS_S = 1e-6
"""Tolerance of the world's time comparisons (s): far below a step, far above the rounding of
a sum of step lengths."""


@dataclass(frozen=True)
class Pause:
    """Stop ``after_s`` after stepping onto the crossing, for ``for_s``; walk at
    ``walking_mps`` otherwise."""

    walking_mps: float
    after_s: float
    for_s: float

    @classmethod
    def of(cls, pedestrian: Pedestrian) -> Pause | None:
        """The pause of ``pedestrian``, None if it does not stop."""
        if pedestrian.pause_for_s <= 0.0:
            return None
        return cls(pedestrian.walking_speed_mps, pedestrian.pause_after_s,
                   pedestrian.pause_for_s)

    def speed(self, since_on_s: float | None) -> float:
        """Its speed (m/s) for the step that begins ``since_on_s`` after it stepped onto its
        crossing (None: it has not yet)."""
        if since_on_s is None:
            return self.walking_mps
        stopped = self.after_s - TIME_EPS_S <= since_on_s < self.after_s + self.for_s - TIME_EPS_S
        return 0.0 if stopped else self.walking_mps

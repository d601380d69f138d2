"""A scenario pedestrian's turn-back: some time after stepping onto its crossing it turns round,
walks back to the zebra's near end, waits there, then crosses after all and leaves the scene at
the far end (``pedestrians.<id>.turn_back_after_s`` and ``turn_back_wait_s``).

A pedestrian who starts across the zebra, thinks better of it and then goes keeps every
assumption of the estimator, as long as its speed stays within its walking speed and, under
the bounded-acceleration model, changes by at most a_max dt a step. SUMO's walking stages cannot
turn a walker round on a crossing (a replaced stage restarts at an edge's end: the walker
jumped 1.97 m; one placed by ``person.moveToXY`` and released jumped 1.9 m back onto its old
walk, and 12 m when it reached the crossing's end). So from the turn on the world holds the
walker still (speed 0) and places it on its crossing's lane before every step
(``person.moveTo``, which SUMO follows exactly on a crossing), along the path
:class:`CrossingWalker` gives, and removes it at the far end, as SUMO removes a walker at its
destination.

The path, of the pedestrian's centre along the lane (m from the lane's start):

1. it slows to a stop (at once without an acceleration bound) and walks back to the near end;
2. it stands there ``wait_s``;
3. it walks to the far end and stops there: then it leaves.

Speeds change as :class:`~sse_cosim.world.sumo_setup.SpeedRamp` changes a SUMO walker's: by at
most a_max dt from one step to the next, each step's displacement that step's speed times dt;
never above the walking speed. Pure kinematics, at whole steps.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from sse_cosim.scenario.model import Pedestrian
from sse_cosim.world.walker_pause import TIME_EPS_S


@dataclass(frozen=True)
class TurnBack:
    """Turn back ``after_s`` after stepping onto the crossing, wait ``wait_s`` at its near end,
    then cross; walk at most ``walking_mps``."""

    walking_mps: float
    after_s: float
    wait_s: float

    @classmethod
    def of(cls, pedestrian: Pedestrian) -> TurnBack | None:
        """The turn-back of ``pedestrian``, None if it crosses."""
        if pedestrian.turn_back_after_s is None:
            return None
        return cls(pedestrian.walking_speed_mps, pedestrian.turn_back_after_s,
                   pedestrian.turn_back_wait_s)

    def due(self, since_on_s: float | None) -> bool:
        """Whether it turns before the step that begins ``since_on_s`` after it stepped onto
        its crossing (None: it has not yet)."""
        return since_on_s is not None and since_on_s >= self.after_s - TIME_EPS_S


class CrossingWalker:
    """A turned pedestrian's centre along its crossing's lane (module docstring).

    ``at_m``: where it is (m from the lane's start); ``velocity_mps``: its velocity along the
    lane in the last step (signed, + toward the lane's end); ``near_m`` / ``far_m``: the ends
    it came from and goes to (where its centre stops); ``rise_mps``: a_max x ``step_s``, the
    most its speed changes in a step (None: no bound).
    """

    def __init__(self, at_m: float, velocity_mps: float, near_m: float, far_m: float,
                 walking_mps: float, wait_s: float, step_s: float,
                 rise_mps: float | None) -> None:
        self.at_m = at_m
        self.velocity_mps = velocity_mps
        self.far_m = far_m
        self.walking_mps = walking_mps
        self.step_s = step_s
        self.rise_mps = rise_mps
        self._wait_steps = max(round(wait_s / step_s - TIME_EPS_S), 0)
        self._target = near_m

    def step(self) -> float | None:
        """Move one step: where it is then (m along the lane), or None once it has stopped at
        the far end (it leaves the scene)."""
        if self.at_m == self._target and self.velocity_mps == 0.0:
            if self._target == self.far_m:
                return None
            if self._wait_steps > 0:
                self._wait_steps -= 1
                return self.at_m
            self._target = self.far_m
        self._toward(self._target)
        return self.at_m

    def _toward(self, target: float) -> None:
        """One step toward ``target``, stopping there."""
        left = target - self.at_m
        v, dt, rise = self.velocity_mps, self.step_s, self.rise_mps
        if rise is None:
            new = math.copysign(min(self.walking_mps, abs(left) / dt), left)
        elif v * left < 0.0 or (left == 0.0 and v != 0.0):  # moving away: slow down first
            new = v - math.copysign(min(rise, abs(v)), v)
        else:
            cap = min(self.walking_mps, abs(left) / dt, stopping_speed(abs(left), rise, dt))
            new = math.copysign(min(abs(v) + rise, cap), left)
        self.velocity_mps = new
        if new * left > 0.0 and abs(new) * dt >= abs(left):
            self.at_m = target  # exactly there, whatever the rounding
        else:
            self.at_m += new * dt


def stopping_speed(distance_m: float, rise_mps: float, step_s: float) -> float:
    """The highest speed from which slowing by ``rise_mps`` a step stops within ``distance_m``.

    From v the speeds are v, v - r, ..., v - n r (n = floor(v / r)), then 0: they cover
    D(v) = dt ((n + 1) v - r n (n + 1) / 2), which grows with v. The largest n with
    D(n r) = dt r n (n + 1) / 2 <= d is floor((sqrt(1 + 8 d / (r dt)) - 1) / 2), and D(v) = d
    then gives v. A walker at that speed covers v dt in the step and can stop in what is left
    from v - r: D(v) = v dt + D(v - r)."""
    r, dt = rise_mps, step_s
    n = math.floor((math.sqrt(1.0 + 8.0 * distance_m / (r * dt)) - 1.0) / 2.0)
    return min((distance_m / dt + r * n * (n + 1) / 2.0) / (n + 1), (n + 1) * r)


@dataclass(frozen=True)
class StraightLane:
    """A straight lane from ``start`` to ``end`` (network coordinates, m): a crossing's, as SUMO
    draws it. Points map to (along, lateral): metres from the start along it, and to its
    left (SUMO's lateral position)."""

    start: tuple[float, float]
    end: tuple[float, float]

    @property
    def length(self) -> float:
        return math.dist(self.start, self.end)

    @property
    def heading(self) -> float:
        """Its direction (rad, CCW from east)."""
        return math.atan2(self.end[1] - self.start[1], self.end[0] - self.start[0])

    def along(self, point: tuple[float, float]) -> float:
        ux, uy = math.cos(self.heading), math.sin(self.heading)
        return (point[0] - self.start[0]) * ux + (point[1] - self.start[1]) * uy

    def lateral(self, point: tuple[float, float]) -> float:
        ux, uy = math.cos(self.heading), math.sin(self.heading)
        return ux * (point[1] - self.start[1]) - uy * (point[0] - self.start[0])

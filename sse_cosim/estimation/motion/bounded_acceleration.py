"""The ``bounded-acceleration`` state model: x = (s, v), the path's position and velocity, with
|v| <= v_max and |a| <= a_max (the set-based pedestrian model of Koschi et al., ITSC 2018,
without their traffic-rule constraints; docs/method.md, "Bounded acceleration").

Discrete form. As in the constant-velocity model, v_k := (s_{k+1} - s_k) / dt is the path's
mean velocity over the next step, so the position row of F = [[I, dt I], [0, I]] is exact.
Two consecutive mean velocities differ by a hat-weighted integral of the acceleration whose
weights sum to dt, so ||v_{k+1} - v_k|| <= a_max dt: the process noise is the box
|dv_x|, |dv_y| <= a_max dt, which holds that disc. The speed bound ||v|| <= v_max holds for
every mean velocity; it is applied every step as strips |n.v| <= v_max along four directions
(an octagon that holds the disc).

Velocity over time. A node's strips of N steps ago bound its current state too
(:meth:`~.base.LinearModel.velocity_strips`): with the current ones they bound the velocity to
about (2 r + a_max T² / 2) / T over T = N dt, best near T = 2 sqrt(r / a_max), where it is
2 sqrt(r a_max) (r: the strips' radius, the jitter included). No sound estimator does better
than sqrt(r a_max): a path that stands and one that has sped up from standstill at a_max to
2 sqrt(r a_max) stay within 2 r of each other, so positions measured halfway between them
hold for both. So the velocity is known only where r is small
against v_max² / a_max (docs/method.md). Nodes use :data:`VELOCITY_WINDOWS_S`.

Reach and arrival. Along any unit direction n the path's velocity component n.v grows by at
most a_max per second and never exceeds v_max, so from a component u the path moves at most

    D(t; u) = integral_0^t min(v_max, u + a_max tau) dtau

along n in t seconds (the discrete path, a sum of its mean velocities, moves no farther at
the step times). A pedestrian whose state lies in a set Z, with velocity set V = Z's velocity
part, has n.v <= h_V(n) (V's support function). To be in a zone, its position must move a
gap g_n along n that the caller measures for each direction of a fan (the least n.q over the
zone minus the largest n.p over the pedestrian's region); the position strays at most eps
from the path at the zone, and at the start too where the region is of positions, so the
path moves at least g_n - eps along n from a path region, g_n - 2 eps from a position region
(:meth:`~.base.LinearModel.path_gap_m`, written G(g) below). So

    arrival >= max over n of T(G(g_n); min(v_max, h_V(n))),   T(d; u) = min t: D(t; u) >= d,

and also >= T(G(d); max speed in V) with d the straight-line distance (any direction),
and >= the speed-bounded arrival G(d) / v_max. Each is a lower bound of the true
arrival, so their largest is one too (docs/controller.md, "Earliest arrival").
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from sse_cosim.estimation.motion.base import LinearModel, Separation, unit_fan
from sse_cosim.estimation.motion.constant_velocity import linear_parts
from sse_cosim.sets import Strips, Zonotope, portable

if TYPE_CHECKING:
    from sse_cosim.scenario.model import Estimator

NAME = "bounded-acceleration"
VELOCITY_WINDOWS_S = (0.3, 0.6, 1.2, 2.4)  # how long ago a node's strips bound its velocity (s)
SPEED_DIRECTIONS = 32  # fan over which the largest speed in a velocity set is bounded
_OCTAGON = np.array([[1.0, 0.0], [0.0, 1.0], [math.sqrt(0.5), math.sqrt(0.5)],
                     [math.sqrt(0.5), -math.sqrt(0.5)]])


def build(config: Estimator, step_length: float, jitter: float) -> BoundedAcceleration:
    """The bounded-acceleration model of ``config`` for steps of ``step_length`` seconds."""
    v_max, a_max = config.max_pedestrian_speed_mps, config.max_pedestrian_accel_mps2
    speed_rows = np.hstack([np.zeros((4, 2)), _OCTAGON])
    return BoundedAcceleration(
        **linear_parts(step_length, a_max * step_length),
        state_bounds=Strips(speed_rows, np.zeros(4), np.full(4, v_max)),
        max_speed=v_max,
        step_length=step_length,
        jitter=jitter,
        velocity_windows=tuple(sorted({max(1, round(t / step_length))
                                       for t in VELOCITY_WINDOWS_S})),
        max_accel=a_max,
    )


@dataclass(frozen=True)
class BoundedAcceleration(LinearModel):
    """A :class:`LinearModel` of the state (s, v) whose path also accelerates at most
    ``max_accel`` (m/s²): its reach and arrivals use the state's velocity set."""

    max_accel: float = field(kw_only=True)

    def __post_init__(self) -> None:
        super().__post_init__()
        if not (np.isfinite(self.max_accel) and self.max_accel > 0):
            raise ValueError(f"max acceleration must be finite and > 0; got {self.max_accel}")
        if self.dim != 4:
            raise ValueError("the bounded-acceleration model's state is (position, velocity)")

    @property
    def acceleration_bound_mps2(self) -> float:
        return self.max_accel

    @property
    def uses_state(self) -> bool:
        return True

    def reach_m(self, steps: int = 1, state: Zonotope | None = None) -> float:
        """D(steps dt; u) with u the largest speed in ``state``'s velocity set (v_max without
        a state): how far the path can move in ``steps`` steps."""
        if state is None:
            return super().reach_m(steps)
        speed = float(self.largest_speed(state))
        return float(self.distance_within(np.array([steps * self.step_length]),
                                          np.array([speed]))[0])

    def earliest_arrival_s(self, distance_m: np.ndarray, state: Zonotope | None = None,
                           separation: Separation | None = None,
                           of_path: bool = False) -> np.ndarray:
        """The module's bound for each distance d (m), shape (z,): the speed-bounded arrival,
        raised by what ``state``'s velocity set and the ``separation`` fan prove (both
        measured from a path region if ``of_path``, else from a position region)."""
        arrival = super().earliest_arrival_s(distance_m, of_path=of_path)
        if state is None:
            return arrival
        speed = np.full(np.shape(distance_m), self.largest_speed(state))
        arrival = np.maximum(arrival, self.travel_time(self.path_gap_m(distance_m, of_path),
                                                       speed))
        if separation is None:
            return arrival
        toward = np.broadcast_to(self.velocity_support(state, separation.directions),
                                 separation.gaps_m.shape)  # (z, K)
        fan = self.travel_time(self.path_gap_m(separation.gaps_m, of_path), toward)
        return np.maximum(arrival, fan.max(axis=1))

    def velocity_support(self, state: Zonotope, directions: np.ndarray) -> np.ndarray:
        """h_V(n) = n.c + sum_i |n.g_i| for each unit direction n of ``directions`` (K, 2), with
        V = ⟨c, G⟩ the velocity part of ``state``; shape (K,), capped at v_max."""
        center, generators = state.center[2:], state.generators[2:, :]
        support = portable.matmul(directions, center) + np.abs(
            portable.matmul(directions, generators)).sum(axis=1)
        return np.minimum(support, self.max_speed)

    def largest_speed(self, state: Zonotope) -> float:
        """An upper bound of ||v|| over ``state``'s velocity set, capped at v_max: the largest
        support over a fan of :data:`SPEED_DIRECTIONS` directions divided by cos(pi / K) (every
        vector lies within pi / K of a fan direction)."""
        support = self.velocity_support(state, self._speed_fan)
        bound = float(support.max()) / portable.cos(math.pi / SPEED_DIRECTIONS)
        return min(max(bound, 0.0), self.max_speed)

    @cached_property
    def _speed_fan(self) -> np.ndarray:
        """:data:`SPEED_DIRECTIONS` unit directions, shape (K, 2) (built once)."""
        return unit_fan(SPEED_DIRECTIONS)

    def distance_within(self, time_s: np.ndarray, toward_mps: np.ndarray) -> np.ndarray:
        """D(t; u) (m): the farthest the path moves along a direction in ``time_s`` seconds from
        a velocity component ``toward_mps`` there (same shapes)."""
        v, a = self.max_speed, self.max_accel
        u = np.clip(toward_mps, -v, v)
        ramp_s = (v - u) / a
        within = np.minimum(time_s, ramp_s)
        return u * within + 0.5 * a * within * within + v * np.maximum(0.0, time_s - ramp_s)

    def travel_time(self, gap_m: np.ndarray, toward_mps: np.ndarray) -> np.ndarray:
        """T(d; u) (s): the least time in which the path can move ``gap_m`` (>= 0) along a
        direction from a velocity component ``toward_mps`` there (same shapes): accelerate at
        a_max up to v_max, then keep v_max."""
        v, a = self.max_speed, self.max_accel
        u = np.clip(toward_mps, -v, v)
        ramp_m = (v * v - u * u) / (2.0 * a)  # covered while speeding up to v_max
        root = np.sqrt(u * u + 2.0 * a * gap_m)
        with np.errstate(divide="ignore", invalid="ignore"):
            speeding = np.where(u > 0.0, 2.0 * gap_m / (u + root), (root - u) / a)
        speeding = np.where(gap_m > 0.0, speeding, 0.0)
        cruising = (v - u) / a + (gap_m - ramp_m) / v
        return np.where(gap_m <= ramp_m, speeding, cruising)

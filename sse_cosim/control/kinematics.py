"""The bus's longitudinal motion as the controller predicts it: pure 1-D kinematics.

SUMO moves a vehicle that follows ``vehicle.setSpeed`` one step at a time (Euler update, its
default): the speed moves toward the command by at most ``accel * dt`` up or ``decel * dt``
down, then the position advances by the *new* speed times ``dt``. The controller predicts
with exactly that update, so its look-ahead and the simulated bus agree step for step.

A comfortable stop starts one step after the command that orders it (the command issued
now acts over the next step) and is padded by the reaction time: the stopping distance and
time below are upper bounds of what SUMO's update does (the Euler sum overshoots the
continuous braking distance ``v^2 / 2b`` by at most ``v dt``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from sse_cosim.scenario.model import AutomatedVehicle, Controller

SPEED_UP_LOOKAHEAD_S = 1.0
"""How long (s) a command that speeds the bus up must keep its plans before a stop could be
ordered (no chatter; :class:`~sse_cosim.control.speed.SafePolicy`)."""


@dataclass(frozen=True)
class BusDynamics:
    """Acceleration, decelerations (m/s^2), reaction time and step length (s) of the bus."""

    accel: float
    decel: float
    emergency_decel: float
    reaction_time: float
    step: float

    @classmethod
    def of(cls, bus: AutomatedVehicle, controller: Controller, step_length: float) -> BusDynamics:
        return cls(bus.accel_mps2, bus.comfortable_decel_mps2, bus.emergency_decel_mps2,
                   controller.reaction_time_s, step_length)

    def next_speed(self, speed: float, command: float) -> float:
        """The speed after one step under ``command`` (m/s)."""
        return max(0.0, min(command, speed + self.accel * self.step),
                   speed - self.decel * self.step)

    def advance(self, position: float, speed: float, command: float) -> tuple[float, float]:
        """``(position, speed)`` after one step under ``command`` (SUMO's Euler update)."""
        new_speed = self.next_speed(speed, command)
        return position + new_speed * self.step, new_speed

    def stopping_distance(self, speed: float) -> float:
        """Distance (m) a comfortable stop ordered now needs: during the reaction time the bus
        may still follow an earlier command that speeds it up, then one step, then braking."""
        r = self.reaction_time
        top = speed + self.accel * r
        return speed * r + 0.5 * self.accel * r * r + top * self.step + top * top / (
            2.0 * self.decel)

    def lookahead_steps(self, command: float, speed: float) -> int:
        """How many steps ``command`` is held before a stop could be ordered: none for a stop
        (the stop itself, ordered now), one for a command that holds or slows the bus, and
        :data:`SPEED_UP_LOOKAHEAD_S` for one that speeds it up."""
        if command == 0.0:
            return 0
        return 1 if command <= speed else max(1, round(SPEED_UP_LOOKAHEAD_S / self.step))

    def lookahead_distance(self, speed: float, top: float) -> float:
        """How far (m) the bus may drive, from ``speed`` now, before a stop could be ordered
        under any command up to ``top`` (its :meth:`lookahead_steps`, at the faster of the
        two: a held command moves the speed toward it)."""
        return max(self.lookahead_steps(top, speed), 1) * self.step * max(speed, top)

    def stopping_time(self, speed: float) -> float:
        """Time (s) until a comfortable stop ordered now has the bus standing (the same worst
        case as :meth:`stopping_distance`)."""
        return self.reaction_time + self.step + (speed + self.accel * self.reaction_time) / (
            self.decel)

    def pass_time(self, distance: float, speed: float, command: float) -> float:
        """Time (s) to advance ``distance`` m holding ``command`` when the command acts only
        after the reaction time, during which the bus may still follow an earlier command
        that brakes it, at most at its emergency deceleration (the least progress)."""
        braked, slowest = self._reaction_brake(speed)
        if braked >= distance:
            brake = self.emergency_decel
            return (speed - math.sqrt(speed * speed - 2.0 * brake * distance)) / brake
        return self.reaction_time + self.travel_time(distance - braked, slowest, command)

    def pass_profile(self, elapsed: float, speed: float, command: float) -> tuple[float, float]:
        """``(distance, speed)`` (m, m/s) the worst case of :meth:`pass_time` has reached
        ``elapsed`` s after ``command`` was given at ``speed``: braking at the emergency
        deceleration through the reaction time, one step more, then the ramp to the command.
        A bus no later and no slower than this (same command or faster) advances every
        distance no later than :meth:`pass_time` says."""
        r, brake = self.reaction_time, self.emergency_decel
        if elapsed <= r:
            braking = min(elapsed, speed / brake)
            return speed * braking - 0.5 * brake * braking * braking, max(
                0.0, speed - brake * elapsed)
        braked, slowest = self._reaction_brake(speed)
        ramping = elapsed - r - self.step
        if ramping <= 0.0:
            return braked, slowest
        rate, ramp_time = self._ramp(slowest, command)
        if ramping <= ramp_time:
            return braked + slowest * ramping + 0.5 * rate * ramping * ramping, (
                slowest + rate * ramping)
        return braked + (slowest + command) * 0.5 * ramp_time + command * (
            ramping - ramp_time), command

    def travel_time(self, distance: float, speed: float, command: float) -> float:
        """Time (s) to advance ``distance`` m from ``speed`` while holding ``command``.

        The speed ramps to the command (at ``accel`` or ``decel``), then stays; one step is
        added for the command to act. Infinite when the bus would stop first.
        """
        if distance <= 0.0:
            return 0.0
        rate, ramp_time = self._ramp(speed, command)
        ramp_distance = (speed + command) * 0.5 * ramp_time
        if ramp_distance >= distance:
            # reached during the ramp: distance = speed t + rate t^2 / 2
            disc = speed * speed + 2.0 * rate * distance
            if disc < 0.0:
                return math.inf
            return self.step + (math.sqrt(disc) - speed) / rate
        if command <= 0.0:
            return math.inf
        return self.step + ramp_time + (distance - ramp_distance) / command

    def _reaction_brake(self, speed: float) -> tuple[float, float]:
        """``(distance, speed)`` (m, m/s) after the reaction time braking from ``speed`` at the
        emergency deceleration (the least progress an earlier command allows)."""
        slowest = max(0.0, speed - self.emergency_decel * self.reaction_time)
        return (speed * speed - slowest * slowest) / (2.0 * self.emergency_decel), slowest

    def _ramp(self, speed: float, command: float) -> tuple[float, float]:
        """``(rate, time)`` (m/s^2, s) of the ramp from ``speed`` to ``command``: up at
        ``accel``, down at ``decel``."""
        rate = self.accel if command >= speed else -self.decel
        return rate, (command - speed) / rate if rate else 0.0

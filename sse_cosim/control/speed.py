"""Speed levels from the situational picture: two policies (``controller.policy``).

The paper (Section IV) lists nominal (100 %), cautious "30 %", slow "50 %" and very slow
"80 %" of the nominal speed. Read as *fractions* the levels would speed up as the danger
grows, so we read them as *reductions*: cautious 0.7, slow 0.5 and very slow 0.2 of nominal
(configurable; ``docs/controller.md`` discusses the other reading). Both policies use them;
``stop`` (a comfortable stop) and ``emergency`` (a stop at the emergency deceleration) command
zero. The safe policy adds ``creep``: when even very slow keeps no plan, the fastest slower
speed that does (a bus beside hidden ground moves on at walking pace instead of lurching
between very slow and a stop).

``safe`` (the default, :class:`SafePolicy`): the fastest level from which the bus, in every
conflict zone ahead, either can still stop before the zone, or will be standing before any
pedestrian can reach it, or will have cleared it before any pedestrian can reach it. The
guarantee and its assumptions: ``docs/controller.md``.

``paper`` (:func:`paper_level`): the paper's rules, most severe first:

1. a pedestrian region in the swept path within the stopping distance: emergency brake;
2. a pedestrian region within ``path_margin_m`` of the path ahead: very slow;
3. the crossing ahead, with a pedestrian region near it or with hidden walkable area near
   it that may hold an undetected pedestrian: slow;
4. such hidden area in the bus's own view while the crossing is farther off: cautious;
5. otherwise nominal.

"The crossing" is the nearest crossing on the route that the bus has not cleared
(``SceneContext.crossing_at``); "near the crossing" is a reachability radius
(``SceneContext.reach_radius``): a hidden place matters only if a pedestrian starting there
could reach that crossing before the bus, at its nominal speed, has cleared it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from enum import IntEnum

from sse_cosim.control.kinematics import BusDynamics
from sse_cosim.control.picture import Picture, SceneContext, ZoneOutlook
from sse_cosim.scenario.model import Controller

STANDING_MPS = 1e-3  # below this the bus counts as standing
KEPT_TOLERANCE = 1e-6  # m and m/s: a bus this close to a pass's worst case still keeps it


class SpeedLevel(IntEnum):
    """Ordered by severity."""

    NOMINAL = 0
    CAUTIOUS = 1
    SLOW = 2
    VERY_SLOW = 3
    CREEP = 4  # safe policy: a speed below very slow, chosen per step
    STOP = 5
    EMERGENCY = 6

    @property
    def label(self) -> str:
        return self.name.lower().replace("_", " ")


@dataclass(frozen=True)
class Decision:
    """A policy's answer for one step: the level and the speed it commands (m/s)."""

    level: SpeedLevel
    command_mps: float


def level_speed(level: SpeedLevel, nominal_mps: float, config: Controller) -> float:
    """Commanded speed (m/s) of a level; a stop and an emergency brake command zero. A creep
    has no fixed speed (:meth:`SafePolicy.decide` chooses it): its ceiling, very slow."""
    factors = {
        SpeedLevel.NOMINAL: 1.0,
        SpeedLevel.CAUTIOUS: config.cautious_factor,
        SpeedLevel.SLOW: config.slow_factor,
        SpeedLevel.VERY_SLOW: config.very_slow_factor,
        SpeedLevel.CREEP: config.very_slow_factor,
        SpeedLevel.STOP: 0.0,
        SpeedLevel.EMERGENCY: 0.0,
    }
    return nominal_mps * factors[level]


def fallback_floor(inconsistent: bool, config: Controller) -> SpeedLevel:
    """The least severe level allowed: ``config.inconsistent_level`` while the picture is
    inconsistent, else nominal.

    A flagged source means some node broke its bounds: before the flag (the detection delay)
    the fused set may have missed the pedestrian, and after it the picture rests on the
    assumption of a single fault. The floor (default slow, docs/faults.md) covers that.
    """
    if not inconsistent:
        return SpeedLevel.NOMINAL
    return SpeedLevel[config.inconsistent_level.upper().replace(" ", "_")]


def paper_level(picture: Picture, config: Controller, floor: SpeedLevel) -> SpeedLevel:
    """The level the paper's rules (module docstring) give for ``picture``, at least
    ``floor``."""
    if picture.pedestrian_in_stopping_distance:
        level = SpeedLevel.EMERGENCY
    elif picture.pedestrian_near_path:
        level = SpeedLevel.VERY_SLOW
    else:
        hidden_near_crossing = picture.unresolved_occluded_m2 > config.occlusion_threshold_m2
        if picture.crossing_ahead and (picture.pedestrian_near_crossing or hidden_near_crossing):
            level = SpeedLevel.SLOW
        elif hidden_near_crossing:
            level = SpeedLevel.CAUTIOUS
        else:
            level = SpeedLevel.NOMINAL
    return max(level, floor)


class PaperPolicy:
    """The paper's rules (:func:`paper_level`); no state."""

    def __init__(self, nominal_mps: float, config: Controller) -> None:
        self.nominal = nominal_mps
        self.config = config

    def decide(self, picture: Picture, floor: SpeedLevel = SpeedLevel.NOMINAL) -> Decision:
        level = paper_level(picture, self.config, floor)
        return Decision(level, min(level_speed(level, self.nominal, self.config),
                                   picture.limit_mps))


def make_policy(context: SceneContext) -> SafePolicy | PaperPolicy:
    """The policy ``context.config.policy`` names, for the bus of ``context``."""
    if context.config.policy == "paper":
        return PaperPolicy(context.bus.nominal_speed_mps, context.config)
    return SafePolicy(context.dynamics, context.bus.nominal_speed_mps, context.config)


@dataclass(frozen=True)
class Commitment:
    """A pass proven at ``proven_s`` (the policy's clock), the front then at ``front_m`` (SUMO's
    distance along the route) and the bus at ``speed_mps``, holding ``command`` (m, m/s)."""

    command: float
    proven_s: float
    front_m: float
    speed_mps: float

    def kept(self, dynamics: BusDynamics, now_s: float, front_m: float, speed: float) -> bool:
        """Whether the bus, its front at ``front_m`` at ``speed`` now, is no later and no
        slower than the worst case the pass was proven on (:meth:`BusDynamics.pass_profile`):
        then, holding this command or a faster one, it clears the zone no later than proven.
        A bus held back by the world (SUMO's right of way, a leader) is not."""
        reached, least = dynamics.pass_profile(now_s - self.proven_s, self.speed_mps,
                                               self.command)
        return (front_m - self.front_m >= reached - KEPT_TOLERANCE
                and speed >= least - KEPT_TOLERANCE)


@dataclass(frozen=True)
class Plan:
    """Why a command is safe for one zone: ``stop`` before it, ``stand`` still before anyone
    can reach it, or ``pass`` it before anyone can (which commits the bus to its speed:
    ``commitment``)."""

    zone: int
    kind: str
    command: float
    commitment: Commitment | None = None


class SafePolicy:
    """The fastest level that keeps a safe plan for every conflict zone ahead.

    For a candidate command the bus is predicted one step ahead (the command acts over the
    next step; :data:`~sse_cosim.control.kinematics.SPEED_UP_LOOKAHEAD_S` for a command that
    speeds the bus up, so that it does not accelerate only to brake at the next step; not at
    all for a stop, which is the comfortable stop ordered now; ``BusDynamics.lookahead_steps``);
    from there, per zone, one of three plans must hold:

    - **stop** before the zone: the comfortable stopping distance (reaction time included)
      plus ``stopping_margin_m`` fits before it;
    - **stand**: a comfortable stop has the bus standing, one step of margin included, before
      the earliest arrival of any pedestrian in the zone (the bus is stopped before any
      contact, wherever it stands), and, if it stands inside the zone, it gives way to every
      pedestrian in view (:meth:`_gives_way`);
    - **pass**: holding the command, the rear clears the zone a step before that arrival.

    The candidates are the levels, fastest first, then creep speeds below very slow in steps
    of one step's acceleration (``accel * dt``), then a stop.

    A traffic light of the route that tells traffic to stop (red, yellow or red-yellow) binds
    every command while the bus can still stop before its stop line: the command's
    comfortable stop must end before the line (:meth:`_stops_for_light`), so the controller
    never commands more than it can stop for at its own red, and a stop ordered now always
    does. Where the bus no longer can (yellow too close), it drives on, as SUMO's vehicles do.

    A pass commits the bus: while it has not cleared the zone, any command at least as fast
    as the one the pass was proven with stays admissible, since the pedestrians that could
    reach the zone in time were all inside the sets when it was proven -- as long as the bus
    keeps to the pass's worst case (:meth:`Commitment.kept`). SUMO may hold the bus below
    its command (a car's right of way at a junction, a leader); a pass it holds back is
    proven again from where the bus is, or given up. ``decide`` is called once a step (its
    clock). If no level and no
    comfortable stop keeps a plan, the bus brakes at the emergency deceleration. Under the
    assumptions of docs/controller.md, with commands acting over the next step as in SUMO,
    the plans proven at one step stay valid at the next (the comfortable stop of the previous
    step is still a stop or a stand), so the emergency brake is never needed; it remains as
    the answer to a broken assumption (and to commands delayed by the whole reaction time,
    which the one-step prediction does not model: docs/controller.md).
    """

    def __init__(self, dynamics: BusDynamics, nominal_mps: float, config: Controller) -> None:
        self.dynamics = dynamics
        self.nominal = nominal_mps
        self.config = config
        self.committed: dict[int, Commitment] = {}  # zone -> the pass it is committed to
        self.now_s = -dynamics.step  # the policy's clock: the time of the latest decide

    def decide(self, picture: Picture, floor: SpeedLevel = SpeedLevel.NOMINAL) -> Decision:
        """The level and command for this step (updates the pass commitment)."""
        self.now_s += self.dynamics.step
        # the fastest level the floor allows; failing that, the slowest faster one (only a
        # committed pass is left: hold it, the floor would break it)
        allowed = [level for level in SpeedLevel if floor <= level < SpeedLevel.EMERGENCY]
        faster = [level for level in reversed(SpeedLevel) if level < floor]
        for level in (*allowed, *faster):
            for command in self._commands(level):
                plans = self._plans(picture, command)
                if plans is not None:
                    self.committed = {p.zone: p.commitment for p in plans
                                      if p.commitment is not None}
                    return Decision(level, min(command, picture.limit_mps))
        self.committed = {}
        return Decision(SpeedLevel.EMERGENCY, 0.0)

    def _commands(self, level: SpeedLevel) -> list[float]:
        """The commands a level stands for: one, or for a creep the speeds below very slow in
        steps of ``accel * dt``, fastest first."""
        ceiling = level_speed(level, self.nominal, self.config)
        if level is not SpeedLevel.CREEP:
            return [ceiling]
        quantum = self.dynamics.accel * self.dynamics.step
        return [ceiling - k * quantum for k in range(1, int(ceiling / quantum) + 1)
                if ceiling - k * quantum >= quantum - 1e-9]

    def _plans(self, picture: Picture, command: float) -> list[Plan] | None:
        """One plan per zone if ``command`` keeps one for every zone, else None.

        The plans form one manoeuvre: hold the command through the nearest zones that it
        passes, then stop (comfortably). So once a zone is not passed, every zone beyond it
        needs a stop or a stand too, proven from where and when the passes end.
        """
        if command == 0.0 and picture.speed_mps < STANDING_MPS:
            return []  # standing still touches nobody
        dyn = self.dynamics
        # a stop command is the comfortable stop itself, ordered now (its reaction time and
        # step are in the stopping distance); any other command is held a step (a speed-up:
        # the look-ahead) before a stop could be ordered
        steps = dyn.lookahead_steps(command, picture.speed_mps)
        position, speed = 0.0, picture.speed_mps
        for _ in range(steps):
            position, speed = dyn.advance(position, speed, command)
        start = _StopStart(position, speed, steps * dyn.step)
        if not self._stops_for_light(picture, start):
            return None
        plans, passing = [], True
        for zone in picture.zones:
            plan = self._stop_or_stand(zone, command, start, picture.speed_mps, picture.zones)
            if plan is None and passing:
                plan = self._pass(zone, picture, command)
                if plan is not None:  # a later stop starts once this zone is cleared
                    # holding the command, the speed moves from the predicted one toward it
                    start = _StopStart(zone.to_clear_m, max(speed, command), dyn.pass_time(
                        zone.to_clear_m, picture.speed_mps, min(command, zone.limit_mps)))
            if plan is None:
                return None
            passing = passing and plan.kind == "pass"
            plans.append(plan)
        return plans

    def _stops_for_light(self, picture: Picture, start: _StopStart) -> bool:
        """Whether a comfortable stop ordered at ``start`` ends before the route's stop line
        ahead while its light tells traffic to stop (``picture.stop_line_m``) -- wherever the
        bus can still stop before it from where it is now; a bus that no longer can (the
        light turned yellow too close) drives on, as SUMO's vehicles do."""
        line = picture.stop_line_m
        if line is None:
            return True
        dyn = self.dynamics
        if dyn.stopping_distance(picture.speed_mps) > line + KEPT_TOLERANCE:
            return True
        return start.position + dyn.stopping_distance(start.speed) <= line + KEPT_TOLERANCE

    def _stop_or_stand(self, zone: ZoneOutlook, command: float, start: _StopStart,
                       speed_now: float, zones: Sequence[ZoneOutlook]) -> Plan | None:
        """A comfortable stop ordered at ``start`` ends before the zone, or has the bus
        standing (one step of margin) before anyone can arrive there, without driving into
        the zone in front of a pedestrian in view (:meth:`_gives_way`; ``zones``: every zone
        ahead)."""
        dyn = self.dynamics
        stop_end = start.position + dyn.stopping_distance(start.speed)
        if stop_end + self.config.stopping_margin_m <= zone.to_start_m:
            return Plan(zone.index, "stop", command)
        if start.time + dyn.stopping_time(start.speed) + dyn.step > zone.arrival_s:
            return None
        if stop_end <= zone.to_start_m or self._gives_way(zone, zones, command, speed_now):
            return Plan(zone.index, "stand", command)
        return None

    def _gives_way(self, zone: ZoneOutlook, zones: Sequence[ZoneOutlook], command: float,
                   speed_now: float) -> bool:
        """Whether a stand that ends inside the zone leaves the way to every pedestrian in
        view: the command stops the bus now (nothing better is left), or the front is already
        in the zone, or holding the command the rear clears the zone a step before any
        pedestrian in view can arrive.

        A command that speeds the bus up must do the same for every zone ahead that the
        front enters before the rear has cleared this one (:func:`_entered_while_clearing`; a
        junction's walking areas overlap along the route): a zone the bus cannot clear before
        its pedestrian in view would stop it there, inside this one. Without this a standing
        bus moved off, found a step later that it could neither clear the next zone nor stop
        before it, stopped, and moved off again (a lurch every 0.1-0.3 s, found by the
        falsifier on the town: tests/cosim/test_town_lurch.py). A command that holds or slows
        the bus is judged on this zone alone (requiring the chain whenever the bus could
        still stop before the zone made scenarios/town.toml's bus creep: 70.6 s to the end of
        its route instead of 40.6 s).

        A stand keeps the bus from touching anyone while it moves, but a bus standing on a
        crossing still blocks it, and SUMO's pedestrians walk into it (people do not). So the
        bus does not creep onto a crossing that someone it sees may be about to use; ground
        that stays hidden still lets it creep (docs/controller.md, "Giving way").
        """
        if command == 0.0 or zone.to_start_m <= 0.0:
            return True
        dyn = self.dynamics
        entered = _entered_while_clearing(zone, zones) if command > speed_now else [zone]
        return all(dyn.pass_time(z.to_clear_m, speed_now, min(command, z.limit_mps)) + dyn.step
                   < z.in_view_arrival_s for z in entered)

    def _pass(self, zone: ZoneOutlook, picture: Picture, command: float) -> Plan | None:
        """Holding the command, the rear clears the zone a step before anyone can arrive (or a
        pass committed earlier still holds: this command is as fast, and the bus has kept to
        the pass). The bus holds the command within the speed limits until it has cleared
        the zone (``zone.limit_mps``): the pass is proven, and committed, at the held speed."""
        dyn, speed_now = self.dynamics, picture.speed_mps
        held = min(command, zone.limit_mps)
        if dyn.pass_time(zone.to_clear_m, speed_now, held) + dyn.step < zone.arrival_s:
            return Plan(zone.index, "pass", command,
                        Commitment(held, self.now_s, picture.front_drive_m, speed_now))
        committed = self.committed.get(zone.index)
        if committed is not None and held >= committed.command and committed.kept(
                dyn, self.now_s, picture.front_drive_m, speed_now):
            return Plan(zone.index, "pass", committed.command, committed)
        return None


def _entered_while_clearing(zone: ZoneOutlook,
                            zones: Sequence[ZoneOutlook]) -> list[ZoneOutlook]:
    """``zone`` and every zone ahead that the front enters before the rear has cleared all
    of them (zones that overlap along the route, as a junction's walking areas do), but those
    the front is already in."""
    reach, out = zone.to_clear_m, [zone]
    for other in sorted(zones, key=lambda z: z.to_start_m):
        if other is not zone and 0.0 < other.to_start_m < reach:
            out.append(other)
            reach = max(reach, other.to_clear_m)
    return out


@dataclass(frozen=True)
class _StopStart:
    """Where (m along the route from the front now), at what speed at most (m/s) and how late
    at most (s from now) a comfortable stop may be ordered."""

    position: float
    speed: float
    time: float

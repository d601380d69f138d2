"""What the falsifier drives down: one margin per run, read from its ``summary.json``.

An objective is a small object with a name, a unit and two readings of a summary: its
``margin`` (lower is worse; the search minimises it) and whether the run ``failed`` (the
guarantee or the target it stands for is broken). An objective that reads a margin the
summary holds only on demand (:mod:`sse_cosim.reporting.margins`) names it in ``margins``, and
the search asks its runs for it. A new objective is one class added to :data:`OBJECTIVES`.

Whatever the objective, a run with a collision or a containment violation is a failure the
report lists (:func:`broken`): the search for one margin still reports every broken promise
it meets. A collision is contact with a moving vehicle: the claim (docs/controller.md) is that
the vehicle stands before any contact. A pedestrian who walks into a standing vehicle (SUMO's
walkers do; people do not) is a **walk-in**: listed beside the broken promises, not one of them.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol

from sse_cosim.reporting import margins as run_margins
from sse_cosim.reporting.recorder import collisions, first_collision_t, walk_ins
from sse_cosim.world.checks import CHECKS

STANDSTILL_TARGET_S = 3.0
"""The safety campaign's liveness target: the bus stands at most this long on a clear path."""

OPEN_DISTANCE_M = 100.0
"""A least distance beyond this (or none: no pedestrian in the scene while the bus moved)
counts as this far."""

OPEN_TTC_S = 10.0
"""A time to collision longer than this (or none: never on a collision course) counts as this
long: a margin the search can no longer tell apart from safe."""


OPEN_DEPTH_M = 5.0
"""A containment depth beyond this (or none: no set held a pedestrian) counts as this deep."""


class Objective(Protocol):
    name: ClassVar[str]
    unit: ClassVar[str]
    help: ClassVar[str]
    margins: ClassVar[tuple[str, ...]]  # the on-demand margins its runs must report

    def margin(self, summary: Mapping[str, Any]) -> float:
        """How far the run stayed from failing (lower is worse; <= 0 at a failure)."""

    def failed(self, summary: Mapping[str, Any]) -> bool:
        """Whether the run broke what this objective stands for."""

    def failed_at(self, summary: Mapping[str, Any]) -> float | None:
        """When the failure began (s), if the summary tells; None: not known."""


def _emergency_s(summary: Mapping[str, Any]) -> float:
    """Time the bus spent braking in emergency (s): its level share times its travel."""
    share = summary["level_share"].get("emergency", 0.0)
    return share * summary["steps"] * _step_s(summary)


def _step_s(summary: Mapping[str, Any]) -> float:
    return summary["travel_time_s"] / max(summary["steps"], 1)


class _FailsAtCollision:
    """An objective whose failure is a collision (contact with a moving vehicle), from the
    first one on."""

    def failed(self, summary: Mapping[str, Any]) -> bool:
        return collisions(summary) > 0

    def failed_at(self, summary: Mapping[str, Any]) -> float | None:
        return first_collision_t(summary)


@dataclass(frozen=True)
class LeastDistance(_FailsAtCollision):
    """The least distance between the bus, while it moves, and any pedestrian (m), capped at
    :data:`OPEN_DISTANCE_M`; 0 at a collision
    (:class:`~sse_cosim.reporting.margins.MovingDistance` measures it). The claim is that the
    bus stands before any contact, so a pedestrian walking up to the standing bus (a walk-in,
    listed apart) does not bring the margin down: the search closes in on contact while the
    bus moves, not on walk-ins (the town's second search, on the distance at every step,
    spent a quarter of CMA-ES's runs on them)."""

    name: ClassVar[str] = "distance"
    unit: ClassVar[str] = "m"
    help: ClassVar[str] = ("least distance between the moving bus and a pedestrian (m); "
                           "fails at a collision")
    margins: ClassVar[tuple[str, ...]] = (run_margins.MovingDistance.name,)

    def margin(self, summary: Mapping[str, Any]) -> float:
        if collisions(summary):
            return 0.0
        least = summary["margins"][run_margins.MovingDistance.name]["least_m"]
        return OPEN_DISTANCE_M if least is None else min(float(least), OPEN_DISTANCE_M)


@dataclass(frozen=True)
class EmergencyBrake:
    """The least distance to the moving bus (as ``distance``) while it never brakes in
    emergency; once it does, minus the time it braked (s): the search first closes in, then
    prolongs the braking."""

    name: ClassVar[str] = "emergency"
    unit: ClassVar[str] = "m, or -s braking"
    help: ClassVar[str] = ("least distance to the moving bus until an emergency brake; then "
                           "minus its duration; fails at an emergency brake or a collision")
    margins: ClassVar[tuple[str, ...]] = LeastDistance.margins

    def margin(self, summary: Mapping[str, Any]) -> float:
        braking = _emergency_s(summary)
        if braking > 0:
            return -braking
        return LeastDistance().margin(summary)

    def failed(self, summary: Mapping[str, Any]) -> bool:
        return _emergency_s(summary) > 0 or collisions(summary) > 0

    def failed_at(self, summary: Mapping[str, Any]) -> float | None:
        return None  # the summary gives the braking's length, not its start


@dataclass(frozen=True)
class Standstill:
    """Liveness, from the truth: the target (3 s) less the longest time a vehicle was held
    (told to creep, stop or brake) while no pedestrian in the scene could have reached a zone
    ahead before it cleared them (``longest_needless_hold_s``, s); a route never finished
    fails."""

    name: ClassVar[str] = "standstill"
    unit: ClassVar[str] = "s"
    help: ClassVar[str] = (f"{STANDSTILL_TARGET_S:g} s less the longest hold while the truth "
                           "left the path clear; fails beyond it or on an unfinished route")
    margins: ClassVar[tuple[str, ...]] = ()

    def margin(self, summary: Mapping[str, Any]) -> float:
        if not summary["route_completed"]:
            return -float(summary["travel_time_s"])
        return STANDSTILL_TARGET_S - float(summary["longest_needless_hold_s"])

    def failed(self, summary: Mapping[str, Any]) -> bool:
        return self.margin(summary) < 0

    def failed_at(self, summary: Mapping[str, Any]) -> float | None:
        return None


@dataclass(frozen=True)
class CrossingBlocked:
    """Liveness at crossings: the target (3 s, the standstill's) less the longest a vehicle
    stood on a crossing while a pedestrian waited at it, at its kerb or on it (s;
    :class:`~sse_cosim.reporting.margins.CrossingBlocked` measures it). The ``standstill``
    objective cannot see a bus that stands on a crossing and waits for the pedestrian it
    holds up, for its path is never clear (the town's and the junction's standoffs,
    results/falsify.md)."""

    name: ClassVar[str] = "blocking"
    unit: ClassVar[str] = "s"
    help: ClassVar[str] = (f"{STANDSTILL_TARGET_S:g} s less the longest a vehicle stood on a "
                           "crossing while a pedestrian waited at it (at its kerb or on it); "
                           "fails beyond it")
    margins: ClassVar[tuple[str, ...]] = (run_margins.CrossingBlocked.name,)

    def margin(self, summary: Mapping[str, Any]) -> float:
        longest = summary["margins"][run_margins.CrossingBlocked.name]["longest_s"]
        return STANDSTILL_TARGET_S - float(longest)

    def failed(self, summary: Mapping[str, Any]) -> bool:
        return self.margin(summary) < 0

    def failed_at(self, summary: Mapping[str, Any]) -> float | None:
        if not self.failed(summary):
            return None
        return summary["margins"][run_margins.CrossingBlocked.name]["t"] + STANDSTILL_TARGET_S


@dataclass(frozen=True)
class TimeToCollision(_FailsAtCollision):
    """The least time to collision of the run (s), capped at :data:`OPEN_TTC_S`; 0 at a
    collision (:class:`~sse_cosim.reporting.margins.TimeToCollision` measures it)."""

    name: ClassVar[str] = "ttc"
    unit: ClassVar[str] = "s"
    help: ClassVar[str] = (f"least time to collision at constant velocities (s, at most "
                           f"{OPEN_TTC_S:g}); fails at a collision")
    margins: ClassVar[tuple[str, ...]] = (run_margins.TimeToCollision.name,)

    def margin(self, summary: Mapping[str, Any]) -> float:
        if collisions(summary):
            return 0.0
        least = summary["margins"][self.margins[0]]["least_s"]
        return OPEN_TTC_S if least is None else min(float(least), OPEN_TTC_S)


@dataclass(frozen=True)
class MovingTimeToCollision(TimeToCollision):
    """The least time to collision while the bus moves (s), capped at :data:`OPEN_TTC_S`; 0 at
    a collision (:class:`~sse_cosim.reporting.margins.MovingTimeToCollision` measures it).
    Where pedestrians walk along the sidewalk beside the moving bus, the moving distance is
    the same sidewalk gap in most runs (S1-S3, the crowd: results/falsify.md) and tells the
    search nothing; a pedestrian walking beside the bus is on no collision course, so this
    margin draws the search to those who head into the moving bus's way, and not to those
    who head into the standing bus (walk-ins), as ``ttc`` does."""

    name: ClassVar[str] = "moving_ttc"
    help: ClassVar[str] = (f"least time to collision of the moving bus at constant velocities "
                           f"(s, at most {OPEN_TTC_S:g}); fails at a collision")
    margins: ClassVar[tuple[str, ...]] = (run_margins.MovingTimeToCollision.name,)


@dataclass(frozen=True)
class ContainmentDepth:
    """How deep the truth lies in the sets and refined regions written for it (m, the least
    of both; :class:`~sse_cosim.reporting.margins.ContainmentDepth` measures it); fails at a
    containment violation (the recorder's own check). Labelled runs only (the search refuses
    an anonymous scenario before it starts); a run whose sets and regions never held a
    pedestrian made no claim to miss and counts as :data:`OPEN_DEPTH_M`."""

    name: ClassVar[str] = "depth"
    unit: ClassVar[str] = "m"
    help: ClassVar[str] = ("least depth of a pedestrian's true position inside its sets and "
                           "refined regions (m); fails at a containment violation")
    margins: ClassVar[tuple[str, ...]] = (run_margins.ContainmentDepth.name,)

    def margin(self, summary: Mapping[str, Any]) -> float:
        found = [least for least in self.depths(summary) if least is not None]
        return min(float(min(found, default=OPEN_DEPTH_M)), OPEN_DEPTH_M)

    def depths(self, summary: Mapping[str, Any]) -> list[float | None]:
        """The least depths (m; None: nothing held a pedestrian) the margin is the least of."""
        depth = summary["margins"][run_margins.ContainmentDepth.name]
        return [depth[part]["least_m"] for part in ("sets", "regions")]

    def failed(self, summary: Mapping[str, Any]) -> bool:
        return bool(summary["containment_violations"])

    def failed_at(self, summary: Mapping[str, Any]) -> float | None:
        violations = summary["violations"]
        return violations[0]["t"] if violations else None


@dataclass(frozen=True)
class AccountedDepth(ContainmentDepth):
    """How deep every pedestrian lies in the area the controller accounts for pedestrians,
    its refined regions and the unobserved area together (m;
    :class:`~sse_cosim.reporting.margins.AccountedDepth`): the margin of a pedestrian
    nobody has detected yet. Fails at a containment violation, as ``depth``. It reads no
    region's name: anonymous runs too."""

    name: ClassVar[str] = "accounted"
    help: ClassVar[str] = ("least depth of a pedestrian inside the refined regions and the "
                           "unobserved area together (m), within the window where they are "
                           "kept; fails at a containment violation")
    margins: ClassVar[tuple[str, ...]] = (run_margins.AccountedDepth.name,)

    def depths(self, summary: Mapping[str, Any]) -> list[float | None]:
        return [summary["margins"][run_margins.AccountedDepth.name]["least_m"]]


OBJECTIVES: dict[str, Objective] = {o.name: o for o in (LeastDistance(), EmergencyBrake(),
                                                         Standstill(), CrossingBlocked(),
                                                         TimeToCollision(),
                                                         MovingTimeToCollision(),
                                                         ContainmentDepth(), AccountedDepth())}


def first_break_t(summary: Mapping[str, Any]) -> float | None:
    """When the simulated world first broke an assumption the run counted (s): the first break
    under any checked assumption's summary key (a walker off the model, ``assumption_breaks``;
    off the walkable ground, ``ground_breaks``; ... :mod:`sse_cosim.world.checks`)."""
    times = [entry["t"] for key in (check.summary_key for check in CHECKS.values())
             for entry in (summary.get(key) or {}).get("first", [])[:1]]
    return min(times, default=None)


def broken(summary: Mapping[str, Any]) -> list[str]:
    """The guarantee's broken promises in a run, within its assumptions: collisions and
    containment violations that began before the world first broke an assumption (after it,
    the estimator's sets owe nothing to a truth outside its model). Walk-ins are listed
    after them, whenever they came: no assumption excuses them, and no promise covers them."""
    since = first_break_t(summary)

    def before(t: float | None) -> bool:
        return since is None or (t is not None and t < since)

    out = []
    if collisions(summary) and before(first_collision_t(summary)):
        out.append(f"{collisions(summary)} collision(s)")
    violations = summary["violations"]
    if summary["containment_violations"] and before(violations[0]["t"] if violations else None):
        out.append(f"{summary['containment_violations']} containment violation(s)")
    if walk_ins(summary):
        out.append(f"{walk_ins(summary)} {WALK_IN}")
    return out


WALK_IN = "walk-in(s) into the standing bus"
"""How :func:`broken` names a run's walk-ins (after their count)."""


def promises_broken(listed: str) -> bool:
    """Whether ``listed`` (:func:`broken`'s entries joined by ``"; "``, as the ledger holds
    them) names a broken promise, not only walk-ins."""
    return any(entry and not entry.endswith(WALK_IN) for entry in listed.split("; "))

"""Margins a run reports when asked: figures of how near it came to failing, beyond the
summary's own.

A margin watches every step beside the recorder and, at the end, gives one JSON value from
what it saw or from what the recorder kept; the run writes it under ``summary.json``'s
``margins`` (only for the margins its task names: a run asked for none writes the summary it
always did). The falsifier's objectives name the margins they read. A new margin is one class
added to :data:`MARGINS`.

:class:`MovingDistance` is the least distance between a moving vehicle and a pedestrian:
the distance of the controller's claim (a vehicle stands before any contact).

:class:`TimeToCollision` is the classic surrogate safety measure: at every step, for every
automated vehicle and pedestrian, how long until they touch if both keep their velocity
(the vehicle along its heading at its speed; the pedestrian at SUMO's speed along the
direction SUMO walks it, :attr:`~sse_cosim.world.snapshot.PersonState.heading`: a sideways step
SUMO takes between the lanes of its walking areas does not turn it). Touching is the
recorder's collision: the pedestrian's centre within its body radius of the vehicle's
footprint, so a time of 0 is a collision.

:class:`MovingTimeToCollision` is the same time over the steps a vehicle moves only.

:class:`CrossingBlocked` measures liveness at crossings: how long a vehicle stood on a
crossing while a pedestrian waited at it, at its kerb or on it.

:class:`ContainmentDepth` grades the recorder's containment checks: how deep each pedestrian's
true position lies inside every position set and refined region written for it (the
distance to the set's boundary; negative: outside, a containment violation);
:class:`AccountedDepth` is its part that reads no set's name, for anonymous runs too.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from itertools import groupby
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

import numpy as np

if TYPE_CHECKING:  # annotations only: the CLI lists the margins without the pipeline
    from sse_cosim.pipeline.result import StepResult
    from sse_cosim.reporting.recorder import RunRecorder
    from sse_cosim.scenario.model import Scenario
    from sse_cosim.world.snapshot import PersonState


class Margin(Protocol):
    """Watches a run step by step; :meth:`value` (from what it saw, or what the run's
    recorder kept) is what ``summary.json`` gets."""

    name: ClassVar[str]
    help: ClassVar[str]
    labelled_only: ClassVar[bool]  # needs sets that name their pedestrian
    reads_regions: ClassVar[bool]  # needs the recorder to keep every step's regions

    def __call__(self, result: StepResult) -> None: ...

    def value(self, recorder: RunRecorder) -> dict[str, Any]: ...


def ray_box_entry(p: np.ndarray, w: np.ndarray, half: np.ndarray) -> np.ndarray:
    """First time ``tau >= 0`` at which ``p + w tau`` lies in the box ``|x_k| <= half_k``
    (0 if it starts inside; inf if never): the slab method.

    ``p``, ``w``, ``half``: shape (n, 2), one box per point. Returns shape (n,).
    """
    enter = np.zeros(len(p))
    leave = np.full(len(p), np.inf)
    for k in range(2):
        moving = w[:, k] != 0
        with np.errstate(divide="ignore", invalid="ignore"):
            t1 = np.where(moving, (-half[:, k] - p[:, k]) / w[:, k], -np.inf)
            t2 = np.where(moving, (half[:, k] - p[:, k]) / w[:, k], np.inf)
        still_outside = ~moving & (np.abs(p[:, k]) > half[:, k])
        enter = np.maximum(enter, np.where(still_outside, np.inf, np.minimum(t1, t2)))
        leave = np.minimum(leave, np.where(still_outside, -np.inf, np.maximum(t1, t2)))
    return np.where(enter <= leave, enter, np.inf)


def ray_disc_entry(p: np.ndarray, w: np.ndarray, centre: np.ndarray,
                   radius: np.ndarray) -> np.ndarray:
    """First time ``tau >= 0`` at which ``p + w tau`` lies within ``radius`` of ``centre``
    (0 if it starts there; inf if never).

    ``p``, ``w``: shape (n, 2); ``centre``: shape (2,); ``radius``: shape (n,).
    """
    d = p - centre
    a = _dot(w, w)
    b = _dot(d, w)
    c = _dot(d, d) - radius**2
    disc = b * b - a * c
    with np.errstate(divide="ignore", invalid="ignore"):
        root = (-b - np.sqrt(np.maximum(disc, 0.0))) / a
    hits = (a > 0) & (disc >= 0) & (root >= 0)
    return np.where(c <= 0, 0.0, np.where(hits, root, np.inf))


def _dot(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Row-wise dot products of shape (n, 2) arrays, shape (n,), in plain float operations
    (the same bits on every CPU, unlike ``einsum``)."""
    return u[:, 0] * v[:, 0] + u[:, 1] * v[:, 1]


def _in_frame(v: np.ndarray, forward: np.ndarray, left: np.ndarray) -> np.ndarray:
    """Vectors ``v`` (n, 2) in the frame of unit axes ``forward`` and ``left`` (2,), (n, 2)."""
    return np.stack([v[:, 0] * forward[0] + v[:, 1] * forward[1],
                     v[:, 0] * left[0] + v[:, 1] * left[1]], axis=1)


def time_to_contact(p: np.ndarray, w: np.ndarray, half: np.ndarray,
                    radius: np.ndarray) -> np.ndarray:
    """First time ``tau >= 0`` at which a point ``p + w tau`` comes within ``radius`` of the
    box ``|x_k| <= half_k`` (inf if never), exactly: the box grown by a disc is the union of
    the box grown along each axis and four discs on its corners.

    ``p``, ``w``: the point and its velocity in the box's frame, shape (n, 2); ``half``:
    shape (2,); ``radius``: shape (n,). Returns shape (n,).
    """
    along_x = np.stack([radius, np.zeros_like(radius)], axis=1)
    times = [ray_box_entry(p, w, half + along_x), ray_box_entry(p, w, half + along_x[:, ::-1])]
    corners = np.array([[sx * half[0], sy * half[1]] for sx in (-1, 1) for sy in (-1, 1)])
    times += [ray_disc_entry(p, w, corner, radius) for corner in corners]
    return np.min(times, axis=0)


@dataclass
class MovingDistance:
    """The least distance between an automated vehicle that moves and any pedestrian (m),
    with when and which vehicle: the recorder's distance (footprint to the pedestrian's
    centre) at the steps the vehicle moved, at
    :data:`~sse_cosim.reporting.recorder.STOPPED_SPEED_MPS` or faster.

    The claim of docs/controller.md is that a vehicle stands before any contact, so this is
    the distance the claim is about: a pedestrian who walks up to (or into) a standing vehicle
    does not bring it down. ``least_m`` is None where no pedestrian was in the scene while a
    vehicle moved.
    """

    name: ClassVar[str] = "moving_distance"
    help: ClassVar[str] = ("least distance between a moving automated vehicle (0.1 m/s or "
                           "faster) and a pedestrian (m)")
    labelled_only: ClassVar[bool] = False
    reads_regions: ClassVar[bool] = False

    scenario: Scenario

    def __call__(self, result: StepResult) -> None:
        """Nothing to watch: the recorder keeps every step's speed and distance."""

    def value(self, recorder: RunRecorder) -> dict[str, Any]:
        from sse_cosim.reporting.recorder import STOPPED_SPEED_MPS

        least = _Least()
        for row in recorder.rows:
            if row["distance_bus_pedestrian"] is not None and \
                    row["bus_speed"] >= STOPPED_SPEED_MPS:
                least.note(row["distance_bus_pedestrian"], t=row["t"], vehicle=row["vehicle"])
        return least.value()


@dataclass
class TimeToCollision:
    """The least time to collision over the run (s), with when and between whom it came.

    ``least_s`` is None when no automated vehicle and pedestrian were ever on a collision
    course (every step's time infinite).
    """

    name: ClassVar[str] = "time_to_collision"
    help: ClassVar[str] = ("least time until an automated vehicle and a pedestrian touch if both "
                           "keep their velocity (s); 0 at a collision")
    labelled_only: ClassVar[bool] = False
    reads_regions: ClassVar[bool] = False

    moving_only: ClassVar[bool] = False  # count only the steps a vehicle moves

    scenario: Scenario
    least_s: float = np.inf
    at: dict[str, Any] = field(default_factory=dict)  # t, vehicle, pedestrian of the least

    def __call__(self, result: StepResult) -> None:
        from sse_cosim.reporting.recorder import STOPPED_SPEED_MPS

        persons = result.snapshot.persons
        ids = sorted(persons)
        xy = np.array([persons[pid].position for pid in ids]).reshape(-1, 2)
        velocity = _walking_velocities([persons[pid] for pid in ids])
        radius = np.array([self.scenario.person_radius_m(pid) for pid in ids])
        for vehicle in result.vehicles if ids else ():
            state = result.snapshot.vehicles[vehicle]
            if self.moving_only and state.speed < STOPPED_SPEED_MPS:
                continue
            footprint = state.footprint
            forward, left = footprint.front.forward, footprint.front.left
            p = _in_frame(xy - footprint.center, forward, left)
            w = _in_frame(velocity - state.speed * forward, forward, left)
            tau = time_to_contact(p, w, 0.5 * np.array([footprint.length, footprint.width]),
                                  radius)
            k = int(np.argmin(tau))
            if tau[k] < self.least_s:
                self.least_s = float(tau[k])
                self.at = {"t": round(result.snapshot.time, 6), "vehicle": vehicle,
                           "pedestrian": ids[k]}

    def value(self, recorder: RunRecorder) -> dict[str, Any]:
        least = None if np.isinf(self.least_s) else self.least_s
        return {"least_s": least, **self.at}


@dataclass
class MovingTimeToCollision(TimeToCollision):
    """The least time to collision over the steps at which the automated vehicle moves (at
    :data:`~sse_cosim.reporting.recorder.STOPPED_SPEED_MPS` or faster), as
    :class:`MovingDistance` is the distance: a pedestrian heading into a standing vehicle
    does not bring it down. ``least_s`` is None when no pedestrian was ever on a collision
    course with a moving vehicle."""

    name: ClassVar[str] = "moving_time_to_collision"
    help: ClassVar[str] = ("least time until a moving automated vehicle (0.1 m/s or faster) and "
                           "a pedestrian touch if both keep their velocity (s)")
    moving_only: ClassVar[bool] = True


@dataclass
class ContainmentDepth:
    """The least depth of a pedestrian's true position in the sets and regions written for it
    (m; negative outside), with where it came: ``sets`` over every local and fused position
    set (``sets.jsonl.gz``), ``regions`` over every refined region (``regions.jsonl.gz``) at the
    steps its pedestrian stood inside the window where regions are kept (the recorder's
    claim: outside it, every walkable place counts as occupied), and ``accounted`` over the
    area where the controller accounts for pedestrians, each automated vehicle's refined
    regions and unobserved area together (the recorder's ``unaccounted`` check), for every
    pedestrian inside that window: an undetected pedestrian's margin.

    The sets are the recorder's own arrays and half-spaces (the depth is the least slack of
    :func:`~sse_cosim.reporting.recorder.zonotope_2d_halfspaces_reference`, exact for a set
    whose generators span the plane, as the jitter box makes every written set). Labelled
    runs only (an anonymous run's sets name tracks, not pedestrians). ``least_m`` is None
    where no set or region held a pedestrian.
    """

    name: ClassVar[str] = "containment_depth"
    help: ClassVar[str] = ("least depth of a pedestrian's true position inside its position "
                           "sets and refined regions, and inside the area the controller "
                           "accounts for (m); negative outside")
    labelled_only: ClassVar[bool] = True
    reads_regions: ClassVar[bool] = True

    scenario: Scenario

    def __call__(self, result: StepResult) -> None:
        """Nothing to watch: the recorder keeps every set and region."""

    def value(self, recorder: RunRecorder) -> dict[str, Any]:
        from sse_cosim.reporting.recorder import zonotope_2d_halfspaces_reference

        truths = _truths(recorder)
        sets = _Least()
        for t, vehicle, node, track, kind, center, generators in recorder.set_records:
            truth = truths.get((t, track))
            if truth is not None:
                x, y = truth[0] - float(center[0]), truth[1] - float(center[1])
                depth = min(b - abs(dx * x + dy * y) for dx, dy, b in
                            zonotope_2d_halfspaces_reference(generators, 0.0))
                sets.note(depth, t=t, vehicle=vehicle, node=node, pedestrian=track, kind=kind)
        regions, accounted = _regions_depths(recorder, truths)
        return {"sets": sets.value(), "regions": regions.value(),
                "accounted": accounted.value()}


@dataclass
class AccountedDepth:
    """The ``accounted`` part of :class:`ContainmentDepth` alone: the least depth of every
    pedestrian inside the window in the area each automated vehicle accounts for, its refined
    regions and unobserved area together. It reads no region's name, so it serves anonymous
    runs as well as labelled ones."""

    name: ClassVar[str] = "accounted_depth"
    help: ClassVar[str] = ("least depth of a pedestrian inside the refined regions and the "
                           "unobserved area together (m); negative outside; any association")
    labelled_only: ClassVar[bool] = False
    reads_regions: ClassVar[bool] = True

    scenario: Scenario

    def __call__(self, result: StepResult) -> None:
        """Nothing to watch: the recorder keeps every region."""

    def value(self, recorder: RunRecorder) -> dict[str, Any]:
        return _regions_depths(recorder, _truths(recorder))[1].value()


def _truths(recorder: RunRecorder) -> dict[tuple[float, str], tuple[float, float]]:
    """(t, pedestrian) -> its true position, from the recorder's truth rows."""
    return {(row["t"], row["pedestrian"]): (row["x"], row["y"]) for row in recorder.truth_rows}


def _regions_depths(recorder: RunRecorder, truths: dict[tuple[float, str], tuple[float, float]]
                    ) -> tuple[_Least, _Least]:
    """The least depth of a pedestrian inside the window in its refined region, and in the
    union of an automated vehicle's regions at one step (its refined regions, then its
    unobserved area, whose record names who stood outside the window)."""
    import shapely

    from sse_cosim.reporting.recorder import REFINED, UNOBSERVED

    present: dict[float, list[str]] = {}
    for t, pid in truths:
        present.setdefault(t, []).append(pid)
    regions, accounted = _Least(), _Least()
    for (t, vehicle), group in groupby(recorder.regions.records,
                                      key=lambda r: (r.time, r.vehicle)):
        records = list(group)
        outside = next(r for r in records if r.kind == UNOBSERVED).outside
        inside = [pid for pid in present.get(t, []) if pid not in outside]
        for record in records:
            if record.kind == REFINED and record.track in inside:
                regions.note(_signed_depth(record.region, truths[(t, record.track)]), t=t,
                             vehicle=vehicle, pedestrian=record.track)
        if inside:
            union = shapely.union_all([r.region for r in records])
            for pid in inside:
                accounted.note(_signed_depth(union, truths[(t, pid)]), t=t, vehicle=vehicle,
                               pedestrian=pid)
    return regions, accounted


@dataclass
class _Least:
    """The least of some depths and where it came."""

    least_m: float = np.inf
    at: dict[str, Any] = field(default_factory=dict)

    def note(self, depth: float, **where: Any) -> None:
        if depth < self.least_m:
            self.least_m, self.at = float(depth), where

    def value(self) -> dict[str, Any]:
        return {"least_m": None if np.isinf(self.least_m) else self.least_m, **self.at}


def _signed_depth(region: Any, point: tuple[float, float]) -> float:
    """The distance from ``point`` to the boundary of the shapely ``region``: positive
    inside, negative outside."""
    import shapely

    p = shapely.Point(point)
    distance = float(shapely.distance(region.boundary, p))
    return distance if region.covers(p) else -distance


@dataclass
class _Blocking:
    """A stretch of one vehicle's steps blocking a crossing: from ``t`` (s), ``steps`` long,
    the crossings it stood on and the pedestrians that waited at them."""

    t: float
    vehicle: str
    steps: int = 0
    crossings: set[str] = field(default_factory=set)
    pedestrians: set[str] = field(default_factory=set)


@dataclass
class CrossingBlocked:
    """How long an automated vehicle stood on a crossing while a pedestrian stood waiting at
    it (s): a liveness measure. SUMO keeps a pedestrian off a crossing a vehicle
    occupies (eclipse-sumo/sumo#3138), and a bus that waits for that pedestrian waits for
    itself (the falsifier's town and junction standoffs, results/falsify.md).

    A step counts for a vehicle that stands (below
    :data:`~sse_cosim.reporting.recorder.STOPPED_SPEED_MPS`) with its body on a crossing
    (:attr:`~sse_cosim.world.snapshot.VehicleState.on_crossings`) while a pedestrian stands
    (below the same speed) at it: on that crossing's own lane, where SUMO stops a walker
    short of the vehicle (:attr:`~sse_cosim.world.snapshot.PersonState.crossing`; the
    junction's standoff), or on a walking area with that crossing next on its walk
    (:attr:`~sse_cosim.world.snapshot.PersonState.next_crossing`; the town's).
    ``longest_s`` is the longest stretch of one vehicle's counted steps, ``total_s`` every
    vehicle's counted steps together; the longest's start ``t``, its ``vehicle``, and the
    ``crossings`` and ``pedestrians`` of its steps come with it (none: no step counted).
    """

    name: ClassVar[str] = "crossing_blocked"
    help: ClassVar[str] = ("longest time an automated vehicle stood on a crossing while a "
                           "pedestrian stood waiting at it, at its kerb or on it (s)")
    labelled_only: ClassVar[bool] = False
    reads_regions: ClassVar[bool] = False

    scenario: Scenario
    _open: dict[str, _Blocking] = field(default_factory=dict)  # vehicle -> its stretch now
    _longest: _Blocking | None = None
    _steps: int = 0

    def __call__(self, result: StepResult) -> None:
        from sse_cosim.reporting.recorder import STOPPED_SPEED_MPS

        persons = result.snapshot.persons
        for vehicle in result.vehicles:
            state = result.snapshot.vehicles[vehicle]
            waiting = {pid: at for pid, p in persons.items()
                       if p.speed < STOPPED_SPEED_MPS
                       and (at := p.crossing or p.next_crossing) in state.on_crossings}
            if state.speed >= STOPPED_SPEED_MPS or not waiting:
                self._open.pop(vehicle, None)
                continue
            stretch = self._open.setdefault(
                vehicle, _Blocking(round(result.snapshot.time, 6), vehicle))
            stretch.steps += 1
            stretch.crossings.update(waiting.values())
            stretch.pedestrians.update(waiting)
            self._steps += 1
            if self._longest is None or stretch.steps > self._longest.steps:
                self._longest = stretch

    def value(self, recorder: RunRecorder) -> dict[str, Any]:
        dt = self.scenario.simulation.step_length_s
        longest = self._longest
        at = {} if longest is None else {
            "t": longest.t, "vehicle": longest.vehicle, "crossings": sorted(longest.crossings),
            "pedestrians": sorted(longest.pedestrians)}
        return {"longest_s": round(dt * (0 if longest is None else longest.steps), 6),
                "total_s": round(dt * self._steps, 6), **at}


MARGINS: dict[str, Callable[[Scenario], Margin]] = {
    margin.name: margin for margin in (MovingDistance, TimeToCollision, MovingTimeToCollision,
                                       ContainmentDepth, AccountedDepth, CrossingBlocked)}


def _walking_velocities(persons: Sequence[PersonState]) -> np.ndarray:
    """Each pedestrian's velocity (m/s): its speed along its heading (none while it waits),
    shape (n, 2). The C library's cos and sin (``math``), the same on every CPU."""
    return np.array([(p.speed * math.cos(p.heading), p.speed * math.sin(p.heading))
                     if p.heading is not None else (0.0, 0.0) for p in persons]).reshape(-1, 2)


def check_margins(names: Sequence[str], scenario: Scenario, source: str) -> None:
    """:class:`UserError` (naming ``source``) if ``scenario`` cannot give a margin of
    ``names``: one that reads labelled sets, in a run with anonymous detections."""
    from sse_cosim.errors import UserError

    for name in names:
        if MARGINS[name].labelled_only and scenario.estimator.association != "labelled":
            raise UserError(source, "estimator.association",
                            f"the {name} margin needs sets that name their pedestrian, and "
                            f"this run's detections are {scenario.estimator.association}",
                            'set estimator.association = "labelled", or ask for another margin')
"""Every margin a run can be asked for, by name."""

"""Collects what a run produced, step by step: trace rows, the pedestrians' truth, per
pedestrian checks, sets, regions, summary figures, scene frames (at chosen times and at the
run's key moments) and, for ``replay.html``, a compact frame of every step.

Soundness is checked per pedestrian (paper Section III): at every step every pedestrian in the
scene lies in each set the automated vehicle holds of it (local, fused), in its refined region,
and in a refined region or the unobserved area; each miss is a violation, counted per
pedestrian. With anonymous tracks (``estimator.association = "anonymous"``) no set names a
pedestrian, so the checks are per pedestrian over all sets: one that some node holds (it has
detected it, and not handed it over since) lies in some track set of that node; a node hands
a pedestrian it does not detect over at a step where it lies in a track the node ended then
(:class:`~sse_cosim.estimation.occupancy.EndedTrack`), whether or not a kept track holds it
too (the node's claim is "in a kept track or in an ended one": a kept track that holds its
position then need not keep holding it), and it must lie in one or the other (a pedestrian
the node detects now, in one of its tracks). One that an automated
vehicle holds, or that a sender held at the step of its newest message to that vehicle, lies
in some fused set and some refined region of that vehicle; every pedestrian, handed over or
never detected, lies in a refined region or the unobserved area (the ``unaccounted`` check).
The true ids the recorder reads from the observations serve these checks only.

Checks stay independent of what they check: the recorder recomputes from what it writes. A
set's position set (:class:`PositionSet`) is computed here from its state estimate's own
arrays and the scenario's estimator settings, never taken from the estimator's memo
(``MotionModel.position``), and the containment test reads the very arrays that go into
``sets.jsonl.gz`` (:func:`zonotope_2d_contains`, written here with its compiled kernels in
:mod:`~sse_cosim.reporting.recorder_kernels`, not the sets library's).

The recorder only reads :class:`~sse_cosim.pipeline.result.StepResult`; writing files is
:mod:`sse_cosim.reporting.outputs`'s job.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from itertools import pairwise
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
import shapely

from sse_cosim.control.speed import SpeedLevel
from sse_cosim.estimation.motion import MODELS
from sse_cosim.reporting.recorder_kernels import FLAT_SINE, contains_2d, position_2d
from sse_cosim.reporting.replay import ReplayLog
from sse_cosim.scenario.model import Scenario, present
from sse_cosim.sensors.faults import FaultLog
from sse_cosim.sets import Zonotope
from sse_cosim.sets.zonotope import generator_volume
from sse_cosim.world.signals import STOP_FOR

if TYPE_CHECKING:  # only the type: a report that reads folders loads no estimation
    from sse_cosim.pipeline.ego import EgoStep
    from sse_cosim.pipeline.result import StepResult

FUSED = "fused"
REFINED = "refined"  # a known pedestrian's zonotope refined with negative information
UNOBSERVED = "unobserved"  # walkable ground where an undetected pedestrian may be
STOPPED_SPEED_MPS = 0.1  # the bus counts as stopped below this actual speed
HOLDING = frozenset(level.label for level in (SpeedLevel.CREEP, SpeedLevel.STOP,
                                              SpeedLevel.EMERGENCY))
"""The levels that hold a vehicle back: told to crawl, stand or brake."""
UNACCOUNTED = "unaccounted"  # a pedestrian in no refined region and not in the unobserved area
CONTAINMENT_TOL_M = 1e-7  # slack of a set's containment check (m)


def _told_to_stop(ego: EgoStep, result: StepResult) -> bool:
    """Whether the vehicle's next signalised stop line (the route's geometry:
    ``picture.light``) shows red, yellow or red-yellow in the world's snapshot: a vehicle held
    there is held by the law, not needlessly."""
    if ego.picture.light is None:
        return False
    light, link = ego.picture.light
    state = result.snapshot.signals.get(light)
    return state is not None and state.shows(link) in STOP_FOR


HalfSpace = tuple[float, float, float]  # (d_x, d_y, b): the points x with |d·(x − c)| <= b


@dataclass(frozen=True, eq=False)
class PositionSet:
    """A pedestrian's position set as the recorder writes it (a line of ``sets.jsonl.gz``) and
    checks it: ⟨center, generators⟩, ``center`` (2,), ``generators`` (2, e), read-only, and
    its ``area`` (m², :meth:`Zonotope.volume` of the same arrays). The line, the area and the
    containment check read these same arrays."""

    center: np.ndarray
    generators: np.ndarray
    area: float

    @classmethod
    def of(cls, estimate: Zonotope, jitter: float) -> PositionSet:
        """The position set of a state estimate (its own arrays; :func:`position_arrays`)."""
        center, generators = position_arrays(estimate.center, estimate.generators, jitter)
        center.setflags(write=False)
        generators.setflags(write=False)
        return cls(center, generators, generator_volume(generators))

    def contains(self, point: np.ndarray) -> bool:
        """Whether ``point`` (2,) lies in the set, to :data:`CONTAINMENT_TOL_M`
        (:func:`zonotope_2d_contains`)."""
        return bool(contains_2d(self.center, self.generators, _float_point(point),
                                CONTAINMENT_TOL_M))

    @cached_property
    def zonotope(self) -> Zonotope:
        """The same arrays as a :class:`Zonotope` (plots, the replay)."""
        return Zonotope.unchecked(self.center, self.generators)


def position_arrays(center: np.ndarray, generators: np.ndarray,
                    jitter: float) -> tuple[np.ndarray, np.ndarray]:
    """The position set C Z ⊕ box(jitter) of a state set Z = ⟨c, G⟩, c (n,), G (n, e): the
    estimator's documented claim (:mod:`sse_cosim.estimation.motion`), computed from Z's arrays.

    C = [I 0] (2, n) picks the position rows, which come first in every state model (a
    constant-velocity state has its velocity rows after them): C Z = ⟨c[:2], G[:2]⟩, exactly,
    with no product. Returns ⟨C c, [C G, jitter I]⟩, shapes (2,), (2, e + 2), or ⟨C c, C G⟩,
    (2,), (2, e), without jitter. A zero is written as 0.0 whatever its sign (``+ 0.0``): the
    sign of a zero is no part of the set, and a product may give either.
    """
    return position_2d(center, generators, jitter)


def zonotope_2d_halfspaces_reference(generators: np.ndarray, tol: float) -> list[HalfSpace]:
    """Half-spaces whose intersection is the 2-D zonotope ⟨c, G⟩, G (2, e), widened by ``tol``
    (m): (d, Σ_i |d·g_i| + tol) for unit directions d; the reference of the compiled
    :func:`~sse_cosim.reporting.recorder_kernels.halfspaces_2d` (the same bits).

    The directions: the normal of every nonzero generator (a 2-D zonotope's facet normals:
    exact for a set whose generators span the plane). A flat set (the sine between every two
    generator directions below :data:`FLAT_SINE`), whose facets alone bound its length only to
    tol over the sine of half its spread, is also bounded along its generators; a point (no
    nonzero generator) along the axes (|x − c|∞ <= tol). Python floats, each operation rounded
    as IEEE 754 prescribes and every sum taken from the left: the same on every machine, and no
    square underflows (each generator is scaled by its largest entry first).
    """
    columns = [(a, b) for a, b in zip(*generators.tolist(), strict=True) if a or b]
    if not columns:
        return [(1.0, 0.0, tol), (0.0, 1.0, tol)]
    units = [_unit(a, b) for a, b in columns]
    directions = [(-uy, ux) for ux, uy in units]
    if not any(abs(ux * vy - uy * vx) >= FLAT_SINE
               for i, (ux, uy) in enumerate(units) for vx, vy in units[i + 1:]):
        directions += units  # a flat set
    return [(dx, dy, _left_sum(abs(dx * a + dy * b) for a, b in columns) + tol)
            for dx, dy in directions]


def zonotope_2d_contains(center: np.ndarray, generators: np.ndarray, point: np.ndarray,
                         tol: float) -> bool:
    """Whether ``point`` (2,) lies in the 2-D zonotope ⟨c, G⟩, ``center`` (2,), ``generators``
    (2, e), up to ``tol`` (m): |d·(x − c)| <= b for every half-space (d, b) of
    :func:`zonotope_2d_halfspaces_reference`, compiled
    (:func:`~sse_cosim.reporting.recorder_kernels.contains_2d`)."""
    return bool(contains_2d(_float_point(center), _float_array(generators),
                            _float_point(point), tol))


def _float_point(point: np.ndarray) -> np.ndarray:
    """``point`` (2,) as float64 (the kernels' one type; no copy if it is one)."""
    return np.asarray(point, dtype=np.float64)


def _float_array(values: np.ndarray) -> np.ndarray:
    """``values`` as a C-ordered float64 array (no copy if it is one)."""
    return np.ascontiguousarray(values, dtype=np.float64)


def _unit(a: float, b: float) -> tuple[float, float]:
    """(a, b) != 0 scaled to length 1 (by its largest entry first: no square underflows)."""
    scale = max(abs(a), abs(b))
    a, b = a / scale, b / scale
    length = math.sqrt(a * a + b * b)
    return a / length, b / length


def _left_sum(values: Iterable[float]) -> float:
    """Σ ``values`` from the left, from 0.0 (``sum`` compensates its rounding from Python
    3.12 on)."""
    total = 0.0
    for value in values:
        total += value
    return total


@dataclass(frozen=True)
class RegionRecord:
    """One region an automated vehicle's controller used at one step: a known pedestrian's
    refined region (``track`` its id) or the unobserved area (``track`` None).
    ``outside``: on the unobserved area's record, every pedestrian who stood outside the
    window in which regions are kept, where that step's regions claim nothing about them
    (every walkable place counts as occupied there); not written to ``regions.jsonl.gz``."""

    time: float
    kind: str  # REFINED or UNOBSERVED
    track: str | None
    region: shapely.Geometry
    vehicle: str  # the automated vehicle's id
    outside: frozenset[str] = frozenset()


class RegionSink(Protocol):
    """Where each step's region records go as they come (``regions.jsonl.gz``, written while
    the run goes: :class:`~sse_cosim.reporting.outputs.RegionFile`)."""

    def add(self, records: Sequence[RegionRecord]) -> None: ...


@dataclass
class RegionLog:
    """The regions the automated vehicles' controllers used, step by step: handed to
    ``sink`` as they come, and kept in ``records`` only with ``keep`` (the margins that
    re-check them after the run). A long run on a town's bus line holds thousands of steps of
    an unobserved area of ten thousand vertices: kept, they would outgrow the memory."""

    sink: RegionSink | None = None
    keep: bool = True
    records: list[RegionRecord] = field(default_factory=list)

    def add(self, records: Sequence[RegionRecord]) -> None:
        if self.sink is not None:
            self.sink.add(records)
        if self.keep:
            self.records.extend(records)


@dataclass(frozen=True)
class SceneFrame:
    """What a scene plot at one time needs (position sets, geometries)."""

    time: float
    footprints: dict[str, tuple[str, shapely.Polygon]]  # vehicle id -> (its kind, footprint)
    sectors: dict[str, tuple[str, shapely.Geometry, shapely.Geometry]]  # sensor -> node, vis, occ
    strips: list[tuple[str, np.ndarray, float, float]]  # (node, normal (2,), value, radius)
    local_sets: list[tuple[str, Zonotope]]  # (node, a pedestrian's position set)
    fused_sets: dict[str, Zonotope]  # pedestrian id -> fused position set
    truths: dict[str, tuple[float, float]]  # pedestrian id -> its true position
    unobserved: shapely.Geometry  # walkable area where an undetected pedestrian may be


@dataclass
class KeyMoments:
    """The scenes of a run's key moments (the paper's Fig. 5), seen by its first automated
    vehicle: the start, the first detection by any node, the first fusion of shared sets,
    the first slow-down to ``slow`` or below, the first stop and the closest approach to a
    pedestrian (kept up to date while the distance shrinks)."""

    frames: dict[str, SceneFrame] = field(default_factory=dict)  # moment -> its scene
    done: set[str] = field(default_factory=set)  # the firsts already seen
    closest_m: float = float("inf")
    previous: SpeedLevel | None = None

    def due(self, level: SpeedLevel, distance: float | None, detected: bool,
            shared_fusion: bool) -> list[str]:
        """The moments that this step is (a step may be several)."""
        before, self.previous = (level if self.previous is None else self.previous), level
        slowed = before < SpeedLevel.SLOW <= level
        firsts = {"start": True, "first detection": detected,
                  "first shared fusion": shared_fusion, "first slow-down": slowed,
                  "first stop": level >= SpeedLevel.STOP}
        due = [name for name, now in firsts.items() if now and name not in self.done]
        self.done.update(due)
        if distance is not None and distance < self.closest_m:
            self.closest_m = distance
            due.append("closest approach")
        return due

    def scenes(self) -> list[tuple[str, SceneFrame]]:
        """Each distinct scene once, in time order, with the names of its moments."""
        names: dict[float, list[str]] = {}
        for name, frame in self.frames.items():
            names.setdefault(frame.time, []).append(name)
        by_time = {frame.time: frame for frame in self.frames.values()}
        return [(", ".join(names[t]), by_time[t]) for t in sorted(by_time)]


@dataclass(frozen=True)
class _LocalSet:
    """A node's position set of one pedestrian at one step, and whether it detects it now."""

    node: str
    pedestrian: str
    position: PositionSet
    detected: bool


@dataclass
class RunRecorder:
    """Callable passed to ``simulate``; keeps everything the reports need (``replay``:
    every step's frame for ``replay.html``, None to keep none)."""

    scenario: Scenario
    scene_times: tuple[float, ...] = ()
    replay: ReplayLog | None = None
    rows: list[dict[str, Any]] = field(default_factory=list)
    truth_rows: list[dict[str, Any]] = field(default_factory=list)  # truth.csv's rows
    pedestrian_rows: list[dict[str, Any]] = field(default_factory=list)  # per vehicle and person
    # the sets to write, each (t, vehicle, node, track, kind, center, generators) with its
    # position set's own read-only arrays: nothing for the garbage collector to walk while the
    # run goes (:attr:`set_lines` makes the lines)
    set_records: list[tuple[Any, ...]] = field(default_factory=list)
    regions: RegionLog = field(default_factory=RegionLog)
    scenes: list[SceneFrame] = field(default_factory=list)
    key_moments: KeyMoments = field(default_factory=KeyMoments)
    violations: list[dict[str, Any]] = field(default_factory=list)
    first_detection: dict[str, dict[str, float]] = field(default_factory=dict)
    first_shared_fusion: dict[str, Any] | None = None
    fusion_larger_than_input: int = 0  # steps where the fused set outgrew its smallest input
    flag_steps: Counter = field(default_factory=Counter)  # "<sensor or node>: <flag>" -> steps
    faults: FaultLog = field(init=False)
    anonymous: bool = field(init=False)  # sets of anonymous tracks: checked over all sets
    jitter: float = field(init=False)  # the estimator's position jitter (m), its claim's box
    state_dim: int = field(init=False)  # the estimator's state dimension (position rows first)
    # node -> pid -> the steps from which the node holds it (True: detected) or has handed it
    # over (False), each a change (anonymous checks)
    custody: dict[str, dict[str, list[tuple[int, bool]]]] = field(default_factory=dict)
    # the position sets made at the current step, by their estimate's identity (with it, so
    # that no id is reused): an estimate fused, shared or checked again is not recomputed
    step_positions: dict[int, tuple[Zonotope, PositionSet]] = field(
        init=False, repr=False, compare=False, default_factory=dict)

    def __post_init__(self) -> None:
        self.start(self.scenario)

    def start(self, scenario: Scenario) -> None:
        """Record ``scenario`` as run: the one the world resolved (its measured jitter) is
        given here before the first step."""
        self.scenario = scenario
        self.faults = FaultLog(scenario)
        self.anonymous = scenario.estimator.association == "anonymous"
        jitter = scenario.estimator.position_jitter_m
        self.jitter = float("nan") if jitter is None else jitter  # nan: not resolved yet
        # the registered model's dimension (its jitter does not change it)
        self.state_dim = MODELS[scenario.estimator.state_model](
            scenario.estimator, scenario.simulation.step_length_s, 0.0).dim

    def __call__(self, result: StepResult) -> None:
        t = round(result.snapshot.time, 6)
        truths = {pid: np.asarray(p.position) for pid, p in sorted(result.snapshot.persons.items())}
        points = _TruePoints.of(truths)
        self.step_positions = {}
        if self.anonymous:  # (by id, every set names its pedestrian: nothing to remember)
            self._note_detected(result)
        persons = result.snapshot.persons
        self.truth_rows += [{"t": t, "pedestrian": pid, "x": xy[0], "y": xy[1],
                             "speed": persons[pid].speed, "heading": persons[pid].heading}
                            for pid, xy in truths.items()]
        local = self._check_local_sets(t, result, truths)
        if self.replay is not None:
            self.replay.add(result, [(s.node, s.pedestrian, s.position.zonotope, s.detected)
                                     for s in local])
        for ego in result.vehicles.values():
            self._vehicle_step(t, result, ego, truths, points, local)

    def _vehicle_step(self, t: float, result: StepResult, ego: EgoStep,
                      truths: dict[str, np.ndarray], points: _TruePoints,
                      local: list[_LocalSet]) -> None:
        """One automated vehicle's row, checks, sets and regions at one step."""
        vehicle = ego.vehicle
        bus = result.snapshot.vehicles[vehicle]
        row: dict[str, Any] = {
            "t": t,
            "vehicle": vehicle,
            "bus_x": bus.footprint.front.x,
            "bus_y": bus.footprint.front.y,
            "bus_speed": bus.speed,
            "commanded_speed": ego.decision.command_mps,
            "level": ego.decision.level.label,
            "emergency": ego.decision.level is SpeedLevel.EMERGENCY,
        }
        self._record_local_sets(t, row, result, vehicle, local)
        self._flags(row, result, ego)
        checks = {pid: _PedestrianCheck(pid) for pid in truths}
        held = _HeldRegions.of(ego, points)
        if self.anonymous:
            fused, regions = self._check_anonymous(t, result, ego, truths, held, checks)
        else:
            fused, regions = self._check_labelled(t, ego, truths, held, checks)
        for key, position in fused.items():
            self._note_fusion(t, key, position, ego)
        row["fused_area"] = _total(z.area for z in fused.values())
        row["fused_contains_truth"] = _all(c.fused for c in checks.values())
        row["possible_area"] = _total(r.area for r in regions.values())
        row["possible_contains_truth"] = _all(c.refined for c in checks.values())
        self._note_regions(t, vehicle, held)
        distances = shapely.distance(bus.footprint.polygon(), points.array).tolist()
        for (pid, check), distance in zip(checks.items(), distances, strict=True):
            check.accounted_for = self._check_accounted(t, pid, held, truths[pid])
            check.distance = distance
            self.pedestrian_rows.append({"t": t, "vehicle": vehicle, **check.row()})
        row["accounted_for"] = _all(c.accounted_for for c in checks.values())
        row["path_clear"] = ego.picture.path_clear
        row["truly_clear"] = self._truly_clear(ego, points, result) and not _told_to_stop(
            ego, result)
        row["unresolved_occluded_m2"] = ego.picture.unresolved_occluded_m2
        row["own_occluded_m2"] = ego.picture.own_occluded_m2
        row["distance_to_crossing"] = ego.picture.distance_to_crossing
        row["distance_bus_pedestrian"] = min((c.distance for c in checks.values()), default=None)
        row["collision"] = any(c.distance <= self.scenario.person_radius_m(pid)
                               for pid, c in checks.items())
        self.rows.append(row)
        shared_fusion_now = (self.first_shared_fusion or {}).get("t") == t
        moments = [] if vehicle != next(iter(result.vehicles)) else self.key_moments.due(
            ego.decision.level, row["distance_bus_pedestrian"], any(s.detected for s in local),
            shared_fusion_now)
        wanted = shared_fusion_now + self._wants_scene(t)
        if not (moments or wanted):
            return
        frame = _frame(t, result, held.unobserved,
                       [(s.node, s.position.zonotope) for s in local],
                       {key: z.zonotope for key, z in fused.items()}, truths)
        self.scenes += [frame] * wanted
        self.key_moments.frames.update(dict.fromkeys(moments, frame))

    def _truly_clear(self, ego: EgoStep, points: _TruePoints, result: StepResult) -> bool:
        """Whether the truth left the vehicle's path clear: from standstill it would have
        cleared every zone ahead (each zone's ``clear_s``) before any pedestrian in the scene
        could be in it. A pedestrian whose true position lies d from the zone's ground is
        there no sooner than (d - 2 eps) / v (A1: its path, within eps of it, moves at most
        v), whatever anyone knows of it; on a signalised crossing's own ground, a walker whom
        the world has off that crossing while its light holds its walkers is there no sooner
        than the light can change (``pedestrian_lights``, read from the snapshot's lights).
        The controller's picture is not read (its zones are the route's geometry, their clear
        times the bus's dynamics)."""
        zones = [z for z in ego.picture.zones if z.ground is not None]
        if not zones or not len(points.array):
            return True
        estimator = self.scenario.estimator
        crossings = np.array([result.snapshot.persons[pid].crossing or ""
                              for pid in points.by_id])  # (k,)
        for zone in zones:
            parts = [(zone.ground, "", 0.0)]
            for cid, own, lights in zone.lit:
                release = lights.release_s(result.snapshot.signals)
                if release > 0.0:
                    parts = [(shapely.difference(parts[0][0], own), "", 0.0), *parts[1:],
                             (shapely.intersection(zone.ground, own), cid, release)]
            for ground, cid, release in parts:
                if ground.is_empty:
                    continue
                distance = shapely.distance(ground, points.array)  # (k,)
                arrival = np.maximum(0.0, distance - 2.0 * estimator.position_jitter_m) \
                    / estimator.max_pedestrian_speed_mps
                if cid:
                    arrival = np.where(crossings != cid, np.maximum(arrival, release), arrival)
                if arrival.min() <= zone.clear_s:
                    return False
        return True

    def _check_labelled(self, t: float, ego: EgoStep, truths: dict[str, np.ndarray],
                        held: _HeldRegions, checks: dict[str, _PedestrianCheck]
                        ) -> tuple[dict[str, PositionSet], dict[str, shapely.Geometry]]:
        """Each pedestrian in its own fused set and refined region; those of the pedestrians in
        the scene (position sets) by id."""
        fused = {pid: self._position(ego.estimate.fused[pid])
                 for pid in truths if pid in ego.estimate.fused}
        for pid, position in fused.items():
            checks[pid].fused = self._check(t, FUSED, pid, [position], truths[pid])
        regions = {pid: held.refined[pid] for pid in truths if pid in held.refined}
        for pid, region in regions.items():
            checks[pid].refined = self._check_region(t, pid, [region], held, truths[pid])
        return fused, regions

    def _check_anonymous(self, t: float, result: StepResult, ego: EgoStep,
                         truths: dict[str, np.ndarray], held: _HeldRegions,
                         checks: dict[str, _PedestrianCheck]
                         ) -> tuple[dict[str, PositionSet], dict[str, shapely.Geometry]]:
        """Each pedestrian the vehicle knows of (module docstring) in some fused set and some
        refined region; every fused set (position sets) and refined region, by fused key."""
        fused = {key: self._position(z) for key, z in ego.estimate.fused.items()}
        known = self._held_by(ego.vehicle, result.step)
        for sender, age in ego.shared.ages.items():
            known |= self._held_by(sender, result.step - age)
        for pid in sorted(known & truths.keys()):
            checks[pid].fused = self._check(t, FUSED, pid, list(fused.values()), truths[pid])
            checks[pid].refined = self._check_region(t, pid, list(held.refined.values()), held,
                                                     truths[pid])
        return fused, dict(held.refined)

    def _note_detected(self, result: StepResult) -> None:
        """Each node holds each pedestrian it detects now (anonymous checks)."""
        for obs in result.observations.values():
            for pid in obs.detections:
                self._note_custody(obs.node, pid, result.step, True)

    def _note_custody(self, node: str, pid: str, step: int, holds: bool) -> None:
        changes = self.custody.setdefault(node, {}).setdefault(pid, [])
        if not changes or changes[-1][1] != holds:
            changes.append((step, holds))

    def _held_by(self, node: str, step: int) -> set[str]:
        """The pedestrians ``node`` holds at ``step``: it detected them by then and did not hand
        them over after its last detection."""
        held = set()
        for pid, changes in self.custody.get(node, {}).items():
            last = [holds for first, holds in changes if first <= step]
            if last and last[-1]:
                held.add(pid)
        return held

    def _check_local_sets(self, t: float, result: StepResult,
                          truths: dict[str, np.ndarray]) -> list[_LocalSet]:
        """Every node's set of each pedestrian in the scene (anonymous: every track of every
        node, each pedestrian the node holds checked against them all, or handed over),
        checked once per step, however many automated vehicles receive it."""
        local: list[_LocalSet] = []
        for node, tracks in result.tracks.items():
            if self.anonymous:
                mine = [_LocalSet(node, key, self._position(track.estimate), track.detected)
                        for key, track in tracks.items()]
                ended = [self._position(e.estimate) for e in tracks.ended_at(result.step)]
                for pid in sorted(self._held_by(node, result.step) & truths.keys()):
                    self._check_held(t, result, node, pid, [s.position for s in mine], ended,
                                     truths[pid])
                local += mine
                continue
            for pid in (pid for pid in truths if pid in tracks):
                position = self._position(tracks[pid].estimate)
                self._check(t, node, pid, [position], truths[pid])
                local.append(_LocalSet(node, pid, position, tracks[pid].detected))
        return local

    def _check_held(self, t: float, result: StepResult, node: str, pid: str,
                    positions: list[PositionSet], ended: list[PositionSet],
                    truth: np.ndarray) -> None:
        """A pedestrian ``node`` holds lies in one of its track sets (``positions``), or, if
        the node does not detect it now, in one of the tracks it ended now (``ended``): then
        the node has handed it over, even if a kept track holds it too (module docstring;
        the unobserved areas take it over, which the ``unaccounted`` check checks)."""
        detected = any(o.node == node and pid in o.detections
                       for o in result.observations.values())
        if not detected and any(z.contains(truth) for z in ended):
            self._note_custody(node, pid, result.step, False)
            return
        self._check(t, node, pid, positions, truth)

    def _position(self, estimate: Zonotope) -> PositionSet:
        """The position set of a state estimate that the recorder writes and checks, from the
        estimate's arrays and the scenario's estimator settings (the estimator's claim C Z ⊕
        box(jitter), not its memo); made once per step and estimate (``step_positions``)."""
        kept = self.step_positions.get(id(estimate))
        if kept is not None and kept[0] is estimate:
            return kept[1]
        if estimate.dim != self.state_dim:
            raise ValueError(f"a {estimate.dim}-D estimate; the state model "
                             f"{self.scenario.estimator.state_model!r} has {self.state_dim}")
        position = PositionSet.of(estimate, self.jitter)
        self.step_positions[id(estimate)] = (estimate, position)
        return position

    def _record_local_sets(self, t: float, row: dict[str, Any], result: StepResult,
                           vehicle: str, local: list[_LocalSet]) -> None:
        """The local sets in ``vehicle``'s record: their lines; per node whether it detects
        any pedestrian and the total area of its sets (None without any)."""
        for s in local:
            self._set_line(t, vehicle, s.node, s.pedestrian, "local", s.position)
            if s.detected and s.node not in self.first_detection:
                self.first_detection[s.node] = self._moment(t, result.vehicles[vehicle])
        for node in result.tracks:
            mine = [s for s in local if s.node == node]
            row[f"{node}_detected"] = any(s.detected for s in mine)
            row[f"{node}_area"] = _total(s.position.area for s in mine)

    def _note_fusion(self, t: float, pid: str, position: PositionSet, ego: EgoStep) -> None:
        """Record a fused set (``pid``: its pedestrian, or its fused key): its line, whether it
        outgrew its smallest input, the first fusion and the first fusion of shared sets."""
        inputs = ego.estimate.inputs[pid]
        smallest = min(self._position(z).area for z in inputs.values())
        if position.area > smallest * (1 + 1e-9) + 1e-12:
            self.fusion_larger_than_input += 1
        self._set_line(t, ego.vehicle, FUSED, pid, "fused", position)
        if FUSED not in self.first_detection:
            self.first_detection[FUSED] = self._moment(t, ego)
        self._note_shared_fusion(t, pid, position, ego)

    def _flags(self, row: dict[str, Any], result: StepResult, ego: EgoStep) -> None:
        """Flag columns (per sensor: left out; per node: excluded/conflict); the fault
        bookkeeping follows the first automated vehicle (the paper's bus)."""
        flags = ego.estimate.flags
        for sensor, flagged in flags.sensors.items():
            row[f"{sensor}_flag"] = flagged
            self.flag_steps[f"{sensor}: left out"] += flagged
        for node, flag in flags.nodes.items():
            row[f"{node}_flag"] = flag
            self.flag_steps[f"{node}: {flag}"] += bool(flag)
        row["inconsistent"] = flags.inconsistent
        row["senders"] = len(ego.shared.ages)  # nodes whose messages reached the vehicle
        if ego.vehicle == next(iter(result.vehicles)):
            self.faults.update(result.step, round(result.snapshot.time, 6), result.faults,
                               flags.sensors, flags.nodes, ego.shared.ages)

    def _check(self, t: float, node: str, pid: str, positions: list[PositionSet],
               truth: np.ndarray) -> bool:
        """Whether pedestrian ``pid``'s true position (shape (2,)) lies in one of
        ``positions`` (their written arrays)."""
        inside = any(z.contains(truth) for z in positions)
        return self._violation_unless(inside, t, node, pid, truth)

    def _check_region(self, t: float, pid: str, regions: list[shapely.Geometry],
                      held: _HeldRegions, truth: np.ndarray) -> bool:
        """Whether pedestrian ``pid``'s true position lies in one of ``regions``, or outside
        the window in which regions are kept (there every walkable place counts as
        occupied)."""
        inside = held.outside_or_in(pid, regions)
        return self._violation_unless(inside, t, "possible", pid, truth)

    def _check_accounted(self, t: float, pid: str, held: _HeldRegions,
                         truth: np.ndarray) -> bool:
        """Whether the pedestrian is where the controller looks for pedestrians: inside a
        refined region (any track's) or the unobserved area, or outside the window where
        hidden ground is tracked (there every walkable place counts as occupied)."""
        inside = held.outside_or_in(pid, held.accounting(pid))
        return self._violation_unless(inside, t, UNACCOUNTED, pid, truth)

    def _violation_unless(self, inside: bool, t: float, node: str, pid: str,
                          truth: np.ndarray) -> bool:
        if not inside:
            self.violations.append({"t": t, "node": node, "pedestrian": pid,
                                    "truth": truth.tolist()})
        return inside

    def _note_regions(self, t: float, vehicle: str, held: _HeldRegions) -> None:
        """Keep the regions ``vehicle``'s controller used this step: every known pedestrian's
        refined region (by id) and the unobserved area, so that anyone can re-check them."""
        self.regions.add([
            *(RegionRecord(t, REFINED, pid, region, vehicle)
              for pid, region in sorted(held.refined.items())),
            RegionRecord(t, UNOBSERVED, None, held.unobserved, vehicle,
                         outside=frozenset(pid for pid, out in held.outside.items() if out))])

    def _set_line(self, t: float, vehicle: str, node: str, track: str, kind: str,
                  position: PositionSet) -> None:
        self.set_records.append((t, vehicle, node, track, kind, position.center,
                                 position.generators))

    @staticmethod
    def _moment(t: float, ego: EgoStep) -> dict[str, float]:
        return {"t": t, "bus_distance_to_crossing_m": ego.picture.distance_to_crossing}

    def _note_shared_fusion(self, t: float, person_id: str, fused_position: PositionSet,
                            ego: EgoStep) -> None:
        """Record the first step at which the bus fuses two or more sets (paper Fig. 7)."""
        if self.first_shared_fusion is not None:
            return
        inputs = ego.estimate.inputs[person_id]
        if len(inputs) < 2:
            return
        self.first_shared_fusion = {
            "t": t,
            "input_areas_m2": {n: self._position(z).area for n, z in inputs.items()},
            "fused_area_m2": fused_position.area,
        }

    @property
    def set_lines(self) -> list[dict[str, Any]]:
        """The lines of ``sets.jsonl.gz``: t, vehicle, node, track, kind, then the position set,
        ``center`` (2 floats) and ``generators`` (2 rows of e floats)."""
        return [{"t": t, "vehicle": vehicle, "node": node, "track": track, "kind": kind,
                 "center": center.tolist(), "generators": generators.tolist()}
                for t, vehicle, node, track, kind, center, generators in self.set_records]

    def _wants_scene(self, t: float) -> bool:
        dt = self.scenario.simulation.step_length_s
        return any(abs(t - s) < 0.5 * dt for s in self.scene_times)

    def summary(self, route_completed: Mapping[str, bool] | None = None) -> dict[str, Any]:
        """The run's figures (``summary.json``).

        ``route_completed``: per automated vehicle whether it reached the end of its route,
        which only the simulation knows (the recorder sees no step after it left); None: not
        known. ``vehicles`` holds each automated vehicle's figures; the top level repeats the
        first one's (the paper's bus) beside the run's totals (violations, collisions, contact
        steps, least distance, and ``route_completed``: every automated vehicle reached the end
        of its route). Rows start once a vehicle is in the network, so its times count from its
        departure.
        """
        pedestrians = self._pedestrian_summary()
        completed = route_completed or {}
        vehicles = {vid: self._vehicle_figures([r for r in self.rows if r["vehicle"] == vid],
                                               completed.get(vid))
                    for vid in present(self.scenario.automated)}
        distances = [r["distance_bus_pedestrian"] for r in self.rows
                     if r["distance_bus_pedestrian"] is not None]
        summary = {
            "scenario": self.scenario.name,
            "pedestrian": bool(pedestrians),
            "nodes": self.scenario.node_ids(),
            **next(iter(vehicles.values())),
            "vehicles": vehicles,
            "pedestrians": pedestrians,
            "min_distance_bus_pedestrian_m": min(distances) if distances else None,
            "first_detection": self.first_detection,
            "set_area_m2": self._area_stats(),
            "first_shared_fusion": self.first_shared_fusion,
            "containment_violations": len(self.violations),
            "fusion_larger_than_input": self.fusion_larger_than_input,
            "containment_violations_by_set": dict(Counter(v["node"] for v in self.violations)),
            "violations": self.violations[:20],
            "faults": self._fault_summary(),
            "flag_counts": {key: n for key, n in sorted(self.flag_steps.items()) if n},
            "inconsistent_steps": sum(r["inconsistent"] for r in self.rows),
            "collisions": sum(p["collisions"] for p in pedestrians.values()),
            "contact_steps": sum(r["collision"] for r in self.rows),
            "route_completed": _all_known([v["route_completed"] for v in vehicles.values()]),
        }
        contact = [r["t"] for r in self.rows if r["collision"]]
        if contact:  # only a run with a collision has these keys (the falsifier reads them)
            summary["first_collision_t_s"] = contact[0]
            summary.update(self._moving_contact())
        return summary

    def _moving_contact(self) -> dict[str, Any]:
        """Contact with a moving vehicle, apart from a pedestrian walking into a standing one:
        the claim of docs/controller.md is that every vehicle stands before any contact.
        ``collisions_moving``: contacts (per vehicle, times contact began) during steps with
        the vehicle at :data:`STOPPED_SPEED_MPS` or faster; ``first_moving_collision_t_s``:
        the first such step (None: every contact was with a standing vehicle)."""
        moving = [[r["collision"] and r["bus_speed"] >= STOPPED_SPEED_MPS
                   for r in self.rows if r["vehicle"] == vid]
                  for vid in present(self.scenario.automated)]
        times = [r["t"] for r in self.rows
                 if r["collision"] and r["bus_speed"] >= STOPPED_SPEED_MPS]
        return {"collisions_moving": sum(_entries(flags) for flags in moving),
                "first_moving_collision_t_s": times[0] if times else None}

    def _vehicle_figures(self, rows: list[dict[str, Any]],
                         route_completed: bool | None) -> dict[str, Any]:
        """One automated vehicle's figures from its rows."""
        dt = self.scenario.simulation.step_length_s
        speeds = np.array([r["bus_speed"] for r in rows]) if rows else np.zeros(0)
        levels = Counter(r["level"] for r in rows)
        distances = [r["distance_bus_pedestrian"] for r in rows
                     if r["distance_bus_pedestrian"] is not None]
        return {
            "steps": len(rows),
            "average_speed_mps": float(speeds.mean()) if speeds.size else None,
            "travel_time_s": len(rows) * dt,
            "distance_travelled_m": float(speeds.sum() * dt),
            "min_distance_pedestrian_m": min(distances) if distances else None,
            "collisions": _entries([r["collision"] for r in rows]),
            "route_completed": route_completed,
            "time_stopped_s": round(dt * int(np.sum(speeds < STOPPED_SPEED_MPS)), 6),
            "first_stop": _first_stop(rows),
            # stop and go: the controller's order to move after its order to stop
            "restarts": sum(before["commanded_speed"] == 0.0 < now["commanded_speed"]
                            for before, now in pairwise(rows)),
            # the controller's own standstill: SUMO holding a bus that was told to go (right of
            # way to a car, a leader) does not count
            "longest_standstill_after_clear_s": round(dt * _longest_run(
                [r["path_clear"] and r["bus_speed"] < STOPPED_SPEED_MPS
                 and r["commanded_speed"] < STOPPED_SPEED_MPS for r in rows]), 6),
            # liveness from the truth: told to creep, stop or brake while the path was clear
            "longest_needless_hold_s": round(dt * _longest_run(
                [r["truly_clear"] and r["level"] in HOLDING for r in rows]), 6),
            "level_share": {
                level.label: levels.get(level.label, 0) / max(len(rows), 1)
                for level in SpeedLevel
            },
        }

    def _pedestrian_summary(self) -> dict[str, dict[str, Any]]:
        """Per pedestrian (the scenario's, then those of route files as they appeared): when a
        fused set first held it, its containment violations, its least distance to the vehicle
        and its collisions (times contact began)."""
        result = {}
        ids = dict.fromkeys([*present(self.scenario.pedestrians),
                             *(r["pedestrian"] for r in self.pedestrian_rows)])
        for pid in ids:
            radius = self.scenario.person_radius_m(pid)
            rows = [r for r in self.pedestrian_rows if r["pedestrian"] == pid]
            fused = [r["t"] for r in rows if r["contained_fused"] is not None]
            result[pid] = {
                "first_fused_t": fused[0] if fused else None,
                "containment_violations": sum(v["pedestrian"] == pid for v in self.violations),
                "min_distance_m": min((r["distance"] for r in rows), default=None),
                "collisions": sum(
                    _entries([r["distance"] <= radius for r in rows if r["vehicle"] == v])
                    for v in present(self.scenario.automated)),
            }
        return result

    def _fault_summary(self) -> list[dict[str, Any]]:
        """Per injected fault its detection, and the violations of the fused set, the refined
        region and the accounting of the pedestrian from its detection on."""
        entries = self.faults.summary()
        for entry in entries:
            since = entry["detected_t"]
            entry["fused_violations_after_detection"] = None if since is None else sum(
                v["node"] in (FUSED, "possible", UNACCOUNTED) and v["t"] >= since
                for v in self.violations)
        return entries

    def _area_stats(self) -> dict[str, dict[str, float]]:
        stats = {}
        for column in [c for c in (self.rows[0] if self.rows else {}) if c.endswith("_area")]:
            values = [r[column] for r in self.rows if r[column] is not None]
            if values:
                name = column.removesuffix("_area")
                stats[name] = {"mean": float(np.mean(values)), "max": float(np.max(values))}
        return stats


@dataclass
class _PedestrianCheck:
    """One pedestrian at one step, as one automated vehicle holds it: whether its fused set
    and its refined region contain it (None: the vehicle holds none), whether it is accounted
    for, and its distance to the vehicle (m)."""

    pedestrian: str
    fused: bool | None = None
    refined: bool | None = None
    accounted_for: bool = True
    distance: float = 0.0

    def row(self) -> dict[str, Any]:
        return {"pedestrian": self.pedestrian, "contained_fused": self.fused,
                "contained_refined": self.refined, "accounted_for": self.accounted_for,
                "distance": self.distance}



@dataclass(frozen=True)
class _TruePoints:
    """The pedestrians' true positions at one step as shapely points, made once for every
    check: ``by_id`` pedestrian id -> point, ``array`` the same points, shape (k,), in that
    order."""

    by_id: dict[str, shapely.Point]
    array: np.ndarray

    @classmethod
    def of(cls, truths: dict[str, np.ndarray]) -> _TruePoints:
        """The points of ``truths`` (pedestrian id -> position (2,))."""
        array = shapely.points(np.array([*truths.values()], dtype=np.float64).reshape(-1, 2))
        return cls(dict(zip(truths, array, strict=True)), array)


@dataclass(frozen=True)
class _HeldRegions:
    """An automated vehicle's regions at one step as polygons, each made once: its refined
    regions (``refined``: track key -> polygons, in the vehicle's order) and unobserved area,
    and per pedestrian whether its true position lies outside the window in which regions are
    kept (``outside``) and that position (``points``)."""

    refined: dict[str, shapely.Geometry]
    unobserved: shapely.Geometry
    outside: dict[str, bool]
    points: dict[str, shapely.Point]

    @classmethod
    def of(cls, ego: EgoStep, points: _TruePoints) -> _HeldRegions:
        """``ego``'s regions, and where the ``points`` lie."""
        outside = np.logical_not(shapely.contains(ego.window.geometry(), points.array))
        return cls({key: region.geometry() for key, region in ego.possible.items()},
                   ego.unobserved.geometry(), dict(zip(points.by_id, outside.tolist(),
                                                       strict=True)), points.by_id)

    @cached_property
    def everywhere(self) -> list[shapely.Geometry]:
        """The unobserved area and every refined region."""
        return [self.unobserved, *self.refined.values()]

    def accounting(self, pid: str) -> list[shapely.Geometry]:
        """:attr:`everywhere`, after pedestrian ``pid``'s own refined region if a track has its
        id: the one most likely to hold it (any of them accounts for it)."""
        own = self.refined.get(pid)
        return self.everywhere if own is None else [own, *self.everywhere]

    def outside_or_in(self, pid: str, regions: list[shapely.Geometry]) -> bool:
        """Whether pedestrian ``pid`` lies outside the window or in one of ``regions`` (to
        1e-7 m)."""
        point = self.points[pid]
        return self.outside[pid] or any(
            shapely.distance(region, point) <= 1e-7 for region in regions)


def _total(values) -> float | None:
    """The sum of ``values``, None if there are none (no set, no area)."""
    values = list(values)
    return sum(values[1:], values[0]) if values else None


def _all(flags) -> bool | None:
    """Whether every known flag holds; None if none is known."""
    known = [f for f in flags if f is not None]
    return all(known) if known else None


def _all_known(flags: list[bool | None]) -> bool | None:
    """Whether every flag holds; None if any is unknown."""
    return None if None in flags else all(flags)


def collisions(summary: Mapping[str, Any]) -> int:
    """A run's collisions: contacts with a moving vehicle (``collisions_moving``; a summary
    written before contact was split counts every contact as one)."""
    if not summary["collisions"]:
        return 0
    return int(summary.get("collisions_moving", summary["collisions"]))


def walk_ins(summary: Mapping[str, Any]) -> int:
    """A run's contacts that began with the vehicle standing: a pedestrian walked into it."""
    return int(summary["collisions"]) - collisions(summary)


def first_collision_t(summary: Mapping[str, Any]) -> float | None:
    """When the first contact with a moving vehicle began (s); None: none, or not known."""
    if "collisions_moving" in summary:
        return summary["first_moving_collision_t_s"]
    return summary.get("first_collision_t_s")


def _entries(flags: list[bool]) -> int:
    """How many times ``flags`` turns true (a first step in contact counts): one collision
    lasts several steps, and the campaign counts collisions, not steps."""
    return sum(now and not before for before, now in pairwise([False, *flags]))


def _frame(t: float, result: StepResult, unobserved: shapely.Geometry,
           local_sets: list[tuple[str, Zonotope]], fused: dict[str, Zonotope],
           truths: dict[str, np.ndarray]) -> SceneFrame:
    snap = result.snapshot
    strips = [
        (obs.node, normal, float(value), float(radius))
        for obs in result.observations.values()
        for d in obs.detections.values()
        for normal, value, radius in zip(
            d.strips.normals, d.strips.values, d.strips.radii, strict=True
        )
    ]
    return SceneFrame(
        time=t,
        footprints={v.id: (v.kind, v.footprint.polygon()) for v in snap.vehicles.values()},
        sectors={name: (o.node, o.visible.geometry(), o.occluded.geometry())
                 for name, o in result.observations.items() if o.pose is not None},
        strips=strips,
        local_sets=local_sets,
        fused_sets=dict(fused),
        truths={pid: (float(xy[0]), float(xy[1])) for pid, xy in truths.items()},
        unobserved=unobserved,
    )


def _first_stop(rows: Sequence[Mapping[str, Any]]) -> dict[str, Any] | None:
    """When the vehicle first stood after it had moved (its speed below
    :data:`STOPPED_SPEED_MPS`), and its front's distance to the crossing then (the trace's
    ``distance_to_crossing``); None if it never did."""
    moved = False
    for row in rows:
        if row["bus_speed"] >= STOPPED_SPEED_MPS:
            moved = True
        elif moved:
            return {"t": row["t"], "bus_distance_to_crossing_m": row.get("distance_to_crossing")}
    return None


def _longest_run(flags: list[bool]) -> int:
    """The most consecutive True values in ``flags``."""
    longest = current = 0
    for flag in flags:
        current = current + 1 if flag else 0
        longest = max(longest, current)
    return longest

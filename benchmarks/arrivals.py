"""Decision tightness: the controller's earliest arrivals against a slow, exact reference.

Every step, each automated vehicle's picture gives, per conflict zone ahead, the earliest time
a pedestrian can be in it (docs/controller.md, "Earliest arrival"); the speed levels are
decided on it. The reference recomputes that time from the same inputs, with arithmetic of its
own:

- the regions the estimator handed the picture (``EgoStep.sources``: the unobserved area,
  then each known pedestrian; each its position region and, where known, its path region), as
  their shapely geometries;
- the zone's walkable ground, exact (the road map's piece, not the region representation's
  outer approximation), as far as the body can still touch it (``ZoneOutlook.ground``);
- the walkable ground outside the tracked window, exact, as a position region;
- the speed bound v and the jitter eps of the scenario as run (the world's measured jitter).

A pedestrian whose path moves at most v, and whose position lies within eps of its path, needs
at least ``(d - eps) / v`` from a path region d away and ``(d - 2 eps) / v`` from a position
region d away (the jitter once at each end; exact distances: the straight line is the
shortest walk). The reference takes, per source, the larger of the two it can form, the least
over the sources and the ground beyond the window, and never less than its own arrival of an
earlier consistent step less the time since (the bound moves a pedestrian no faster; a step
whose picture is inconsistent starts afresh, as the controller's floors do).

At a signalised crossing whose light holds its walkers (the ``pedestrian_lights`` assumption,
docs/controller.md, "Walkers at their red light"), the reference applies the rule with exact
geometry of its own: the zone's ground on the crossing's own ground (``RoadMap.own_grounds``,
the route's geometry like the zone's ground) is reached from a position region's part off the
crossing's area (grown by a walker's radius) no sooner than the release (the network's
program, as the world checks it), and from a known pedestrian seen off that area at red
since, no sooner than that step's release (its own record of them, kept by pedestrian id).

Soundness: the controller's arrival is never later than the reference's (a later one would let
a pedestrian be slower than the bound allows). Tightness: how much earlier, as the mean of the
controller's arrivals over the mean of the reference's, over every zone-step where both are
finite. Speed-bound models only: a model that reads the state set (bounded acceleration)
proves later arrivals than a speed bound can, and its exact reference is not this one.
"""

from __future__ import annotations

import math
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import shapely

from sse_cosim.control.picture import SceneContext, ZoneOutlook
from sse_cosim.estimation.motion import motion_model
from sse_cosim.pipeline.result import StepResult
from sse_cosim.regions import kind as region_kind
from sse_cosim.reporting.recorder import RunRecorder
from sse_cosim.runner.simulation import SimulationInfo, simulate
from sse_cosim.scenario.loader import load_scenario
from sse_cosim.scenario.model import Scenario, present
from sse_cosim.world.checks.lights import AREA_TOL_M
from sse_cosim.world.roadmap import RoadMap
from sse_cosim.world.signals import CrossingLights, SignalState

SCENARIOS = ("scenarios/s1_pedestrian.toml", "scenarios/s2_pedestrian.toml",
             "scenarios/s3_pedestrian.toml", "scenarios/s1_no_pedestrian.toml",
             "scenarios/s2_no_pedestrian.toml", "scenarios/s3_no_pedestrian.toml",
             "scenarios/town.toml", "scenarios/junction.toml")
TOLERANCE_S = 1e-6
"""How much later than the reference a controller's arrival may be before it counts as
unsound: rounding of two distance computations of the same geometries (m / v, far below a
step)."""
DECISION_HORIZON_S = 10.0
"""Arrivals up to this (s) are those the speed levels turn on (a bus clears a zone from
standstill within about 5 s): the tightness is also given over them alone."""


@dataclass(frozen=True)
class _Seen:
    """What one vehicle's picture was made from at one step."""

    step: int
    vehicle: str
    front_s: float
    zones: tuple[ZoneOutlook, ...]
    positions: tuple[shapely.Geometry, ...]  # each source's position region
    paths: tuple[shapely.Geometry | None, ...]  # each source's path region, None if unknown
    inconsistent: bool
    keys: tuple[str | None, ...] = ()  # each source's pedestrian (None: the unobserved area)
    signals: Mapping[str, SignalState] = field(default_factory=dict)  # the lights then
    time_s: float = 0.0


@dataclass
class ArrivalRecorder:
    """A step callback that keeps, per automated vehicle and step, the picture's arrivals and
    the geometries of the sources they came from (references, no copies)."""

    seen: list[_Seen] = field(default_factory=list)

    def __call__(self, result: StepResult) -> None:
        for vid, ego in result.vehicles.items():
            keyed = [(key, s) for key, s in zip([None, *ego.possible], ego.sources, strict=True)
                     if not s.region.is_empty]  # sources: the unobserved area, then by key
            self.seen.append(_Seen(
                result.step, vid, ego.picture.front_s, ego.picture.zones,
                tuple(s.region.geometry() for _, s in keyed),
                tuple(None if s.path is None or s.path.is_empty else s.path.geometry()
                      for _, s in keyed),
                ego.estimate.flags.inconsistent, tuple(key for key, _ in keyed),
                result.snapshot.signals, result.snapshot.time))


@dataclass(frozen=True)
class ZoneStep:
    """One zone at one step of one vehicle: the controller's arrival and the reference's (s)."""

    vehicle: str
    step: int
    zone: int
    controller_s: float
    reference_s: float


class ExactArrivals:
    """The reference's arrivals for one automated vehicle of a run (module docstring)."""

    def __init__(self, context: SceneContext, roadmap: RoadMap, speed_mps: float,
                 jitter_m: float, dt: float, radius_m: float, labelled: bool) -> None:
        self.context = context
        self.v, self.eps, self.dt = speed_mps, jitter_m, dt
        self.beyond = shapely.difference(roadmap.walkable, context.window.geometry())
        self._whole = {i: self._beyond_s(z.ground) for i, z in enumerate(context.zones)}
        self._last: tuple[int, dict[int, float]] | None = None
        areas = {c.id: c.area for c in roadmap.crossings}
        reach = radius_m + AREA_TOL_M  # how far a walker on a crossing may lie off its area
        self.lit = [_Lit(c.lights, c.own, areas[c.id].buffer(reach)) for c in context.lit]
        self.labelled = labelled  # a key is one pedestrian: its sightings at red count
        self._off_until: dict[tuple[str, int], float] = {}

    def _beyond_s(self, ground: shapely.Geometry) -> float:
        if self.beyond.is_empty or ground.is_empty:
            return math.inf
        return max(0.0, float(shapely.distance(self.beyond, ground)) - 2.0 * self.eps) / self.v

    def _beyond_at(self, zone: ZoneOutlook, front_s: float) -> float:
        """The arrival from beyond the window at ``zone``'s ground as far as the body (front
        at ``front_s``) can touch it: the whole zone's until the front reaches it."""
        whole = self.context.zones[zone.index]
        return self._whole[zone.index] if front_s <= whole.start_m \
            else self._beyond_s(zone.ground)

    def arrivals(self, seen: _Seen) -> dict[int, float]:
        """Zone index -> the reference's earliest arrival (s) at ``seen``'s step."""
        releases = [lit.lights.release_s(seen.signals) for lit in self.lit]
        self._sightings(seen, releases)
        sets = self._from_sources(seen, np.array([z.ground for z in seen.zones], dtype=object))
        out: dict[int, float] = {}
        for zone, arrival in zip(seen.zones, sets, strict=True):
            held = [i for i in self.context.zones[zone.index].lit if releases[i] > 0.0]
            out[zone.index] = self._held(seen, zone, held, releases) if held else \
                min(self._beyond_at(zone, seen.front_s), float(arrival))
        floors = {} if seen.inconsistent or self._last is None else {
            i: a - (seen.step - self._last[0]) * self.dt for i, a in self._last[1].items()}
        out = {i: max(a, floors.get(i, 0.0)) for i, a in out.items()}
        self._last = None if seen.inconsistent else (seen.step, out)
        return out

    def _sightings(self, seen: _Seen, releases: Sequence[float]) -> None:
        """Keep, per pedestrian and lit crossing, until when it is known off the crossing: seen
        with its region off the crossing's area while the light held (labelled runs; a step
        whose picture is inconsistent forgets them all)."""
        if seen.inconsistent or not self.labelled:
            self._off_until = {}
            return
        for key, position in zip(seen.keys, seen.positions, strict=True):
            for i, (lit, release) in enumerate(zip(self.lit, releases, strict=True)):
                if key is not None and release > 0.0 and \
                        not shapely.intersects(position, lit.near):
                    self._off_until[(key, i)] = max(self._off_until.get((key, i), 0.0),
                                                    seen.time_s + release)

    def _held(self, seen: _Seen, zone: ZoneOutlook, held: Sequence[int],
              releases: Sequence[float]) -> float:
        """The arrival at a zone on the own ground of crossings whose lights hold their
        walkers (``held``): the rest of its ground as usual; each crossing's part no sooner
        than the release from where a walker off the crossing may be."""
        ground = zone.ground
        rest = shapely.difference(ground, shapely.union_all([self.lit[i].own for i in held]))
        best = math.inf
        if rest.area > 0.0:
            best = min(self._beyond_s(rest), float(self._from_sources(
                seen, np.array([rest], dtype=object))[0]))
        for i in held:
            piece = shapely.intersection(ground, self.lit[i].own)
            if piece.area <= 0.0:
                continue
            beyond = self._beyond_s(piece)
            if not shapely.intersects(self.beyond, self.lit[i].near):
                beyond = max(beyond, releases[i])
            best = min(best, beyond, self._held_piece(seen, piece, i, releases[i]))
        return best

    def _held_piece(self, seen: _Seen, piece: shapely.Geometry, i: int,
                    release: float) -> float:
        """The least over the sources of each one's arrival at ``piece`` (on held crossing
        ``i``'s own ground)."""
        best = math.inf
        target = np.array([piece], dtype=object)
        for key, position, path in zip(seen.keys, seen.positions, seen.paths, strict=True):
            one = _Seen(seen.step, seen.vehicle, seen.front_s, (), (position,), (path,), False)
            usual = float(self._from_sources(one, target)[0])
            until = self._off_until.get((key, i), seen.time_s) if key is not None \
                else seen.time_s
            if until > seen.time_s:
                best = min(best, max(usual, release, until - seen.time_s))
                continue
            near = shapely.intersection(position, self.lit[i].near)
            off = shapely.difference(position, self.lit[i].near)
            best = min(best, max(usual, min(self._position_s(near, piece),
                                            max(release, self._position_s(off, piece)))))
        return best

    def _position_s(self, region: shapely.Geometry, ground: shapely.Geometry) -> float:
        """The arrival at ``ground`` from a position region (inf from an empty one)."""
        if region.is_empty:
            return math.inf
        return max(0.0, float(shapely.distance(region, ground)) - 2.0 * self.eps) / self.v

    def _from_sources(self, seen: _Seen, grounds: np.ndarray) -> np.ndarray:
        """The least over the sources of each one's arrival at each zone, shape (z,)."""
        if not seen.positions:
            return np.full(len(grounds), math.inf)
        positions = np.array(seen.positions, dtype=object)[:, None]
        arrival = np.maximum(0.0, shapely.distance(positions, grounds) - 2.0 * self.eps)
        pathed = [i for i, p in enumerate(seen.paths) if p is not None]
        if pathed:
            paths = np.array([seen.paths[i] for i in pathed], dtype=object)[:, None]
            arrival[pathed] = np.maximum(arrival[pathed], np.maximum(
                0.0, shapely.distance(paths, grounds) - self.eps))
        return arrival.min(axis=0) / self.v


@dataclass(frozen=True)
class _Lit:
    """A signalised crossing of the route: its lights, its own ground and its area grown by
    how far a walker on it may lie off it (``near``)."""

    lights: CrossingLights
    own: shapely.Geometry
    near: shapely.Geometry


def compare(recorder: ArrivalRecorder, info: SimulationInfo) -> list[ZoneStep]:
    """Every zone-step of a run: the controller's arrival beside the reference's."""
    scenario = info.scenario
    config = scenario.estimator
    if motion_model(config, scenario.simulation.step_length_s).uses_state:
        raise ValueError(f"estimator.state_model = {config.state_model!r} reads the state set; "
                         "the reference bounds the speed alone")
    references = {vid: ExactArrivals(_context(scenario, info, vid), info.roadmap,
                                     config.max_pedestrian_speed_mps, config.position_jitter_m,
                                     scenario.simulation.step_length_s,
                                     scenario.pedestrian_radius_m(),
                                     config.association == "labelled")
                  for vid in present(scenario.automated)}
    rows = []
    for seen in recorder.seen:
        reference = references[seen.vehicle].arrivals(seen)
        rows += [ZoneStep(seen.vehicle, seen.step, z.index, z.arrival_s, reference[z.index])
                 for z in seen.zones]
    return rows


def _context(scenario: Scenario, info: SimulationInfo, vid: str) -> SceneContext:
    """The scene as vehicle ``vid``'s controller had it (its zones and window)."""
    dt = scenario.simulation.step_length_s
    vehicle = scenario.automated[vid]
    return SceneContext.build(info.roadmap, vehicle.route_edges, vehicle, scenario.controller,
                              motion_model(scenario.estimator, dt),
                              scenario.pedestrian_radius_m(), dt,
                              region_kind(scenario.estimator.regions))


def run(path: str, overrides: Mapping[str, Any] | None = None) -> tuple[list[ZoneStep], dict]:
    """Run the scenario file ``path`` (with ``overrides``) once, recording its arrivals: every
    zone-step and the run's summary."""
    scenario = load_scenario(Path(path), dict(overrides or {}))
    recorder, arrivals = RunRecorder(scenario), ArrivalRecorder()

    def on_step(result: StepResult) -> None:
        recorder(result)
        arrivals(result)

    with tempfile.TemporaryDirectory(prefix="sse-bench-arrivals-") as tmp:
        info = simulate(scenario, Path(tmp), Path(path).stem, on_step,
                        on_start=recorder.start)
    return compare(arrivals, info), recorder.summary()


def figures(rows: Sequence[ZoneStep]) -> dict[str, Any]:
    """Soundness and tightness of some zone-steps: how many, how many later than the
    reference (and the latest by how much), and the ratio of the means, over every finite
    zone-step and over those the decisions turn on (:data:`DECISION_HORIZON_S`)."""
    both = [r for r in rows if math.isfinite(r.reference_s) and math.isfinite(r.controller_s)]
    near = [r for r in both if r.reference_s <= DECISION_HORIZON_S]
    late = [r for r in rows if r.controller_s > r.reference_s + TOLERANCE_S]
    return {
        "zone_steps": len(rows),
        "finite": len(both),
        "later_than_reference": len(late),
        "latest_excess_s": max((r.controller_s - r.reference_s for r in late), default=0.0),
        "ratio_of_means": _ratio(both),
        "ratio_of_means_within_horizon": _ratio(near),
        "within_horizon": len(near),
        "earliest_shortfall_s": max((r.reference_s - r.controller_s for r in both),
                                    default=0.0),
    }


def _ratio(rows: Sequence[ZoneStep]) -> float | None:
    total = sum(r.reference_s for r in rows)
    return None if total <= 0.0 else sum(r.controller_s for r in rows) / total


def run_all(paths: Sequence[str] = SCENARIOS,
            overrides: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """The benchmark's row: each scenario's figures and all of them together."""
    per_scenario, every = {}, []
    for path in paths:
        rows, summary = run(path, overrides)
        per_scenario[Path(path).stem] = {**figures(rows),
                                         "collisions": summary["collisions"],
                                         "containment_violations":
                                             summary["containment_violations"]}
        every += rows
    return {"scenarios": per_scenario, "all": figures(every)}

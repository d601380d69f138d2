"""Collects what a run produced, step by step: trace rows, sets, regions, summary figures,
scene frames.

The recorder only reads :class:`~sse_cosim.pipeline.result.StepResult`; writing files is
:mod:`sse_cosim.reporting.outputs`'s job.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from itertools import pairwise
from typing import TYPE_CHECKING, Any

import numpy as np
import shapely

from sse_cosim.control.speed import SpeedLevel
from sse_cosim.scenario.model import Scenario, present
from sse_cosim.sensors.faults import FaultLog
from sse_cosim.sets import Zonotope

if TYPE_CHECKING:  # only the type: a report that reads folders loads no estimation
    from sse_cosim.pipeline.result import StepResult

FUSED = "fused"
REFINED = "refined"  # a known pedestrian's zonotope refined with negative information
UNOBSERVED = "unobserved"  # walkable ground where an undetected pedestrian may be
STOPPED_SPEED_MPS = 0.1  # the bus counts as stopped below this actual speed
UNACCOUNTED = "unaccounted"  # a pedestrian in no refined region and not in the unobserved area


@dataclass(frozen=True)
class RegionRecord:
    """One region the controller used at one step: a known pedestrian's refined region
    (``track`` its id) or the unobserved area (``track`` None)."""

    time: float
    kind: str  # REFINED or UNOBSERVED
    track: str | None
    region: shapely.Geometry


@dataclass(frozen=True)
class SceneFrame:
    """What a scene plot at one time needs (position sets, geometries)."""

    time: float
    footprints: dict[str, shapely.Polygon]  # vehicle id -> footprint
    sectors: dict[str, tuple[str, shapely.Geometry, shapely.Geometry]]  # sensor -> node, vis, occ
    strips: list[tuple[str, np.ndarray, float, float]]  # (node, normal (2,), value, radius)
    local_sets: dict[str, Zonotope]  # node -> position set
    fused_set: Zonotope | None
    truth: tuple[float, float] | None
    unobserved: shapely.Geometry  # walkable area where an undetected pedestrian may be


@dataclass
class RunRecorder:
    """Callable passed to ``simulate``; keeps everything the reports need."""

    scenario: Scenario
    scene_times: tuple[float, ...] = ()
    rows: list[dict[str, Any]] = field(default_factory=list)
    set_lines: list[dict[str, Any]] = field(default_factory=list)
    regions: list[RegionRecord] = field(default_factory=list)  # serialised only when written
    scenes: list[SceneFrame] = field(default_factory=list)
    violations: list[dict[str, Any]] = field(default_factory=list)
    first_detection: dict[str, dict[str, float]] = field(default_factory=dict)
    first_shared_fusion: dict[str, Any] | None = None
    fusion_larger_than_input: int = 0  # steps where the fused set outgrew its smallest input
    flag_steps: Counter = field(default_factory=Counter)  # "<sensor or node>: <flag>" -> steps
    faults: FaultLog = field(init=False)

    def __post_init__(self) -> None:
        self.faults = FaultLog(self.scenario)

    def __call__(self, result: StepResult) -> None:
        snap = result.snapshot
        bus = snap.vehicles[result.screen.node]
        t = round(snap.time, 6)
        person = next(iter(sorted(snap.persons.items())), None)
        truth = np.asarray(person[1].position) if person else None
        person_id = person[0] if person else None
        row: dict[str, Any] = {
            "t": t,
            "bus_x": bus.footprint.front.x,
            "bus_y": bus.footprint.front.y,
            "bus_speed": bus.speed,
            "commanded_speed": result.commanded_speed,
            "level": result.level.label,
            "emergency": result.level is SpeedLevel.EMERGENCY,
            "ped_x": truth[0] if truth is not None else None,
            "ped_y": truth[1] if truth is not None else None,
        }
        local_sets: dict[str, Zonotope] = {}
        for node, tracks in result.tracks.items():
            track = tracks.get(person_id) if person_id else None
            row[f"{node}_detected"] = bool(track and track.detected)
            area = None
            if track is not None:
                position = result.model.position(track.estimate)
                local_sets[node] = position
                area = position.volume()
                self._check(t, node, position, truth)
                self._set_line(t, node, "local", position)
                if track.detected and node not in self.first_detection:
                    self.first_detection[node] = self._moment(t, result)
            row[f"{node}_area"] = area
        self._flags(row, result)
        fused = result.fused.get(person_id) if person_id else None
        fused_position = result.model.position(fused) if fused is not None else None
        row["fused_area"] = fused_position.volume() if fused_position is not None else None
        row["fused_contains_truth"] = (
            self._check(t, FUSED, fused_position, truth) if fused_position is not None else None
        )
        if fused_position is not None:
            inputs = _fusion_inputs(result, person_id)
            smallest = min(result.model.position(z).volume() for z in inputs.values())
            if fused_position.volume() > smallest * (1 + 1e-9) + 1e-12:
                self.fusion_larger_than_input += 1
            self._set_line(t, FUSED, "fused", fused_position)
            if FUSED not in self.first_detection:
                self.first_detection[FUSED] = self._moment(t, result)
            self._note_shared_fusion(t, person_id, local_sets, fused_position, result)
        region = result.possible.get(person_id) if person_id else None
        row["possible_area"] = region.area if region is not None else None
        row["possible_contains_truth"] = (
            self._check_region(t, region, truth) if region is not None else None
        )
        self._note_regions(t, result)
        row["accounted_for"] = self._check_accounted(t, result, truth)
        row["path_clear"] = result.picture.path_clear
        row["unresolved_occluded_m2"] = result.picture.unresolved_occluded_m2
        row["own_occluded_m2"] = result.picture.own_occluded_m2
        row["distance_to_crossing"] = result.picture.distance_to_crossing
        distance = _distance(bus.footprint.polygon(), truth)
        row["distance_bus_pedestrian"] = distance
        row["collision"] = bool(
            distance is not None and distance <= self.scenario.pedestrians[person_id].radius_m
        )
        self.rows.append(row)
        if self._wants_scene(t):
            self.scenes.append(_frame(t, result, local_sets, fused_position, truth))

    def _flags(self, row: dict[str, Any], result: StepResult) -> None:
        """Flag columns (per sensor: left out; per node: excluded/conflict), fault bookkeeping."""
        flags = result.flags
        for sensor, flagged in flags.sensors.items():
            row[f"{sensor}_flag"] = flagged
            self.flag_steps[f"{sensor}: left out"] += flagged
        for node, flag in flags.nodes.items():
            row[f"{node}_flag"] = flag
            self.flag_steps[f"{node}: {flag}"] += bool(flag)
        row["inconsistent"] = flags.inconsistent
        self.faults.update(result.step, round(result.snapshot.time, 6), result.faults,
                           flags.sensors, flags.nodes, result.shared.ages)

    def _check(self, t: float, node: str, position: Zonotope, truth) -> bool | None:
        if truth is None:
            return None
        inside = bool(position.contains(truth, tol=1e-7))
        if not inside:
            self.violations.append({"t": t, "node": node, "truth": truth.tolist()})
        return inside

    def _check_region(self, t: float, region: shapely.Geometry, truth) -> bool | None:
        if truth is None:
            return None
        inside = bool(shapely.distance(region, shapely.Point(truth)) <= 1e-7)
        if not inside:
            self.violations.append({"t": t, "node": "possible", "truth": truth.tolist()})
        return inside

    def _check_accounted(self, t: float, result: StepResult, truth) -> bool | None:
        """Whether the pedestrian is where the controller looks for pedestrians: inside a
        refined region (any track's) or the unobserved area, or outside the window where
        hidden ground is tracked (there every walkable place counts as occupied)."""
        if truth is None:
            return None
        point = shapely.Point(truth)
        inside = not result.window.contains(point) or any(
            shapely.distance(region, point) <= 1e-7
            for region in [result.unobserved, *result.possible.values()])
        if not inside:
            self.violations.append({"t": t, "node": UNACCOUNTED, "truth": truth.tolist()})
        return inside

    def _note_regions(self, t: float, result: StepResult) -> None:
        """Keep the regions the controller used this step: every known pedestrian's refined
        region (by id) and the unobserved area, so that anyone can re-check them."""
        self.regions.extend(RegionRecord(t, REFINED, pid, region)
                            for pid, region in sorted(result.possible.items()))
        self.regions.append(RegionRecord(t, UNOBSERVED, None, result.unobserved))

    def _set_line(self, t: float, node: str, kind: str, position: Zonotope) -> None:
        self.set_lines.append({"t": t, "node": node, "kind": kind, **position.to_json()})

    @staticmethod
    def _moment(t: float, result: StepResult) -> dict[str, float]:
        return {"t": t, "bus_distance_to_crossing_m": result.picture.distance_to_crossing}

    def _note_shared_fusion(self, t, person_id, local_sets, fused_position, result) -> None:
        """Record the first step at which the bus fuses two or more sets (paper Fig. 7)."""
        if self.first_shared_fusion is not None:
            return
        inputs = _fusion_inputs(result, person_id)
        if len(inputs) < 2:
            return
        self.first_shared_fusion = {
            "t": t,
            "input_areas_m2": {n: result.model.position(z).volume() for n, z in inputs.items()},
            "fused_area_m2": fused_position.volume(),
        }
        self.scenes.append(_frame(t, result, local_sets, fused_position, None))

    def _wants_scene(self, t: float) -> bool:
        dt = self.scenario.simulation.step_length_s
        return any(abs(t - s) < 0.5 * dt for s in self.scene_times)

    def summary(self, route_completed: bool | None = None) -> dict[str, Any]:
        """The run's figures (``summary.json``).

        ``route_completed`` is whether the bus reached the end of its route, which only the
        simulation knows (the recorder sees no step after the bus left); None: not known.
        Rows start once the bus is in the network, so times count from its departure.
        """
        dt = self.scenario.simulation.step_length_s
        contact = [r["collision"] for r in self.rows]
        speeds = np.array([r["bus_speed"] for r in self.rows]) if self.rows else np.zeros(0)
        levels = Counter(r["level"] for r in self.rows)
        distances = [r["distance_bus_pedestrian"] for r in self.rows
                     if r["distance_bus_pedestrian"] is not None]
        return {
            "scenario": self.scenario.name,
            "pedestrian": bool(present(self.scenario.pedestrians)),
            "nodes": self.scenario.node_ids(),
            "steps": len(self.rows),
            "average_speed_mps": float(speeds.mean()) if speeds.size else None,
            "travel_time_s": len(self.rows) * dt,
            "distance_travelled_m": float(speeds.sum() * dt),
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
            "collisions": _entries(contact),
            "contact_steps": sum(contact),
            "route_completed": route_completed,
            "time_stopped_s": round(dt * int(np.sum(speeds < STOPPED_SPEED_MPS)), 6),
            "longest_standstill_after_clear_s": round(dt * _longest_run(
                [r["path_clear"] and r["bus_speed"] < STOPPED_SPEED_MPS for r in self.rows]), 6),
            "level_share": {
                level.label: levels.get(level.label, 0) / max(len(self.rows), 1)
                for level in SpeedLevel
            },
        }

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


def _fusion_inputs(result: StepResult, person_id: str) -> dict[str, Zonotope]:
    """The state sets the bus fused for ``person_id``: its own and the received ones that
    passed the consistency screen."""
    own = result.tracks[result.screen.node].get(person_id)
    return result.screen.inputs(person_id, None if own is None else own.estimate)


def _entries(flags: list[bool]) -> int:
    """How many times ``flags`` turns true (a first step in contact counts): one collision
    lasts several steps, and the campaign counts collisions, not steps."""
    return sum(now and not before for before, now in pairwise([False, *flags]))


def _distance(footprint: shapely.Polygon, truth) -> float | None:
    return None if truth is None else float(footprint.distance(shapely.Point(truth)))


def _frame(t, result, local_sets, fused_position, truth) -> SceneFrame:
    snap = result.snapshot
    if truth is None and snap.persons:
        truth = np.asarray(next(iter(sorted(snap.persons.items())))[1].position)
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
        footprints={v.id: v.footprint.polygon() for v in snap.vehicles.values()},
        sectors={name: (o.node, o.visible, o.occluded)
                 for name, o in result.observations.items() if o.pose is not None},
        strips=strips,
        local_sets=dict(local_sets),
        fused_set=fused_position,
        truth=None if truth is None else (float(truth[0]), float(truth[1])),
        unobserved=result.unobserved,
    )


def _longest_run(flags: list[bool]) -> int:
    """The most consecutive True values in ``flags``."""
    longest = current = 0
    for flag in flags:
        current = current + 1 if flag else 0
        longest = max(longest, current)
    return longest

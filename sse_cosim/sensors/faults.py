"""Fault injection: what a scenario's ``[faults]`` make sensors, nodes and V2X links do wrong.

The injector sits between the simulated truth and the estimation, so the estimators see only
the faulty outputs; it also reports, for bookkeeping, whether each fault is active and whether
its output broke the bounds this step (a strip or an estimate that excludes the truth) --
never used by the estimation, only by the recorder (:class:`FaultLog`).

- Sensor faults change one sensor's observation from ``start_s`` to ``end_s``, whatever its
  kind (they act on strips): ``bias`` adds an offset along the strips' normals to every
  measurement, i.e. a camera's forward and lateral axes, a range sensor's measured bearing
  and across it (``within_bound``: the error is clipped to the strips' half-widths, so they
  still hold the truth); ``stuck`` repeats the detections of the fault's first step;
  ``dropout`` loses whole frames (no detection, nothing seen) with a seeded probability;
  ``phantom`` reports a pedestrian that is not there, on a straight track, measured by the
  sensor's own kind.
- Node faults change the estimates a connected node sends: ``shift`` moves them, ``shrink``
  scales their generators (an over-confident or spoofed sender).
- Link faults: ``loss`` drops every message sent in the window, ``latency`` delays them.

Faults draw from their own generator (the scenario seed's third stream), so the healthy
sensors measure exactly what they measure without faults.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from sse_cosim.regions import RegionKind
from sse_cosim.scenario.model import FaultWindow, LinkFault, NodeFault, Scenario, SensorFault
from sse_cosim.sensors.measurement import Detection
from sse_cosim.sensors.observe import SensorObservation
from sse_cosim.sensors.spec import SensorSpec
from sse_cosim.sets import Strips, Zonotope, portable
from sse_cosim.world.snapshot import Snapshot

if TYPE_CHECKING:  # node faults act on estimates; the sensor layer does not import estimation
    from sse_cosim.estimation.motion import MotionModel

TIME_TOL = 1e-6  # s: a window's ends are compared with step times up to rounding


@dataclass(frozen=True)
class FaultStatus:
    """One fault at one step: ``active`` in its window, ``beyond_bounds`` if its output this
    step excluded the truth (a strip or an estimate that misses the true position)."""

    active: bool = False
    beyond_bounds: bool = False


def is_active(window: FaultWindow, time: float) -> bool:
    """Whether ``time`` (s) lies in the fault's window [start_s, end_s)."""
    started = time >= window.start_s - TIME_TOL
    return started and (window.end_s is None or time < window.end_s - TIME_TOL)


def fault_keys(scenario: Scenario) -> dict[str, SensorFault | NodeFault | LinkFault]:
    """Every fault of the scenario under its report key ``<table>.<name>``."""
    tables = {"sensor": scenario.faults.sensor, "node": scenario.faults.node,
              "link": scenario.faults.link}
    return {f"{table}.{name}": fault for table, faults in tables.items()
            for name, fault in sorted(faults.items())}


class FaultInjector:
    """Applies a scenario's faults step by step; :meth:`statuses` reports what they did."""

    def __init__(self, scenario: Scenario, specs: Mapping[str, SensorSpec],
                 rng: np.random.Generator) -> None:
        self.specs = specs
        self.rng = rng
        self.faults = fault_keys(scenario)
        self._frozen: dict[str, dict[str, Detection]] = {}  # stuck fault -> its detections
        self._status: dict[str, FaultStatus] = {}

    def begin_step(self, time: float) -> None:
        """Start bookkeeping a step at ``time`` (s): which faults are active."""
        self._status = {key: FaultStatus(is_active(f, time)) for key, f in self.faults.items()}

    def statuses(self) -> dict[str, FaultStatus]:
        """What every fault did at the current step."""
        return dict(self._status)

    def _active(self, kind: type) -> list[tuple[str, Any]]:
        return [(k, f) for k, f in self.faults.items()
                if isinstance(f, kind) and self._status.get(k, FaultStatus()).active]

    def _mark(self, key: str, beyond: bool) -> None:
        if beyond:
            self._status[key] = FaultStatus(True, True)

    # --- sensors --------------------------------------------------------------------------

    def corrupt_observations(
        self, snapshot: Snapshot, observations: dict[str, SensorObservation],
        kind: RegionKind | None = None,
    ) -> dict[str, SensorObservation]:
        """The observations as the faulty sensors report them (same order; their regions of
        ``kind``, None when regions were not requested)."""
        active = self._active(SensorFault)
        if not active:
            return observations
        truth = {pid: np.asarray(p.position, dtype=float) for pid, p in snapshot.persons.items()}
        result = dict(observations)
        for key, fault in active:
            obs = result[fault.sensor]
            if obs.pose is None:  # its carrier is not in the scene: nothing to corrupt
                continue
            result[fault.sensor] = self._corrupt(key, fault, obs, snapshot.time, truth, kind)
        return result

    def _corrupt(self, key: str, fault: SensorFault, obs: SensorObservation, time: float,
                 truth: Mapping[str, np.ndarray], kind: RegionKind | None) -> SensorObservation:
        spec = self.specs[fault.sensor]
        if fault.kind == "dropout":
            if self.rng.random() >= fault.dropout_probability:
                return obs
            if kind is None:
                return replace(obs, detections={})
            # a lost frame hides the whole sector
            return replace(obs, detections={}, visible=kind.empty(),
                           occluded=kind.union_all([obs.visible, obs.occluded]))
        if fault.kind == "bias":
            detections = {pid: _biased(d, fault, truth.get(pid))
                          for pid, d in obs.detections.items()}
        elif fault.kind == "stuck":
            frozen = self._frozen.setdefault(key, dict(obs.detections))
            detections = {pid: replace(d, time=time) for pid, d in frozen.items()}
        else:  # phantom
            velocity = np.asarray(fault.phantom_velocity_mps)
            where = np.asarray(fault.phantom_xy_m) + (time - fault.start_s) * velocity
            strips = spec.kind.measure(obs.pose, where[np.newaxis, :], self.rng)[0]
            ghost = Detection(fault.sensor, obs.node, time, fault.phantom_id, strips)
            detections = {**obs.detections, fault.phantom_id: ghost}
        self._mark(key, any(pid not in truth or not d.strips.contains(truth[pid])
                            for pid, d in detections.items()))
        return replace(obs, detections=detections)

    # --- connected nodes and links ---------------------------------------------------------

    def corrupt_estimates(
        self, node: str, estimates: dict[str, Zonotope], snapshot: Snapshot, model: MotionModel
    ) -> dict[str, Zonotope]:
        """The estimates ``node`` sends (by pedestrian id), as its faults distort them."""
        for key, fault in self._active(NodeFault):
            if fault.node != node:
                continue
            if fault.kind == "shift":
                offset = portable.matmul(model.position_matrix.T, np.asarray(fault.shift_m))
                estimates = {pid: z.translate(offset) for pid, z in estimates.items()}
            else:
                estimates = {pid: Zonotope(z.center, fault.scale * z.generators)
                             for pid, z in estimates.items()}
            self._mark(key, any(
                pid in snapshot.persons
                and not model.position(z).contains(snapshot.persons[pid].position, tol=1e-7)
                for pid, z in estimates.items()))
        return estimates

    def link_lost(self, node: str) -> bool:
        """Whether ``node``'s message sent now is lost by a loss burst."""
        return any(f.node == node and f.kind == "loss" for _, f in self._active(LinkFault))

    def extra_latency(self, node: str) -> int:
        """Steps added to the delivery of ``node``'s message sent now."""
        return sum(f.extra_latency_steps for _, f in self._active(LinkFault)
                   if f.node == node and f.kind == "latency")


def _biased(detection: Detection, fault: SensorFault, truth: np.ndarray | None) -> Detection:
    """The detection offset by the fault's bias (clipped to the bound if ``within_bound``)."""
    strips = detection.strips
    values = strips.values + np.asarray(fault.bias_m)
    if fault.within_bound and truth is not None:
        exact = portable.matmul(strips.normals, truth)
        values = exact + np.clip(values - exact, -strips.radii, strips.radii)
    return replace(detection, strips=Strips(strips.normals, values, strips.radii))


# --- bookkeeping: when was each fault detected? --------------------------------------------


@dataclass
class FaultRecord:
    """One injected fault over a run (``summary.json``: ``faults``)."""

    key: str
    target: str  # "sensor <name> on <node>", "node <id>", "link <id>"
    kind: str
    start_s: float
    end_s: float | None
    first_active_step: int | None = None
    first_beyond_bounds_step: int | None = None
    detected_step: int | None = None
    detected_t: float | None = None
    flagged_steps: int = 0

    def to_json(self) -> dict[str, Any]:
        delay = None if self.detected_step is None or self.first_active_step is None \
            else self.detected_step - self.first_active_step
        after = None if self.detected_step is None or self.first_beyond_bounds_step is None \
            else self.detected_step - self.first_beyond_bounds_step
        return {
            "fault": self.key, "target": self.target, "kind": self.kind,
            "start_s": self.start_s, "end_s": self.end_s,
            "first_active_step": self.first_active_step,
            "first_beyond_bounds_step": self.first_beyond_bounds_step,
            "detected_step": self.detected_step, "detected_t": self.detected_t,
            "detection_delay_steps": delay,
            "delay_after_beyond_bounds_steps": after,
            "flagged_steps": self.flagged_steps,
        }


@dataclass
class FaultLog:
    """Per fault: first active step, first step beyond the bounds, first step it was noticed.

    A sensor fault is noticed when its sensor is flagged or its node is flagged; a node
    fault when its node is flagged (the bus left its estimate out, or a conflict); a link
    fault when the bus sees the sender's newest message older than the link's latency.
    Only steps in the fault's window count.
    """

    scenario: Scenario
    records: dict[str, FaultRecord] = field(default_factory=dict)
    faults: dict[str, SensorFault | NodeFault | LinkFault] = field(init=False)

    def __post_init__(self) -> None:
        self.faults = fault_keys(self.scenario)
        for key, fault in self.faults.items():
            if isinstance(fault, SensorFault):
                node = self.scenario.sensors[fault.sensor].node
                target = f"sensor {fault.sensor} on {node}"
            else:
                target = f"{'node' if isinstance(fault, NodeFault) else 'link'} {fault.node}"
            self.records[key] = FaultRecord(key, target, fault.kind, fault.start_s, fault.end_s)

    def update(self, step: int, time: float, statuses: Mapping[str, FaultStatus],
               sensor_flags: Mapping[str, bool], node_flags: Mapping[str, str],
               ages: Mapping[str, int]) -> None:
        """Note one step: fault statuses, flags, and the age of every sender's newest message."""
        for key, fault in self.faults.items():
            status = statuses.get(key, FaultStatus())
            if not status.active:
                continue
            record = self.records[key]
            if record.first_active_step is None:
                record.first_active_step = step
            if status.beyond_bounds and record.first_beyond_bounds_step is None:
                record.first_beyond_bounds_step = step
            if self._noticed(fault, sensor_flags, node_flags, ages):
                record.flagged_steps += 1
                if record.detected_step is None:
                    record.detected_step, record.detected_t = step, time

    def _noticed(self, fault: SensorFault | NodeFault | LinkFault,
                 sensor_flags: Mapping[str, bool], node_flags: Mapping[str, str],
                 ages: Mapping[str, int]) -> bool:
        """Whether what the bus and the nodes flag this step points at ``fault``'s target."""
        if isinstance(fault, SensorFault):
            node = self.scenario.sensors[fault.sensor].node
            return sensor_flags.get(fault.sensor, False) or bool(node_flags.get(node))
        if isinstance(fault, NodeFault):
            return bool(node_flags.get(fault.node))
        return ages.get(fault.node, 0) > self.scenario.v2x.latency_steps

    def summary(self) -> list[dict[str, Any]]:
        return [record.to_json() for record in self.records.values()]

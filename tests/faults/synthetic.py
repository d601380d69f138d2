"""A SUMO-free estimation loop for the fault tests (imported as ``synthetic``).

A pedestrian follows p = s + e (a path s moving at most ``speed * DT`` per step, plus a jitter
of norm at most ``jitter``, often at full size); nodes with one or more sensors at random
poses measure it with bounded noise (uniform or on the bound); every node other than the bus
sends its estimate over a lossless V2X link, which delivers it ``latency`` steps later; the bus
also gets "clear" regions (boxes that provably miss the pedestrian when they were seen) for
negative information. Hooks corrupt a sensor's strips or a sender's estimate to inject faults.
The nodes' observers, the link and the bus's screen, fusion and flags are the co-simulation's
own (:class:`~sse_cosim.estimation.fusion_centre.FusionCentre`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import shapely

from sse_cosim.estimation.bus_screen import BusScreen
from sse_cosim.estimation.flags import StepFlags, disagrees
from sse_cosim.estimation.fusion_centre import FusionCentre
from sse_cosim.estimation.motion import MotionModel, motion_model
from sse_cosim.estimation.observer import LocalObservers, Track
from sse_cosim.estimation.occupancy import ClearRegion
from sse_cosim.estimation.settings import EstimatorSettings
from sse_cosim.estimation.v2x import Message, V2XLink
from sse_cosim.regions import PolygonRegion as R
from sse_cosim.regions import kind
from sse_cosim.scenario.model import V2X, Estimator
from sse_cosim.sets import Strips, Zonotope

K = kind("polygon")

BUS = "bus"  # the automated vehicle's id (its node)

DT = 0.1
PED = "ped"
StripHook = Callable[[int, str, Strips, np.ndarray], Strips | None]  # step, sensor, strips, p
EstimateHook = Callable[[int, str, Zonotope], Zonotope]  # step, sender, estimate


def trajectory(rng: np.random.Generator, steps: int, speed: float, jitter: float
               ) -> tuple[np.ndarray, np.ndarray]:
    """(p, s), each (steps, 2): the jittered positions and the admissible path."""
    path = np.zeros((steps, 2))
    heading = rng.uniform(0, 2 * np.pi)
    for k in range(1, steps):
        heading += rng.normal(0, 0.6)
        step = rng.uniform(0.5, 1.0) * speed * DT
        path[k] = path[k - 1] + step * np.array([np.cos(heading), np.sin(heading)])
    angles = rng.uniform(0, 2 * np.pi, steps)
    sizes = np.where(rng.random(steps) < 0.3, jitter, rng.uniform(0, jitter, steps))
    return path + sizes[:, None] * np.column_stack([np.cos(angles), np.sin(angles)]), path


def axes(angle: float) -> np.ndarray:
    """H: a sensor's forward and lateral unit axes as rows."""
    return np.array([[np.cos(angle), np.sin(angle)], [-np.sin(angle), np.cos(angle)]])


@dataclass(frozen=True)
class SensorSetup:
    node: str
    angle: float
    bound: float


@dataclass
class StepRecord:
    """What the bus had at one step."""

    step: int
    truth: np.ndarray
    tracks: dict[str, dict[str, Track]]
    screen: BusScreen
    fused: dict[str, Zonotope]
    flags: StepFlags


@dataclass
class Harness:
    """The loop; ``sensors`` by name. Every node sees the pedestrian at every step."""

    sensors: dict[str, SensorSetup]
    seed: int = 0
    latency: int = 1
    worst_case: bool = False
    jitter: float = 0.3
    speed: float = 2.5
    gain: str = "frobenius"
    clear_regions: bool = True
    strip_hook: StripHook | None = None
    estimate_hook: EstimateHook | None = None
    model: MotionModel = field(init=False)

    def __post_init__(self) -> None:
        config = Estimator(max_pedestrian_speed_mps=self.speed, position_jitter_m=self.jitter,
                           gain_method=self.gain)
        self.model = motion_model(config, DT)

    def run(self, steps: int) -> list[StepRecord]:
        rng = np.random.default_rng(self.seed)
        truth, _ = trajectory(rng, steps, self.speed, self.jitter)
        settings = EstimatorSettings(self.gain, "girard", 8)
        nodes = sorted({s.node for s in self.sensors.values()} | {BUS})
        observers = LocalObservers.labelled(nodes, self.model, settings)
        link = V2XLink(V2X(latency_steps=self.latency), np.random.default_rng(0))
        centre = FusionCentre(self.model, settings, "strips", self.sensors, BUS, K)
        records = []
        for k, p in enumerate(truth):
            detections = self._detections(rng, k, p)
            tracks = observers.step(k, detections)
            for node in nodes:
                if node != BUS and PED in tracks[node]:
                    link.send(self._message(k, node, tracks[node], detections.get(node, {})), 0.0)
            link.deliver(k)
            shared = link.picture(k, self.model)
            clear = self._clear(rng, truth, k) if self.clear_regions else []
            detected = frozenset({PED}) if any(PED in d for d in detections.values()) \
                else frozenset()
            estimate = centre.step(tracks, shared, {PED: clear}, detected)
            records.append(StepRecord(k, p, tracks, estimate.screen, estimate.fused,
                                      estimate.flags))
        return records

    def _message(self, k: int, node: str, tracks: dict[str, Track], seen: dict) -> Message:
        """What ``node`` sends at step ``k``: its estimate, as the estimate hook distorts it."""
        estimate = tracks[PED].estimate
        if self.estimate_hook is not None:
            estimate = self.estimate_hook(k, node, estimate)
        return Message(node, k, {PED: estimate}, K.empty(), frozenset(seen),
                       disagrees(tracks.values()))

    def _detections(self, rng, k: int, p: np.ndarray) -> dict[str, dict[str, dict]]:
        result: dict[str, dict[str, dict]] = {}
        for name, setup in self.sensors.items():
            h = axes(setup.angle)
            noise = (rng.choice([-1.0, 1.0], 2) if self.worst_case
                     else rng.uniform(-1.0, 1.0, 2)) * setup.bound
            strips = Strips(h, h @ p + noise, np.full(2, setup.bound))
            if self.strip_hook is not None:
                strips = self.strip_hook(k, name, strips, p)
            if strips is not None:
                result.setdefault(setup.node, {}).setdefault(PED, {})[name] = strips
        return result

    def _clear(self, rng, truth: np.ndarray, k: int) -> list[ClearRegion]:
        """Boxes seen now (by the bus) and ``latency`` steps ago (by a sender) that miss the
        pedestrian at that time, some of them only just."""
        regions = []
        for age in {0, self.latency}:
            if k - age < 0:
                continue
            where = truth[k - age]
            direction = rng.normal(size=2)
            direction /= np.linalg.norm(direction)
            gap = rng.choice([1e-3, rng.uniform(0.01, 2.0)])
            size = rng.uniform(2.0, 15.0)
            near = where + direction * (gap + size / 2 * np.sqrt(2))
            box = shapely.box(*(near - size / 2), *(near + size / 2))
            assert not box.covers(shapely.Point(where))
            regions.append(ClearRegion(R(box), age))
        return regions


def contains(model: MotionModel, estimate: Zonotope, point: np.ndarray) -> bool:
    """Whether the position set of ``estimate`` (jitter included) holds ``point``."""
    return bool(model.position(estimate).contains(point, tol=1e-7))

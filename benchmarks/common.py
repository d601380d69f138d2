"""Shared pieces of the benchmarks: the machine, medians, an independent containment LP, and a
plain replay of the estimator on recorded (or synthetic) measurement streams."""

from __future__ import annotations

import os
import platform
import statistics
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import linprog

from sse_cosim.estimation.bus_fusion import fuse_sets
from sse_cosim.estimation.motion import MotionModel
from sse_cosim.estimation.observer import NodeObserver
from sse_cosim.estimation.settings import EstimatorSettings
from sse_cosim.sets import Strips, Zonotope

CONTAINMENT_TOL = 1e-7


def machine() -> dict[str, object]:
    """CPU model, cores, Python, SUMO and the numeric libraries' versions."""
    import cvxpy
    import numpy
    import scipy
    import shapely

    from sse_cosim.world.sumo import sumo_version

    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as handle:
            for line in handle:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return {
        "cpu": cpu,
        "cores": cores,
        "python": platform.python_version(),
        "platform": platform.platform(),
        "sumo": sumo_version(),
        "numpy": numpy.__version__,
        "scipy": scipy.__version__,
        "shapely": shapely.__version__,
        "cvxpy": cvxpy.__version__,
        "load_average_at_start": list(os.getloadavg()) if hasattr(os, "getloadavg") else None,
    }


def median(values: Sequence[float]) -> float:
    return float(statistics.median(values))


def time_calls(call: Callable[[], object], number: int, repeats: int) -> float:
    """Median over ``repeats`` of the mean seconds per call of ``number`` calls."""
    samples = []
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(number):
            call()
        samples.append((time.perf_counter() - start) / number)
    return median(samples)


def contains_lp(center: np.ndarray, generators: np.ndarray, point: np.ndarray,
                tol: float = CONTAINMENT_TOL) -> bool:
    """Whether ``point`` ∈ ⟨c, G⟩: ∃ β with |β|∞ <= 1 + tol and Gβ = x - c (scipy HiGHS).

    Independent of the estimator's code path (``Zonotope.contains`` uses facet normals).
    """
    g = np.asarray(generators, dtype=float)
    e = g.shape[1]
    offset = np.asarray(point, dtype=float) - np.asarray(center, dtype=float)
    if e == 0:
        return bool(np.all(np.abs(offset) <= tol))
    result = linprog(np.zeros(e), A_eq=g, b_eq=offset, bounds=[(-1 - tol, 1 + tol)] * e,
                     method="highs")
    return result.status == 0


def contains_lp_batch(checks: Sequence[tuple[np.ndarray, np.ndarray, np.ndarray]],
                      tol: float = CONTAINMENT_TOL, chunk: int = 64) -> list[bool]:
    """:func:`contains_lp` for many (c, G, x) at once: one block-diagonal feasibility LP per
    ``chunk`` checks (all feasible iff the block LP is); a chunk that fails is re-checked one
    by one, so the answer per check is exact."""
    from scipy.sparse import block_diag

    answers: list[bool] = []
    for first in range(0, len(checks), chunk):
        part = checks[first:first + chunk]
        blocks = [np.asarray(g, dtype=float) for _, g, _ in part]
        offsets = np.concatenate([np.asarray(x, float) - np.asarray(c, float)
                                  for c, _, x in part])
        e = sum(b.shape[1] for b in blocks)
        if e == 0 or any(b.shape[1] == 0 for b in blocks):
            answers += [contains_lp(c, g, x, tol) for c, g, x in part]
            continue
        result = linprog(np.zeros(e), A_eq=block_diag(blocks, format="csr"), b_eq=offsets,
                         bounds=[(-1 - tol, 1 + tol)] * e, method="highs")
        if result.status == 0:
            answers += [True] * len(part)
        else:
            answers += [contains_lp(c, g, x, tol) for c, g, x in part]
    return answers


@dataclass
class StepRecord:
    """What the estimator was fed at one step of a run, and the truth.

    ``strips``: node -> pedestrian id -> the position strips of its sensors that saw it;
    ``received``: pedestrian id -> sender -> the step the sender's estimate was sent;
    ``truth``: pedestrian id -> true position (2,).
    """

    step: int
    strips: dict[str, dict[str, list[Strips]]]
    received: dict[str, dict[str, int]]
    truth: dict[str, np.ndarray]


@dataclass
class Recording:
    """A run's measurement stream (enough to replay every node and the bus offline)."""

    scenario: str
    nodes: list[str]
    steps: list[StepRecord] = field(default_factory=list)
    jitter_m: float | None = None  # the run's position jitter (measured for its network)


def record_step(result, recording: Recording) -> None:
    """Append one :class:`~sse_cosim.pipeline.result.StepResult` to ``recording``."""
    recording.jitter_m = result.model.jitter
    strips: dict[str, dict[str, list[Strips]]] = {}
    for obs in result.observations.values():
        for person_id, detection in obs.detections.items():
            strips.setdefault(obs.node, {}).setdefault(person_id, []).append(detection.strips)
    shared = next(iter(result.vehicles.values())).shared  # the (one) automated vehicle's
    received = {
        pid: {sender: result.step - shared.ages[sender] for sender in by_sender}
        for pid, by_sender in shared.estimates.items()
    }
    truth = {pid: np.asarray(p.position, dtype=float) for pid, p in result.snapshot.persons.items()}
    recording.steps.append(StepRecord(result.step, strips, received, truth))


class PlainObserver:
    """The loop's node observer (``estimation.observer.NodeObserver``) that also remembers
    every estimate by step, so that replays can age shared sets exactly as the bus would."""

    def __init__(self, model: MotionModel, gain: str, reduction: str = "girard",
                 max_generators: int = 8) -> None:
        self.model = model
        self.settings = EstimatorSettings(gain, reduction, max_generators)
        self.observer = NodeObserver("replay", model, self.settings)
        self.history: dict[str, dict[int, Zonotope]] = {}

    def step(self, step: int, detections: Mapping[str, Sequence[Strips]]) -> dict[str, Zonotope]:
        estimates = {pid: t.estimate for pid, t in self.observer.step(step, detections).items()}
        for pid, estimate in estimates.items():
            self.history.setdefault(pid, {})[step] = estimate
        return estimates

    def estimate_at(self, pid: str, step: int) -> Zonotope | None:
        return self.history.get(pid, {}).get(step)


def fuse_inputs(inputs: Sequence[Zonotope], method: str, model: MotionModel,
                max_generators: int = 8, reduction: str = "girard") -> Zonotope:
    """The bus's fusion rule (``estimation.bus_fusion.fuse_sets``)."""
    return fuse_sets(inputs, method, EstimatorSettings("volume", reduction, max_generators), model)

"""Item 5: tightness against the exact 2-D polygon filter.

The six scenarios run once with their defaults while a callback records every node's strips
per step, which senders' estimates the bus held (and when they were sent) and the truth
(:func:`benchmarks.common.record_step`). The streams are then replayed offline through every
gain method (local sets) and every gain × fusion method (fused sets at the bus), and through
the exact filter: shapely polygons, exact prediction (F P ⊕ Q) and exact strip intersections
(``sets.exact``). Areas are those of the path sets (the state sets, before the jitter box
that both would add alike); the ratio is zonotope area / exact area per node-step.
"""

from __future__ import annotations

import tempfile
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path

import numpy as np
import shapely
from shapely.geometry.base import BaseGeometry

from benchmarks.common import PlainObserver, Recording, fuse_inputs, record_step
from sse_cosim.estimation.motion import MotionModel, motion_model
from sse_cosim.reporting.recorder import RunRecorder
from sse_cosim.runner.simulation import simulate
from sse_cosim.scenario.loader import load_scenario
from sse_cosim.scenario.model import Estimator, Scenario
from sse_cosim.sets import Strips
from sse_cosim.sets.exact import intersect_strips_exact, predict_exact

BUS = "bus"  # the automated vehicle's id (its node)

SCENARIOS = [f"scenarios/s{i}_{kind}.toml" for i in (1, 2, 3)
             for kind in ("pedestrian", "no_pedestrian")]
GAINS = ("frobenius", "volume", "cvxpy-frobenius", "cvxpy-volume", "volume/pca",
         "volume/16", "enclose", "enclose/16")
"""Gain methods (default reduction: girard to 8 generators); ``volume/pca``: PCA reduction,
``volume/16``: girard to 16 generators (where the looseness comes from); ``enclose``: the
exact 2-D intersection enclosed in a zonotope (``sets.enclosure``), not a Prop. 1 gain."""


def _observer(model: MotionModel, variant: str) -> PlainObserver:
    gain, _, option = variant.partition("/")
    if option == "pca":
        return PlainObserver(model, gain, reduction="pca")
    if option:
        return PlainObserver(model, gain, max_generators=int(option))
    return PlainObserver(model, gain)
FUSIONS = ("frobenius", "volume", "strips", "enclose")
DT = 0.1


def record(path: str, overrides: dict | None = None) -> tuple[Recording, dict, Scenario]:
    """Run one scenario with its defaults, recording its stream; also its summary."""
    scenario = load_scenario(Path(path), overrides)
    recorder = RunRecorder(scenario)
    recording = Recording(Path(path).stem, scenario.node_ids())

    def on_step(result) -> None:
        recorder(result)
        record_step(result, recording)

    with tempfile.TemporaryDirectory(prefix="sse-bench-rec-") as tmp:
        simulate(scenario, Path(tmp), Path(path).stem, on_step, on_start=recorder.start)
    summary = recorder.summary()
    summary["kf_misses"] = sum(r["possible_contains_truth"] is False for r in recorder.rows)
    summary["steps_with_region"] = sum(r["possible_contains_truth"] is not None
                                       for r in recorder.rows)
    return recording, summary, scenario


class ExactObserver:
    """The exact 2-D filter of one node: polygons of the path, no reduction."""

    def __init__(self, model: MotionModel) -> None:
        self.model = model
        self.tracks: dict[str, tuple[int, BaseGeometry]] = {}
        self.history: dict[str, dict[int, BaseGeometry]] = {}

    def predict(self, geometry: BaseGeometry, steps: int) -> BaseGeometry:
        if steps == 0:
            return geometry
        return predict_exact(geometry, np.eye(2), self.model.process_noise.scale(steps))

    def step(self, step: int, detections) -> dict[str, BaseGeometry]:
        updated = {}
        for pid in self.tracks.keys() | detections.keys():
            strips = list(detections.get(pid, ()))
            path = self.model.path_strips(Strips.stack(strips)) if strips else None
            previous = self.tracks.get(pid)
            if previous is None:
                center = np.linalg.lstsq(path.normals, path.values, rcond=None)[0]
                box = shapely.box(*(center - 1e3), *(center + 1e3))
                geometry = intersect_strips_exact(box, path)
            else:
                geometry = self.predict(previous[1], step - previous[0])
                if path is not None:
                    geometry = intersect_strips_exact(geometry, path)
            updated[pid] = (step, geometry)
            self.history.setdefault(pid, {})[step] = geometry
        self.tracks = updated
        return {pid: g for pid, (_, g) in updated.items()}


def _replay(recording: Recording, gains: Sequence[str], fusions: Sequence[str],
            model: MotionModel) -> dict:
    exact = {n: ExactObserver(model) for n in recording.nodes}
    plain = {g: {n: _observer(model, g) for n in recording.nodes} for g in gains}
    local = {g: [] for g in gains}
    fused = {(g, f): [] for g in gains for f in fusions}
    for rec in recording.steps:
        ex = {n: exact[n].step(rec.step, rec.strips.get(n, {})) for n in recording.nodes}
        zs = {g: {n: plain[g][n].step(rec.step, rec.strips.get(n, {})) for n in recording.nodes}
              for g in gains}
        for node in recording.nodes:
            for pid, geometry in ex[node].items():
                area = geometry.area
                for g in gains:
                    local[g].append(zs[g][node][pid].volume() / area)
        for pid in set(ex[BUS]) | set(rec.received):
            senders = rec.received.get(pid, {})
            parts = [ex[BUS][pid]] if pid in ex[BUS] else []
            parts += [exact[s].predict(exact[s].history[pid][sent], rec.step - sent)
                      for s, sent in sorted(senders.items())
                      if sent in exact[s].history.get(pid, {})]
            if len(parts) < 2:
                continue  # nothing to fuse: the local figures cover it
            target = shapely.intersection_all(parts).area
            for g in gains:
                inputs = [zs[g][BUS][pid]] if pid in zs[g][BUS] else []
                inputs += [model.predict(plain[g][s].estimate_at(pid, sent), rec.step - sent)
                           for s, sent in sorted(senders.items())
                           if plain[g][s].estimate_at(pid, sent) is not None]
                for f in fusions:
                    z = fuse_inputs(inputs, f, model, plain[g][BUS].settings.max_generators,
                                    plain[g][BUS].settings.reduction_method)
                    fused[(g, f)].append(z.volume() / target)
    return {"local": local, "fused": {f"{g}|{f}": v for (g, f), v in fused.items()}}


def replay(recording: Recording, gains=GAINS, fusions=FUSIONS) -> dict:
    model = motion_model(Estimator(position_jitter_m=recording.jitter_m), DT)
    return _replay(recording, gains, fusions, model)


def _stats(values: list[float]) -> dict:
    if not values:
        return {"count": 0}
    v = np.asarray(values)
    return {"count": int(v.size), "mean": float(v.mean()), "max": float(v.max()),
            "median": float(np.median(v))}


def run(recordings: Sequence[Recording], gains=GAINS, fusions=FUSIONS, workers: int = 2) -> dict:
    if workers <= 1:
        parts = [replay(r, gains, fusions) for r in recordings]
    else:
        with ProcessPoolExecutor(max_workers=workers, mp_context=get_context("spawn")) as pool:
            parts = list(pool.map(replay, recordings, [gains] * len(recordings),
                                  [fusions] * len(recordings)))
    local = {g: [x for p in parts for x in p["local"][g]] for g in gains}
    fused = {k: [x for p in parts for x in p["fused"][k]] for k in parts[0]["fused"]}
    per_scenario = {
        rec.scenario: {
            "local_volume_mean": _stats(p["local"].get("volume", [])).get("mean"),
            "fused_volume_strips_mean": _stats(p["fused"].get("volume|strips", [])).get("mean"),
            "local_enclose_mean": _stats(p["local"].get("enclose", [])).get("mean"),
            "fused_enclose_enclose_mean": _stats(p["fused"].get("enclose|enclose", [])
                                                 ).get("mean"),
        }
        for rec, p in zip(recordings, parts, strict=True)
    }
    result = {
        "local": {g: _stats(v) for g, v in local.items()},
        "fused": {k: _stats(v) for k, v in fused.items()},
        "per_scenario": per_scenario,
    }
    best_local = min(result["local"], key=lambda g: result["local"][g].get("mean", np.inf))
    best_fused = min(result["fused"], key=lambda k: result["fused"][k].get("mean", np.inf))
    result["best_local"] = best_local
    result["best_fused"] = best_fused
    return result

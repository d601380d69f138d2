"""Item 7: a Kalman filter fed the same measurements (``sse_cosim.estimation.kalman``).

Open loop: the recorded streams of the pedestrian scenarios are replayed through the KF at
the bus (every node's strips at the step they are taken) and through the zonotope observers
and fusion (defaults); per step with a truth and an estimate, does the KF's 3-sigma ellipse
(grown by the jitter, the region the controller would get) hold the pedestrian, and does the
fused position set? Closed loop: the same scenarios with ``estimator.filter = "kalman"``, so
the controller reasons with the ellipses: average speed, minimum distance, misses.
"""

from __future__ import annotations

from collections.abc import Sequence

from benchmarks.common import PlainObserver, Recording, contains_lp_batch, fuse_inputs
from benchmarks.tightness import DT, record
from sse_cosim.estimation.kalman import KalmanTracker
from sse_cosim.estimation.motion import motion_model
from sse_cosim.regions import kind as regions_kind
from sse_cosim.scenario.model import Estimator

BUS = "bus"  # the automated vehicle's id (its node)

PEDESTRIAN_SCENARIOS = [f"scenarios/s{i}_pedestrian.toml" for i in (1, 2, 3)]


def open_loop(recording: Recording) -> dict:
    config = Estimator(position_jitter_m=recording.jitter_m)
    model = motion_model(config, DT)
    kalman, kind = KalmanTracker(model), regions_kind()
    plain = {n: PlainObserver(model, config.gain_method) for n in recording.nodes}
    steps = kf_misses = 0
    checks = []
    for rec in recording.steps:
        merged: dict[str, list] = {}
        for by_pid in rec.strips.values():
            for pid, strips in by_pid.items():
                merged.setdefault(pid, []).extend(strips)
        kalman.step(rec.step, merged)
        regions = kalman.regions(kind)
        local = {n: plain[n].step(rec.step, rec.strips.get(n, {})) for n in recording.nodes}
        for pid, truth in rec.truth.items():
            if pid not in regions:
                continue
            steps += 1
            kf_misses += not regions[pid].contains_points(truth)[0]
            inputs = [local[BUS][pid]] if pid in local[BUS] else []
            inputs += [model.predict(plain[s].estimate_at(pid, sent), rec.step - sent)
                       for s, sent in sorted(rec.received.get(pid, {}).items())
                       if plain[s].estimate_at(pid, sent) is not None]
            if inputs:
                fused = model.position(fuse_inputs(inputs, config.fusion_method, model))
                checks.append((fused.center, fused.generators, truth))
    zonotope_misses = sum(not ok for ok in contains_lp_batch(checks))
    return {"steps": steps, "kf_misses": kf_misses,
            "kf_miss_share": kf_misses / steps if steps else None,
            "zonotope_steps": len(checks), "zonotope_misses": zonotope_misses}


def run(recordings: Sequence[Recording], zonotope_summaries: dict[str, dict],
        quick: bool = False) -> dict:
    open_results = {rec.scenario: open_loop(rec) for rec in recordings
                    if rec.scenario in {p.split("/")[-1][:-5] for p in PEDESTRIAN_SCENARIOS}}
    steps = sum(r["steps"] for r in open_results.values())
    misses = sum(r["kf_misses"] for r in open_results.values())
    closed = {}
    for path in PEDESTRIAN_SCENARIOS[-1:] if quick else PEDESTRIAN_SCENARIOS:
        name = path.split("/")[-1][:-5]
        overrides = {"estimator.filter": "kalman"}
        if quick:
            overrides["simulation.duration_s"] = 8.0
        _, summary, _ = record(path, overrides)
        zono = zonotope_summaries.get(name, {})
        closed[name] = {
            "kalman": {"average_speed_mps": summary["average_speed_mps"],
                       "min_distance_m": summary["min_distance_bus_pedestrian_m"],
                       "ellipse_misses": summary["kf_misses"],
                       "steps_with_region": summary["steps_with_region"],
                       "collisions": summary["collisions"]},
            "zonotope": {"average_speed_mps": zono.get("average_speed_mps"),
                         "min_distance_m": zono.get("min_distance_bus_pedestrian_m"),
                         "containment_violations": zono.get("containment_violations"),
                         "collisions": zono.get("collisions")},
        }
    return {"open_loop": open_results, "open_loop_total": {
        "steps": steps, "kf_misses": misses, "kf_miss_share": misses / steps if steps else None,
        "zonotope_misses": sum(r["zonotope_misses"] for r in open_results.values())},
        "closed_loop": closed}

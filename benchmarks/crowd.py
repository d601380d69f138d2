"""The any-scene issue's benchmark scene: ``scenarios/crowd.toml`` with its pedestrians repeated
in later waves until the scene holds at least 50 (each wave 40 s after the previous, with
start positions moved a little so that nobody stands on another), every per-step check on.
Cost per step of the full loop (recording included) with labelled and with anonymous detections
(``estimator.association``), and bare SUMO stepping the same scene, side by side."""

from __future__ import annotations

import copy
import tempfile
from pathlib import Path
from typing import Any

from benchmarks.common import median
from benchmarks.loop_cost import bare_sumo, cosim
from sse_cosim.scenario.loader import load_scenario_data, validate_scenario
from sse_cosim.scenario.model import Scenario

SCENARIO = "scenarios/crowd.toml"
PEDESTRIANS = 50
WAVE_OFFSET_S = 40.0  # later waves step onto the zebra this much later (the bus is gone)
SHIFT_M = 0.7  # and stand this much further along their sidewalk


def crowd_scene(pedestrians: int = PEDESTRIANS, association: str = "labelled") -> Scenario:
    """crowd.toml with its pedestrians repeated in waves up to ``pedestrians`` of them, its
    detections ``association`` (``estimator.association``)."""
    data: dict[str, Any] = load_scenario_data(SCENARIO)
    base = [(pid, p) for pid, p in data["pedestrians"].items() if p.get("present", True)]
    walkers = dict(data["pedestrians"])
    wave = 0
    while len(walkers) < pedestrians:
        wave += 1
        for pid, p in base:
            if len(walkers) == pedestrians:
                break
            twin = copy.deepcopy(p)
            twin["steps_onto_crossing_s"] = p["steps_onto_crossing_s"] + wave * WAVE_OFFSET_S
            twin["start_pos_m"] = max(0.0, p["start_pos_m"] - wave * SHIFT_M)
            walkers[f"{pid}_w{wave}"] = twin
    data["pedestrians"] = walkers
    data["estimator"] = {**data.get("estimator", {}), "association": association}
    data["simulation"] = {**data.get("simulation", {}),
                          "duration_s": max(data["simulation"]["duration_s"],
                                            wave * WAVE_OFFSET_S + 60.0)}
    return validate_scenario(data, f"{SCENARIO} (x{pedestrians} pedestrians)")


def run(pedestrians: int = PEDESTRIANS, repeats: int = 2, duration_s: float | None = None
        ) -> dict:
    scenes = {association: _cut(crowd_scene(pedestrians, association), duration_s)
              for association in ("labelled", "anonymous")}
    scenario = scenes["labelled"]
    loop: dict[str, list[float]] = {name: [] for name in scenes}
    per_stage: dict[str, list[dict[str, float]]] = {name: [] for name in scenes}
    bare: list[float] = []
    steps: dict[str, int] = {}
    with tempfile.TemporaryDirectory(prefix="sse-bench-crowd-") as tmp:
        for i in range(repeats):
            for name, scene in scenes.items():
                per_step, stages, steps[name] = cosim(scene, Path(tmp) / f"{name}{i}")
                loop[name].append(per_step)
                per_stage[name].append(stages)
            bare.append(bare_sumo(scenario, steps["labelled"], Path(tmp) / f"bare{i}"))
    cost, anonymous, sumo = median(loop["labelled"]), median(loop["anonymous"]), median(bare)
    return {"scenario": f"{SCENARIO}, pedestrians repeated in waves", "pedestrians":
            len(scenario.pedestrians), "steps": steps["labelled"], "repeats": repeats,
            "us_per_step": 1e6 * cost, "bare_us_per_step": 1e6 * sumo,
            "ratio_to_bare": cost / sumo,
            "stages_us": _median_stages(per_stage["labelled"]),
            "anonymous": {"us_per_step": 1e6 * anonymous, "steps": steps["anonymous"],
                          "ratio_to_labelled": anonymous / cost,
                          "stages_us": _median_stages(per_stage["anonymous"])}}


def _cut(scenario: Scenario, duration_s: float | None) -> Scenario:
    """``scenario`` cut to ``duration_s`` (None: as it is)."""
    if duration_s is None:
        return scenario
    return scenario.model_copy(update={"simulation": scenario.simulation.model_copy(
        update={"duration_s": duration_s})})


def _median_stages(runs: list[dict[str, float]]) -> dict[str, float]:
    """Each stage's median µs per step over ``runs``."""
    return {stage: median([d[stage] for d in runs]) for stage in runs[0]}

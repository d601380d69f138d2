"""The any-scene issue's benchmark scene: ``scenarios/crowd.toml`` with its pedestrians repeated
in later waves until the scene holds at least 50 (each wave 40 s after the previous, with
start positions moved a little so that nobody stands on another), every per-step check on.
Cost per step of the full loop against bare SUMO stepping the same scene, side by side."""

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


def crowd_scene(pedestrians: int = PEDESTRIANS) -> Scenario:
    """crowd.toml with its pedestrians repeated in waves up to ``pedestrians`` of them."""
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
    data["simulation"] = {**data.get("simulation", {}),
                          "duration_s": max(data["simulation"]["duration_s"],
                                            wave * WAVE_OFFSET_S + 60.0)}
    return validate_scenario(data, f"{SCENARIO} (x{pedestrians} pedestrians)")


def run(pedestrians: int = PEDESTRIANS, repeats: int = 2, duration_s: float | None = None
        ) -> dict:
    scenario = crowd_scene(pedestrians)
    if duration_s is not None:
        scenario = scenario.model_copy(update={"simulation": scenario.simulation.model_copy(
            update={"duration_s": duration_s})})
    loop, bare, per_stage, steps = [], [], [], 0
    with tempfile.TemporaryDirectory(prefix="sse-bench-crowd-") as tmp:
        for i in range(repeats):
            per_step, stages, steps = cosim(scenario, Path(tmp) / f"cosim{i}")
            loop.append(per_step)
            per_stage.append(stages)
            bare.append(bare_sumo(scenario, steps, Path(tmp) / f"bare{i}"))
    cost, sumo = median(loop), median(bare)
    return {"scenario": f"{SCENARIO}, pedestrians repeated in waves", "pedestrians":
            len(scenario.pedestrians), "steps": steps, "repeats": repeats,
            "us_per_step": 1e6 * cost, "bare_us_per_step": 1e6 * sumo,
            "ratio_to_bare": cost / sumo,
            "stages_us": {s: median([d[s] for d in per_stage]) for s in per_stage[0]}}

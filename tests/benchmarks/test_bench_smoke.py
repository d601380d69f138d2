"""The benchmarks' smoke test: a tiny version of each runs and writes both report files."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from benchmarks.common import contains_lp, contains_lp_batch  # noqa: E402

pytestmark = pytest.mark.sumo


@pytest.fixture(scope="module")
def quick(tmp_path_factory) -> tuple[dict, Path]:
    import os

    from benchmarks.run import run_all

    out = tmp_path_factory.mktemp("bench")
    cwd = os.getcwd()
    os.chdir(ROOT)
    try:
        results = run_all(out, quick=True, log=lambda text: None)
    finally:
        os.chdir(cwd)
    return results, out


def test_every_benchmark_runs_and_reports(quick):
    _, out = quick
    data = json.loads((out / "benchmarks.json").read_text())
    for key in ("machine", "gain_methods", "kernels", "loop_cost", "tightness", "baseline",
                "arrivals", "soundness", "scaling", "crowd", "throughput", "cluster",
                "campaign"):
        assert key in data, key
    assert {"cpu", "cores", "python", "sumo"} <= set(data["machine"])
    assert data["command"].endswith("--quick")
    text = (out / "benchmarks.md").read_text()
    assert "## Targets" in text and "bare SUMO" in text and "libsumo alone" in text
    assert "Dask cluster" in text and "many pedestrians" in text
    assert "## 8. The safety campaign, projected" in text
    assert "| 5b earliest arrival, controller / exact reference, mean | " in text
    assert "| 8 `make safety` (the whole campaign), minutes on 2 cores, projected | " in text


def test_the_cluster_sweep_gives_the_local_pools_rows(quick):
    """The runs on the dask scheduler + workers give the same summaries as the local pool."""
    cluster = quick[0]["cluster"]
    assert cluster["runs"] == 10 and cluster["rows_identical"], cluster["rows_different"]
    for executor in ("local", "dask_cluster"):  # every run worker's CPU time is found
        cpu = cluster[executor]["cpu_seconds"]
        assert cpu["runs"] > 0 and cpu["cluster"] > 0


def test_quick_figures_are_sane(quick):
    results, _ = quick
    loop = results["loop_cost"]
    assert 0 < loop["libsumo_us_per_step"] < loop["bare_us_per_step"]
    # libsumo alone read S3's bus, truck and pedestrian
    assert loop["libsumo_actors_read"] == {"vehicles": 2, "persons": 1}
    assert set(loop["configs"]["a_frobenius"]["stages_us"]) >= {"sumo", "geometry", "output"}
    anonymous = loop["configs"]["anonymous"]
    assert anonymous["association"] == "anonymous" and anonymous["ratio_to_labelled"] > 0
    assert results["crowd"]["anonymous"]["us_per_step"] > 0
    assert results["soundness"]["violations"] == 0
    assert results["soundness"]["node_steps"] >= 300
    assert results["baseline"]["open_loop_total"]["zonotope_misses"] == 0
    startup = results["throughput"]["worker_startup"]
    assert startup["imports_seconds"] > 0 and startup["first_run_seconds"] > 0
    local = results["tightness"]["local"]["volume"]
    assert local["count"] > 0 and local["mean"] >= 1.0 - 1e-9  # never below the exact set
    arrivals = results["arrivals"]["all"]
    assert arrivals["zone_steps"] > 0 and arrivals["later_than_reference"] == 0


def test_independent_lp_catches_a_point_outside():
    import numpy as np

    c, g = np.zeros(2), np.array([[1.0, 0.5], [0.0, 1.0]])
    inside, outside = np.array([1.2, 0.9]), np.array([1.6, 0.0])
    assert contains_lp(c, g, inside) and not contains_lp(c, g, outside)
    checks = [(c, g, inside)] * 70 + [(c, g, outside)] + [(c, g, inside)] * 5
    answers = contains_lp_batch(checks)
    assert answers.count(False) == 1 and answers[70] is False


def test_a_missed_cost_target_says_how_much_of_the_step_must_go():
    from benchmarks.report import SAFETY_ROW, _summary
    from benchmarks.run import TARGETS

    labelled = {"ratio_to_libsumo": 350.0, "us_per_step": 700.0,
                "stages_us": {"sumo": 50.0, "occupancy": 200.0, "local_fusion": 100.0}}
    anonymous = {"ratio_to_labelled": 1200.0 / 700.0, "us_per_step": 1200.0,
                 "stages_us": {"sumo": 60.0, "occupancy": 220.0, "local_fusion": 600.0}}
    crowd = {"pedestrians": 50, "us_per_step": 20_000.0, "ratio_to_bare": 50.0,
             "stages_us": {"occupancy": 9_000.0, "output": 4_000.0},
             "anonymous": {"ratio_to_labelled": 1.2, "us_per_step": 24_000.0,
                           "stages_us": {"occupancy": 9_000.0, "output": 4_000.0}}}
    results = {"loop_cost": {"libsumo_us_per_step": 2.0, "bare_ratio_to_libsumo": 30.0,
                             "configs": {"default_enclose": labelled, "anonymous": anonymous}},
               "scaling": {"exponent_in_pedestrians_x_sensors": 0.5,
                           "largest": {"pedestrians": 64, "sensors": 16, "us_per_step": 1e5}},
               "crowd": crowd}
    lines = _summary(results, TARGETS)
    rows = {line.split(" | ")[0].removeprefix("| "): line for line in lines
            if line.startswith("| ")}
    missed = {line.split("**")[1]: line for line in lines if line.startswith("- **")}
    text = missed["1 co-sim (default methods) / libsumo alone"]
    assert "At ≤ 150× libsumo alone a step may take 300 µs" in text and "400 µs must go" in text
    assert "more than its largest stage, `occupancy`, at 200 µs" in text
    text = missed["1c anonymous / labelled detections, S3"]
    assert "may take 1,050 µs" in text and "150 µs must go" in text
    assert "Against labelled detections: `local_fusion` +500 µs, `occupancy` +20 µs" in text
    text = missed["3b crowd (50 pedestrians, real SUMO), ms per step"]
    assert "At ≤ 15 ms a step may take 15,000 µs" in text and "5,000 µs must go" in text
    assert "must go" not in missed["3 64 pedestrians × 16 sensors, ms per step"]
    assert "3b anonymous / labelled detections, crowd" not in missed  # 1.2× is met
    assert rows["3b anonymous / labelled detections, crowd"].endswith("| **met** |")
    for info in ("1 bare SUMO through `SumoWorld` (the project's snapshot) / libsumo alone",
                 SAFETY_ROW):
        assert rows[info].endswith("|  |")  # information, no verdict
    assert "| not measured |" in rows[SAFETY_ROW]  # without item 8


def test_the_campaign_projection_counts_every_run_on_two_workers():
    """Item 8: planning + runs x one run's time per scenario / item 4's speed-up; a missed
    target says how many minutes must go and which scenario's runs are the largest part."""
    from benchmarks.report import SAFETY_ROW, _summary, markdown
    from benchmarks.run import TARGETS

    campaign = {"campaign": "sweeps/safety.toml", "quick": False, "duration_s": None,
                "planning_seconds": 120.0, "runs": 300, "not_feasible": 10,
                "scenarios": {"s1_pedestrian": {"runs": 200, "sample": "a", "run_seconds": 3.0,
                                                "serial_minutes": 10.0},
                              "crowd": {"runs": 100, "sample": "b", "run_seconds": 54.0,
                                        "serial_minutes": 90.0}}}
    throughput = {"configs": {"local_2": {"speedup_vs_1_worker": 1.6}}}
    results = {"campaign": campaign, "throughput": throughput}
    lines = _summary(results, TARGETS)
    row = next(line for line in lines if line.startswith(f"| {SAFETY_ROW} "))
    assert row == f"| {SAFETY_ROW} | 64 | ≤ 60 | **not met** |"  # 2 + 100 / 1.6 = 64.5
    missed = next(line for line in lines if line.startswith(f"- **{SAFETY_ROW}**"))
    assert "it takes 64, so 4 minutes must go" in missed and "`crowd`'s runs, takes 56" in missed
    campaign["scenarios"]["crowd"]["serial_minutes"] = 50.0  # 2 + 60 / 1.6 = 39.5: met
    row = next(line for line in _summary(results, TARGETS) if line.startswith(f"| {SAFETY_ROW} "))
    assert row.endswith("| 40 | ≤ 60 | **met** |")
    text = markdown({"campaign": campaign, "machine": {k: "x" for k in (
        "cpu", "cores", "python", "sumo", "numpy", "scipy", "shapely", "cvxpy", "platform")},
        "targets": TARGETS, "command": "sse-cosim bench", "total_seconds": 1.0})
    assert "| crowd | 100 | 54.0 | 50.0 | 83 % |" in text
    assert "two workers counted as twice one (item 4 not run) = **32 min**" in text

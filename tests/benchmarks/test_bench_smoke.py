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
                "soundness", "scaling", "crowd", "throughput", "cluster"):
        assert key in data, key
    assert {"cpu", "cores", "python", "sumo"} <= set(data["machine"])
    assert data["command"].endswith("--quick")
    text = (out / "benchmarks.md").read_text()
    assert "## Targets" in text and "bare SUMO" in text and "libsumo alone" in text
    assert "Dask cluster" in text and "many pedestrians" in text
    assert "`make safety` (the whole campaign), minutes on 2 cores | not measured" in text


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


def test_independent_lp_catches_a_point_outside():
    import numpy as np

    c, g = np.zeros(2), np.array([[1.0, 0.5], [0.0, 1.0]])
    inside, outside = np.array([1.2, 0.9]), np.array([1.6, 0.0])
    assert contains_lp(c, g, inside) and not contains_lp(c, g, outside)
    checks = [(c, g, inside)] * 70 + [(c, g, outside)] + [(c, g, inside)] * 5
    answers = contains_lp_batch(checks)
    assert answers.count(False) == 1 and answers[70] is False


def test_a_missed_cost_target_says_how_much_of_the_step_must_go():
    from benchmarks.report import _summary
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
                 "`make safety` (the whole campaign), minutes on 2 cores"):
        assert rows[info].endswith("|  |")  # information, no verdict
    assert "| not measured |" in rows["`make safety` (the whole campaign), minutes on 2 cores"]

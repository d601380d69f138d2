"""The six paper scenarios in real SUMO: the co-simulation issue's acceptance, end to end."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import linprog

from sse_cosim.files import read_text
from sse_cosim.reporting.outputs import RUNS_FOLDER
from sse_cosim.reporting.paper import read_run_folders, write_paper_report
from sse_cosim.runner.batch import run_batch
from sse_cosim.runner.executors import Execution

pytestmark = pytest.mark.sumo
SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"
NAMES = [f"s{i}_{kind}" for i in (1, 2, 3) for kind in ("pedestrian", "no_pedestrian")]


@pytest.fixture(scope="module")
def batch(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("batch")
    outcomes = run_batch([SCENARIOS / f"{n}.toml" for n in NAMES], out,
                         Execution(workers=2, progress=False))
    assert all(o.ok for o in outcomes), [o.error for o in outcomes if not o.ok]
    write_paper_report(out, read_run_folders([out / RUNS_FOLDER]))
    return out


@pytest.fixture(scope="module")
def summaries(batch) -> dict[str, dict]:
    return {n: json.loads((batch / RUNS_FOLDER / n / "summary.json").read_text()) for n in NAMES}


def fused_detection_time(summary: dict) -> float:
    return summary["first_detection"]["fused"]["t"]


def test_shared_awareness_buys_speed_without_pedestrian(summaries):
    """Table I as the paper reports it (issue #61): S2's car and S3's road-side units cover
    the hidden sidewalk, so the bus keeps its nominal speed (S2 at least 19.5 m/s), S1 slows
    for it; S3 >= S2 >= S1 with and without the pedestrian (equal within 0.05 m/s where the
    pedestrian decides, docs/results.md)."""
    for kind, slack in (("no_pedestrian", 0.0), ("pedestrian", 0.05)):
        speed = {name: summaries[f"{name}_{kind}"]["average_speed_mps"]
                 for name in ("s1", "s2", "s3")}
        assert speed["s3"] >= speed["s2"] - slack and speed["s2"] >= speed["s1"] - slack, kind
    without = {name: summaries[f"{name}_no_pedestrian"]["average_speed_mps"]
               for name in ("s1", "s2", "s3")}
    assert without["s2"] >= 19.5 and without["s3"] >= 0.99 * 20.0
    assert without["s1"] < 0.99 * 20.0


def test_pedestrian_slows_every_scenario_and_sharing_detects_it_earlier(summaries):
    for i in (1, 2, 3):
        assert (summaries[f"s{i}_pedestrian"]["average_speed_mps"]
                < summaries[f"s{i}_no_pedestrian"]["average_speed_mps"])
    s1 = summaries["s1_pedestrian"]
    for name in ("s2_pedestrian", "s3_pedestrian"):
        assert fused_detection_time(summaries[name]) < fused_detection_time(s1), name
        # in the decisive case the pedestrian's reach, not its detection, sets the speed
        assert summaries[name]["average_speed_mps"] >= 0.99 * s1["average_speed_mps"], name


def test_every_run_is_sound_and_safe(summaries):
    for name, summary in summaries.items():
        assert summary["containment_violations"] == 0, (name, summary["violations"])
        assert summary["collisions"] == summary["contact_steps"] == 0, name
        assert summary["route_completed"], name
        assert summary["fusion_larger_than_input"] == 0, name


def test_sets_file_lets_anyone_recheck_containment(batch):
    """Re-check with an LP of our own: exists beta in [-1, 1]^e with G beta = truth - c."""
    folder = batch / RUNS_FOLDER / "s3_pedestrian"
    truth_of = pd.read_csv(folder / "truth.csv").set_index(["t", "pedestrian"])
    lines = [json.loads(line) for line in read_text(folder / "sets.jsonl.gz").splitlines()]
    assert {line["kind"] for line in lines} == {"local", "fused"}
    assert {(line["vehicle"], line["track"]) for line in lines} == {("bus", "pedestrian")}
    for line in lines[:: max(len(lines) // 150, 1)]:
        truth = truth_of.loc[(line["t"], line["track"]), ["x", "y"]].to_numpy(dtype=float)
        generators = np.array(line["generators"], dtype=float).reshape(2, -1)
        e = generators.shape[1]
        result = linprog(np.zeros(e), A_eq=generators, b_eq=truth - np.array(line["center"]),
                         bounds=[(-1 - 1e-7, 1 + 1e-7)] * e, method="highs")
        assert result.status == 0, (line["t"], line["node"])


def test_batch_writes_table1_and_figures(batch):
    table = pd.read_csv(batch / "table1.csv")
    assert len(table) == 6
    assert set(table["paper_average_speed"]) == {13.0, 15.0, 13.1, 20.0, 13.2}
    assert "Table I" in (batch / "table1.md").read_text()
    for name in ("speed_profiles.png", "fig7_set_sizes.png", "fig7_set_sizes.csv"):
        assert (batch / name).stat().st_size > 0
    run = batch / RUNS_FOLDER / "s2_pedestrian"
    for name in ("trace.csv", "sets.jsonl.gz", "summary.json", "scenario.json", "speed.png",
                 "set_areas.png"):
        assert (run / name).is_file(), name
    assert list(run.glob("scene_t*.png")), "the first shared fusion is drawn"

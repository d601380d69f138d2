"""Several pedestrians in real SUMO: their paths cross on the zebra, each is held by its own
sets at every step, and the bus gives way to all of them."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest

from sse_cosim.files import read_text
from sse_cosim.runner.run import run_scenario_file

pytestmark = pytest.mark.sumo
S3 = Path(__file__).resolve().parents[2] / "scenarios" / "s3_pedestrian.toml"


def walker(pid: str, start: tuple[str, float], end: tuple[str, float], speed: float,
           step_s: float) -> dict[str, object]:
    """Overrides adding pedestrian ``pid``."""
    return {f"pedestrians.{pid}.start_edge": start[0], f"pedestrians.{pid}.start_pos_m": start[1],
            f"pedestrians.{pid}.end_edge": end[0], f"pedestrians.{pid}.end_pos_m": end[1],
            f"pedestrians.{pid}.walking_speed_mps": speed,
            f"pedestrians.{pid}.steps_onto_crossing_s": step_s}


# S3's pedestrian (north over the zebra at 11.5 s), one walking south over it at the same
# time from the north-east, and one from the north-west to the south-east, a little later:
# the three paths cross on the zebra
CROSSING_PATHS = {
    **walker("south", ("EC", 92.0), ("CE", 10.0), 1.5, 11.0),
    **walker("diagonal", ("CW", 4.0), ("CE", 14.0), 2.0, 12.0),
    # several walkers on one walking area: SUMO moves one by up to 1.15 m in a step
    # (scenarios/crowd.toml)
    "estimator.position_jitter_m": 1.2,
    "simulation.duration_s": 50.0,
}


@pytest.fixture(scope="module")
def run(tmp_path_factory) -> tuple[dict, Path]:
    out = tmp_path_factory.mktemp("pedestrians")
    summary = run_scenario_file(S3, out, CROSSING_PATHS, plots=False)
    return summary, out


def test_each_pedestrian_is_held_by_its_own_sets_at_every_step(run):
    summary, out = run
    assert set(summary["pedestrians"]) == {"pedestrian", "south", "diagonal"}
    for pid, figures in summary["pedestrians"].items():
        assert figures["first_fused_t"] is not None, pid
        assert figures["containment_violations"] == 0, (pid, summary["violations"])
    checks = pd.read_csv(out / "pedestrians.csv")
    assert set(checks["pedestrian"]) == set(summary["pedestrians"])
    for column in ("contained_fused", "contained_refined", "accounted_for"):
        assert checks[column].dropna().astype(bool).all(), column
    truth = pd.read_csv(out / "truth.csv")
    assert truth.groupby("t")["pedestrian"].nunique().max() == 3
    tracks = {json.loads(line)["track"] for line in read_text(out / "sets.jsonl.gz").splitlines()}
    assert tracks == {"pedestrian", "south", "diagonal"}


def test_the_bus_gives_way_to_all_of_them_and_finishes(run):
    summary, _ = run
    assert summary["collisions"] == summary["contact_steps"] == 0
    assert summary["containment_violations"] == 0
    assert all(p["min_distance_m"] > 1.0 for p in summary["pedestrians"].values())
    assert summary["route_completed"]

"""The paper's decisive case in real SUMO: a pedestrian steps onto the zebra in front of the bus.

For S1, S2 and S3, at the scenarios' own walking speed and at the estimator's speed bound, the
safe policy must give way without a collision, without a containment violation of any set or
of the refined region, without ever needing its emergency brake, and finish the route.
"""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest

from sse_cosim.runner.run import run_scenario_file

pytestmark = pytest.mark.sumo
SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"
# At the speed bound itself, 2.5 m/s: SUMO's walker jumps 0.8 m in one step on the far walking
# area (:C_w0_0, t = 13.9 s), which the jitter measured for the road covers
# (sse_cosim/world/walker_jitter.py).
AT_THE_BOUND = {"pedestrians.pedestrian.walking_speed_mps": 2.5,
                "pedestrians.pedestrian.steps_onto_crossing_s": 9.0}
CASES = [(f"s{i}", label, overrides) for i in (1, 2, 3)
         for label, overrides in (("default", {}), ("speed bound", AT_THE_BOUND))]
LANE_Y = (-3.5, 0.0)  # the bus's driving lane (sumo_net/README.md)
CROSSING_X = 198.0  # where the zebra starts along the bus's route


@pytest.fixture(scope="module", params=CASES, ids=[f"{s}-{label}" for s, label, _ in CASES])
def run(request, tmp_path_factory) -> tuple[dict, pd.DataFrame]:
    scenario, _, overrides = request.param
    out = tmp_path_factory.mktemp(scenario)
    summary = run_scenario_file(SCENARIOS / f"{scenario}_pedestrian.toml", out, overrides,
                                plots=False)
    assert json.loads((out / "summary.json").read_text()) == json.loads(json.dumps(summary))
    assert summary["source"] == f"scenarios/{scenario}_pedestrian.toml"  # no machine path
    return summary, with_truth(out)


def with_truth(folder: Path) -> pd.DataFrame:
    """The run's trace with the pedestrian's position at each step (``ped_x``, ``ped_y``)."""
    truth = pd.read_csv(folder / "truth.csv").query("pedestrian == 'pedestrian'")
    truth = truth[["t", "x", "y"]].rename(columns={"x": "ped_x", "y": "ped_y"})
    return pd.read_csv(folder / "trace.csv").merge(truth, on="t", how="left")


def test_the_pedestrian_crosses_the_lane_before_the_bus_reaches_the_zebra(run):
    """The case is the hard one: the bus has to give way."""
    _, trace = run
    in_lane = trace[trace["ped_y"].between(*LANE_Y)]
    assert not in_lane.empty
    bus_at_zebra = trace.loc[trace["bus_x"] >= CROSSING_X, "t"].min()
    assert in_lane["t"].min() < bus_at_zebra


def test_no_contact_no_violation_no_emergency_and_the_route_is_finished(run):
    summary, trace = run
    assert summary["collisions"] == summary["contact_steps"] == 0
    assert summary["containment_violations"] == 0, summary["violations"]
    assert summary["route_completed"]
    assert summary["level_share"]["emergency"] == 0.0
    assert summary["min_distance_bus_pedestrian_m"] > 1.0
    assert trace["possible_contains_truth"].dropna().all()


def test_the_bus_stands_or_is_clear_of_the_zebra_while_the_pedestrian_is_in_its_lane(run):
    _, trace = run
    in_lane = trace[trace["ped_y"].between(*LANE_Y) & trace["ped_x"].between(197.0, 203.0)]
    bus_rear = in_lane["bus_x"] - 12.0
    on_zebra = (in_lane["bus_x"] > CROSSING_X - 0.5) & (bus_rear < 202.5)
    assert (in_lane.loc[on_zebra, "bus_speed"] < 1e-3).all()

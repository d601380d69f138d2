"""The lanes SUMO drives (issue: live on real streets), on tests/networks/two_lanes/, a street
with two driving lanes each way and a signalised junction. The controller plans on the
rightmost lane that leads on along the route and the bus departs there, where SUMO keeps it on
an empty street (before, the plan took the left lane and SUMO moved the bus right, 3.2 m off
its corridor, silently). SUMO changes none of its lanes of its own accord (it overtook a slow
car before); a bus that SUMO drives on another lane all the same stops the run with one line
(exit status 5) instead of deciding on the zones of a lane it is not on."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from sse_cosim.errors import AssumptionBroken
from sse_cosim.runner.run import run_scenario_file
from sse_cosim.scenario.loader import load_scenario
from sse_cosim.world.checks import CheckSetup, Ledger, StepFacts
from sse_cosim.world.checks.lanes import PlannedLanesCheck
from sse_cosim.world.network import build_network
from sse_cosim.world.roadmap import load_roadmap
from sse_cosim.world.snapshot import Footprint, Pose, Snapshot, VehicleState

pytestmark = pytest.mark.sumo
ROOT = Path(__file__).resolve().parents[2]
SLOW_CAR = """
[vehicles.slow]
route_edges = ["WJ", "JE"]
lane_index = 1
depart_pos_m = 60.0
speed_mps = 2.0
"""
SCENARIO = f"""
name = "two_lanes"
description = "A bus along a street with two lanes each way"
[simulation]
duration_s = 20.0
step_length_s = 0.1
seed = 1
[network]
sources_dir = "{(ROOT / 'tests' / 'networks' / 'two_lanes').as_posix()}"
[automated.bus]
route_edges = ["WJ", "JE"]
depart_pos_m = 20.0
nominal_speed_mps = 8.0
"""


def test_on_an_empty_street_the_bus_keeps_the_lane_it_plans_on(tmp_path: Path) -> None:
    path = tmp_path / "two_lanes.toml"
    path.write_text(SCENARIO)
    run_scenario_file(path, tmp_path / "out", {}, plots=False)  # no planned_lanes stop
    trace = pd.read_csv(tmp_path / "out" / "trace.csv")
    assert trace["bus_y"].to_numpy() == pytest.approx(-4.8)  # lane 1's centre all along


def test_behind_a_slow_car_the_bus_keeps_its_planned_lane(tmp_path: Path) -> None:
    """SUMO would overtake the slow car on the left lane (before, that stopped the run with
    ``planned_lanes``); the automated vehicle changes no lane of SUMO's accord (lane change
    mode 512), so it follows the car on the lane its controller plans on."""
    path = tmp_path / "two_lanes.toml"
    path.write_text(SCENARIO + SLOW_CAR)
    run_scenario_file(path, tmp_path / "out", {}, plots=False)  # no planned_lanes stop
    trace = pd.read_csv(tmp_path / "out" / "trace.csv")
    assert trace["bus_y"].to_numpy() == pytest.approx(-4.8)
    assert trace["bus_speed"].iloc[-50:].max() < 2.5  # behind the car, at its speed


def test_a_body_on_another_lane_is_off_the_plan(tmp_path: Path) -> None:
    """The world's check (``planned_lanes``, exit status 5) still stands guard: a body on the
    left lane lies a lane's width outside the planned sweep and stops the run in one line, one
    on the planned lane does not."""
    path = tmp_path / "two_lanes.toml"
    path.write_text(SCENARIO)
    sc = load_scenario(path)
    bus = sc.automated["bus"]
    roadmap = load_roadmap(build_network(ROOT / "tests" / "networks" / "two_lanes"))
    check = PlannedLanesCheck.build(CheckSetup(sc, roadmap))
    sweep = check.sweeps["bus"]

    def body(front_x: float, y: float) -> np.ndarray:
        half = 0.5 * bus.width_m
        return np.array([[front_x - bus.length_m, y - half], [front_x, y - half],
                         [front_x, y + half], [front_x - bus.length_m, y + half]])

    assert sweep.off_m(body(-50.0, -4.8), 100.0) == 0.0
    assert sweep.off_m(body(-50.0, -1.6), 100.0) == pytest.approx(3.2, abs=0.05)
    assert sweep.off_m(body(-50.0, -1.6), 0.5 * bus.length_m) == 0.0  # its back not on yet
    ledger = Ledger([check], (), "two_lanes.toml")
    left = Footprint(Pose(-50.0, -1.6, 0.0), bus.length_m, bus.width_m)
    with pytest.raises(AssumptionBroken, match=r"\(planned_lanes\): automated vehicle 'bus' "
                       r"at t=4\.00 s has its body 3\.\d{3} m outside the lanes"):
        ledger.step(Snapshot(4.0, {"bus": VehicleState("bus", "automated", left, 5.0,
                                                       route_m=100.0)}), StepFacts())


def test_on_one_lane_the_body_stays_in_its_planned_sweep(tmp_path: Path) -> None:
    summary = run_scenario_file(ROOT / "scenarios" / "s3_no_pedestrian.toml", tmp_path, {},
                                plots=False)
    assert summary["vehicles"]["bus"]["route_completed"]

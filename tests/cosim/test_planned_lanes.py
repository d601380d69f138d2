"""The lanes SUMO drives (issue: live on real streets), on tests/networks/two_lanes/, a street
with two driving lanes each way and a signalised junction. The controller plans on the
rightmost lane that leads on along the route and the bus departs there, where SUMO keeps it on
an empty street (before, the plan took the left lane and SUMO moved the bus right, 3.2 m off
its corridor, silently). A bus that SUMO drives on another lane all the same (here it
overtakes a slow car) stops the run with one line (exit status 5) instead of deciding on the
zones of a lane it is not on."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from sse_cosim.errors import AssumptionBroken
from sse_cosim.runner.run import run_scenario_file

pytestmark = pytest.mark.sumo
ROOT = Path(__file__).resolve().parents[2]
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


def test_a_bus_moved_off_its_planned_lane_stops_the_run_in_one_line(tmp_path: Path) -> None:
    path = tmp_path / "two_lanes.toml"
    path.write_text(SCENARIO + """
[vehicles.slow]
route_edges = ["WJ", "JE"]
lane_index = 1
depart_pos_m = 60.0
speed_mps = 2.0
""")
    with pytest.raises(AssumptionBroken, match=r"planned_lanes.*automated vehicle 'bus' at "
                       r"t=\d+\.\d\d s has its body \d+\.\d{3} m outside the lanes") as caught:
        run_scenario_file(path, tmp_path / "out", {}, plots=False)
    assert "\n" not in str(caught.value)


def test_on_one_lane_the_body_stays_in_its_planned_sweep(tmp_path: Path) -> None:
    summary = run_scenario_file(ROOT / "scenarios" / "s3_no_pedestrian.toml", tmp_path, {},
                                plots=False)
    assert summary["vehicles"]["bus"]["route_completed"]

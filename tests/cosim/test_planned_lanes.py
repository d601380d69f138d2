"""A bus that SUMO drives on another lane than the one its controller plans on stops the run
with one line (exit status 5), instead of deciding on the zones of a lane it is not on
(issue: live on real streets). tests/networks/two_lanes/ is a street with two driving lanes
each way and a signalised junction: the road map plans a route on each edge's innermost
driving lane, the left one, and SUMO moves the bus to the right lane (keep right) within
seconds. On the one-lane scenes the body never leaves its planned sweep."""

from __future__ import annotations

from pathlib import Path

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


def test_a_bus_moved_off_its_planned_lane_stops_the_run_in_one_line(tmp_path: Path) -> None:
    path = tmp_path / "two_lanes.toml"
    path.write_text(SCENARIO)
    with pytest.raises(AssumptionBroken, match=r"planned_lanes.*automated vehicle 'bus' at "
                       r"t=\d+\.\d\d s has its body \d+\.\d{3} m outside the lanes") as caught:
        run_scenario_file(path, tmp_path / "out", {}, plots=False)
    assert "\n" not in str(caught.value)


def test_on_one_lane_the_body_stays_in_its_planned_sweep(tmp_path: Path) -> None:
    summary = run_scenario_file(ROOT / "scenarios" / "s3_no_pedestrian.toml", tmp_path, {},
                                plots=False)
    assert summary["vehicles"]["bus"]["route_completed"]

"""The bus at its own traffic light (issue: live on real streets), in real SUMO on
tests/networks/two_lanes/: junction J's program gives the cars 77 s of green, 3 s of yellow,
then 10 s of red (5 s of them the walkers' green), from t = 0. A bus that reaches J during the
yellow stops at the stop line (x = -2 m, the end of lane WJ_1), and before this issue it
commanded its nominal speed all along while SUMO braked it. Now it never commands more than it
can stop for before its red stop line, it does not cross on red, and the wait at the light
does not count as a needless hold (the truth says the light holds it)."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from sse_cosim.control.kinematics import BusDynamics
from sse_cosim.runner.run import run_scenario_file
from sse_cosim.scenario.model import AutomatedVehicle, Controller

pytestmark = pytest.mark.sumo
ROOT = Path(__file__).resolve().parents[2]
STOP_LINE_X = -2.0
DT = 0.1
SCENARIO = f"""
name = "red_light"
description = "A bus meets its red light at a signalised junction"
[simulation]
duration_s = 112.0
step_length_s = {DT}
seed = 1
[network]
sources_dir = "{(ROOT / 'tests' / 'networks' / 'two_lanes').as_posix()}"
[automated.bus]
route_edges = ["WJ", "JE"]
depart_s = 66.0
depart_pos_m = 20.0
nominal_speed_mps = 8.0
[sensors.around]
node = "bus"
fov_deg = 360.0
range_m = 60.0
noise_bound_m = [0.3, 0.3]
"""


def cars_stop(t: float) -> bool:
    """Whether J tells the bus's lane to stop at time t (yellow or red)."""
    return t % 90.0 >= 77.0 - 1e-9


def test_the_bus_commands_no_more_than_it_can_stop_for_at_its_red(tmp_path: Path) -> None:
    path = tmp_path / "red_light.toml"
    path.write_text(SCENARIO)
    summary = run_scenario_file(path, tmp_path / "out", {}, plots=False)
    trace = pd.read_csv(tmp_path / "out" / "trace.csv")
    dynamics = BusDynamics.of(AutomatedVehicle(nominal_speed_mps=8.0), Controller(), DT)
    held = 0
    for t, x, speed, command in trace[["t", "bus_x", "bus_speed", "commanded_speed"]].to_numpy():
        if not cars_stop(t):
            continue
        assert x <= STOP_LINE_X + 1e-6, t  # never over the stop line at yellow or red
        line = STOP_LINE_X - x
        if dynamics.stopping_distance(speed) > line:
            continue  # too close to stop when it turned: SUMO's vehicles drive on too
        held += 1
        steps = 0 if command == 0.0 else 1 if command <= speed else round(1.0 / DT)
        position, v = 0.0, speed
        for _ in range(steps):
            position, v = dynamics.advance(position, v, command)
        assert position + dynamics.stopping_distance(v) <= line + 1e-6, (t, x, speed, command)
    assert held > 50  # it met the light, and stood at it
    assert summary["route_completed"]
    assert summary["longest_needless_hold_s"] == 0.0
    assert summary["level_share"]["emergency"] == 0.0

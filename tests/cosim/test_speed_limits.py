"""A route through several speed limits (issue: live on real streets), in real SUMO on
tests/networks/two_lanes/ with its east arm JE limited to 5 m/s: the bus, nominal 13.89 m/s,
is no longer refused, SUMO holds it to each lane's limit, its commands never ask for more than
the limit where its front is, and its passes over J's crossings are proven at the speed the
limits leave it (control/limits.py), so the run stays sound and never stands needlessly."""

from __future__ import annotations

import shutil
from pathlib import Path

import pandas as pd
import pytest

from sse_cosim.runner.run import run_scenario_file

pytestmark = pytest.mark.sumo
ROOT = Path(__file__).resolve().parents[2]
SLOW_MPS = 5.0
NOMINAL_MPS = 13.89


def slow_east_arm(folder: Path) -> Path:
    """The two-lane street's sources in ``folder``, its edge JE (J to E) limited to
    SLOW_MPS."""
    sources = ROOT / "tests" / "networks" / "two_lanes"
    folder.mkdir()
    for name in ("netconvert.cfg", "two_lanes.nod.xml"):
        shutil.copy(sources / name, folder / name)
    edges = (sources / "two_lanes.edg.xml").read_text()
    fast = '<edge id="JE" from="J" to="E" numLanes="3" speed="13.89"'
    assert fast in edges
    (folder / "two_lanes.edg.xml").write_text(
        edges.replace(fast, fast.replace('speed="13.89"', f'speed="{SLOW_MPS}"')))
    return folder


def test_the_bus_drives_each_lane_at_most_at_its_limit(tmp_path: Path) -> None:
    sources = slow_east_arm(tmp_path / "net")
    path = tmp_path / "slow_arm.toml"
    path.write_text(f"""
name = "slow_arm"
description = "A bus from a 50 km/h street onto a 18 km/h one"
[simulation]
duration_s = 50.0
step_length_s = 0.1
seed = 1
[network]
sources_dir = "{sources.as_posix()}"
[automated.bus]
route_edges = ["WJ", "JE"]
depart_pos_m = 20.0
nominal_speed_mps = {NOMINAL_MPS}
[sensors.around]
node = "bus"
fov_deg = 360.0
range_m = 60.0
noise_bound_m = [0.3, 0.3]
""")
    summary = run_scenario_file(path, tmp_path / "out", {}, plots=False)
    trace = pd.read_csv(tmp_path / "out" / "trace.csv")
    on_slow = trace[trace["bus_x"] > 12.0]  # the front well onto JE, past J's crossing
    assert len(on_slow) > 100
    assert on_slow["bus_speed"].max() <= SLOW_MPS + 1e-6
    assert on_slow["commanded_speed"].max() <= SLOW_MPS + 1e-9
    assert trace["bus_speed"].max() > 13.0  # the fast street at its limit
    assert summary["route_completed"]
    assert summary["containment_violations"] == 0 and summary["collisions"] == 0
    assert summary["longest_needless_hold_s"] <= 0.5
    assert summary["level_share"].get("emergency", 0.0) == 0.0

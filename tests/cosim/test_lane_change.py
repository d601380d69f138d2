"""Lane changes (issue: live on real streets), in real SUMO on tests/networks/lane_change/: a
street from W over J and K to E with two driving lanes, where only WJ's left lane leads on into
JK (onto its left lane) and only JK's right lane leads on into KE. A bus from WJ to KE cannot
follow its route lane to lane: it departs on WJ's left lane, and the world asks SUMO to move
it to JK's right lane once its body is on JK. Its sweep covers both lanes of JK meanwhile
(``RoadMap.route_plan``, ``RoutePath.detours``), so the world's checks that its body lies in
its planned sweep and its front where its odometer puts it hold on either lane, every step.

A change on an edge no longer than the bus can never be made: refused before the run (exit
status 2), naming the field and the edge."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import shapely
from swept_checks import bus_footprints

from sse_cosim.cli.main import main
from sse_cosim.control.swept import RoutePath, body_sweep, footprint, swept_region
from sse_cosim.runner.run import run_scenario_file
from sse_cosim.scenario.loader import load_scenario

pytestmark = pytest.mark.sumo
ROOT = Path(__file__).resolve().parents[2]
NETWORK = ROOT / "tests" / "networks" / "lane_change"
ROUTE = ["WJ", "JK", "KE"]
LEFT_Y, RIGHT_Y = -1.6, -4.8  # the driving lanes' centres (m)
LENGTH_M, WIDTH_M = 12.0, 2.55  # the bus's defaults


def scenario_text(sources: Path, duration_s: float = 40.0) -> str:
    return f"""
name = "lane_change"
description = "A bus that changes lanes on JK to follow its route"
[simulation]
duration_s = {duration_s}
step_length_s = 0.1
seed = 1
[network]
sources_dir = "{sources.as_posix()}"
[automated.bus]
route_edges = {ROUTE}
depart_pos_m = 20.0
nominal_speed_mps = 13.89
[sensors.around]
node = "bus"
fov_deg = 360.0
range_m = 60.0
noise_bound_m = [0.3, 0.3]
"""


def test_the_bus_changes_lanes_once_its_body_is_on_the_edge(tmp_path: Path) -> None:
    path = tmp_path / "lane_change.toml"
    path.write_text(scenario_text(NETWORK))
    summary = run_scenario_file(path, tmp_path / "out", {}, plots=False)  # no check stops it
    trace = pd.read_csv(tmp_path / "out" / "trace.csv")
    assert trace["bus_y"].iloc[0] == pytest.approx(LEFT_Y)  # departs on the lane that leads on
    left = np.isclose(trace["bus_y"], LEFT_Y, atol=1e-9)
    right = np.isclose(trace["bus_y"], RIGHT_Y, atol=1e-9)
    assert (left | right).all()  # on one lane or the other, nothing between
    first = int(np.argmax(right))
    assert left[:first].all() and right[first:].all()  # one change
    on_left = trace[left]
    # asked for once the front is more than a body length onto JK (J at x = 0), made in a step
    assert LENGTH_M < on_left["bus_x"].iloc[-1] <= LENGTH_M + 13.89 * 0.1 + 1e-6
    assert summary["route_completed"]
    assert summary["containment_violations"] == 0 and summary["collisions"] == 0
    assert summary["longest_needless_hold_s"] == 0.0
    assert summary["level_share"]["nominal"] == 1.0  # the street is empty


def test_the_sweep_covers_each_lane_the_bus_may_be_on(tmp_path: Path) -> None:
    """SUMO's footprints over the whole run lie in the sweep of the route with its detours;
    without the detour, the footprints on JK's left lane before the change do not."""
    scenario = load_scenario(_written(tmp_path, NETWORK))
    corners, roadmap = bus_footprints(scenario, tmp_path / "world", "lane_change")
    lanes, changes = roadmap.route_plan(ROUTE)
    assert [(c.edge_id, c.from_index, c.to_index) for c in changes] == [("JK", 2, 1)]
    width = WIDTH_M
    planned = swept_region(body_sweep(RoutePath.of_route(lanes, changes), LENGTH_M, width))
    alone = swept_region(body_sweep(RoutePath.of_route(lanes), LENGTH_M, width))
    points = shapely.points(np.vstack(corners))
    assert float(shapely.distance(planned, points).max()) <= 1e-6
    assert float(shapely.distance(alone, points).max()) == pytest.approx(3.2)
    # the detour stops at JK's end: KE's left lane, never driven, is not swept
    assert not planned.contains(shapely.Point(200.0, LEFT_Y))
    on_left = footprint(np.array([14.0, LEFT_Y]), np.array([1.0, 0.0]), LENGTH_M, width)
    assert planned.contains(shapely.Polygon(on_left).buffer(-1e-9))


def test_a_change_on_an_edge_shorter_than_the_bus_is_refused(tmp_path: Path, capsys) -> None:
    sources = tmp_path / "short"
    shutil.copytree(NETWORK, sources, ignore=shutil.ignore_patterns("build"))
    nodes = (sources / "lane_change.nod.xml").read_text()
    (sources / "lane_change.nod.xml").write_text(nodes.replace('x="150.0"', 'x="10.0"'))
    path = _written(tmp_path, sources)
    with pytest.raises(SystemExit) as info:
        main(["run", str(path), "--out", str(tmp_path / "out")])
    assert info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "automated.bus.route_edges" in err[0]
    assert "from lane 2 to lane 1 on edge 'JK'" in err[0] and "not longer than the vehicle" \
        in err[0]


def _written(folder: Path, sources: Path) -> Path:
    path = folder / "lane_change.toml"
    path.write_text(scenario_text(sources))
    return path

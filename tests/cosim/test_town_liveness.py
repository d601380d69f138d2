"""Liveness on the real town, in SUMO: a bus that stops with its rear over walkable ground
moves on.

The falsifier's first search of the town (`sse-cosim falsify scenarios/town.toml --file
sweeps/falsify_crossing.toml`, seed 1) found the bus standing for good in about half its
runs. In this one (CMA-ES's second evaluation: the pedestrian takes the zebra at
:1207351645_c0 at 2.2 m/s) the bus stops for it at about 40 s, 0.3 m before the zebra, with
its rear over the sidewalk corner it has just crossed, and hidden ground 4 m behind. A
pedestrian there could reach that corner's zone in 1.6 s, while moving the rear out of it
takes the bus 2.1 s from standstill: no plan held, and the bus stood until the run's end at
120 s (route unfinished, 85 s stopped). The ground behind the rear is out of a forward-moving
bus's way, so a zone the body is on counts only where the footprints to come reach
(`control.picture._ahead_of_body`): the bus now finishes its route at 73.6 s, with no
collision and no containment violation.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from sse_cosim.runner.run import run_scenario_file

pytestmark = pytest.mark.sumo

CASE = Path(__file__).with_name("town_stands_over_a_corner.toml")


def test_a_bus_stopped_with_its_rear_over_a_sidewalk_corner_moves_on(tmp_path: Path):
    run_scenario_file(CASE, tmp_path, plots=False, summary_only=True)
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["route_completed"]
    assert summary["travel_time_s"] < 80.0
    assert summary["time_stopped_s"] > 5.0  # it did stop for the pedestrian
    assert summary["collisions"] == 0
    assert summary["containment_violations"] == 0

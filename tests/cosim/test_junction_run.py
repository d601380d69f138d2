"""The four-arm junction in real SUMO with its background traffic (sumo_net/junction/ and its
traffic.rou.xml): S1's bus and pedestrian moved there -- the bus drives west to east through
the junction, the pedestrian crosses the west arm's zebra in front of it while cars come from
every arm. Nobody is hit, every set holds the pedestrian, and the bus passes the zebra only
after the pedestrian has left it."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from sse_cosim.runner.run import run_scenario_file

ROOT = Path(__file__).resolve().parents[2]
JUNCTION = ROOT / "sumo_net" / "junction"
SCENARIO = ROOT / "scenarios" / "s1_pedestrian.toml"
WEST_ZEBRA_X = (-7.5, -3.5)
ROAD_Y = (-3.5, 3.5)
CASE = {
    "network.sources_dir": str(JUNCTION),
    "network.route_files": [str(JUNCTION / "traffic.rou.xml")],
    "automated.bus.route_edges": ["WJ", "JE"], "automated.bus.depart_pos_m": 30.0,
    "automated.bus.nominal_speed_mps": 13.89,
    "parked.truck.present": False,
    "pedestrians.pedestrian.start_edge": "WJ", "pedestrians.pedestrian.start_pos_m": 172.0,
    "pedestrians.pedestrian.end_edge": "JW", "pedestrians.pedestrian.end_pos_m": 170.0,
    "pedestrians.pedestrian.steps_onto_crossing_s": 9.0,
    "simulation.duration_s": 30.0,
}


@pytest.mark.sumo
def test_the_bus_gives_way_on_the_junctions_zebra_amid_traffic(tmp_path: Path) -> None:
    summary = run_scenario_file(SCENARIO, tmp_path, CASE, plots=False)
    assert summary["collisions"] == summary["contact_steps"] == 0
    assert summary["containment_violations"] == 0, summary["violations"]
    trace = pd.read_csv(tmp_path / "trace.csv")
    truth = pd.read_csv(tmp_path / "truth.csv")
    on_zebra = truth["x"].between(*WEST_ZEBRA_X) & truth["y"].between(*ROAD_Y)
    assert on_zebra.any()
    bus_on_zebra = trace["bus_x"] >= WEST_ZEBRA_X[0]
    assert bus_on_zebra.any()  # the bus reached the zebra in the run
    assert truth.loc[on_zebra, "t"].max() < trace.loc[bus_on_zebra, "t"].min()

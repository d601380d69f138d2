"""The town scene (scenarios/town.toml) in real SUMO: Bismarckstrasse in Bad Hersfeld, cut from
an OpenStreetMap extract (sumo_net/town/). The pedestrian behind the parked truck steps onto
the zebra at node 1384946487 while the bus comes; nobody is hit, every set holds its
pedestrian, the bus passes the zebra only after the pedestrian has left it and finishes its
route (at about 40 s, when the run ends). With anonymous detections:
tests/cosim/test_town_anonymous.py (one run for all its checks)."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest
import shapely

from sse_cosim.runner.run import run_scenario_file
from sse_cosim.world.network import build_network
from sse_cosim.world.roadmap import load_roadmap

pytestmark = pytest.mark.sumo
ROOT = Path(__file__).resolve().parents[2]
TOWN = ROOT / "scenarios" / "town.toml"
ZEBRA = ":1384946487_c0"  # the zebra the pedestrian steps onto, on the bus's route
# the bus's front is at most this far from the zebra when the pedestrian steps onto it (m):
# in front of the bus, not long before it comes
NEAR_M = 40.0


def _zebra() -> shapely.Polygon:
    roadmap = load_roadmap(build_network(ROOT / "sumo_net" / "town"))
    return next(c.area for c in roadmap.crossings if c.id == ZEBRA)


def test_the_bus_gives_way_at_the_town_zebra_and_finishes_its_route(tmp_path: Path) -> None:
    summary = run_scenario_file(TOWN, tmp_path, plots=False)
    assert summary["collisions"] == summary["contact_steps"] == 0
    assert summary["containment_violations"] == 0, summary["violations"]
    assert summary["route_completed"]
    zebra = _zebra()
    truth = pd.read_csv(tmp_path / "truth.csv")
    walker = truth[truth["pedestrian"] == "pedestrian"]
    on_zebra = walker[shapely.contains_xy(zebra, walker["x"], walker["y"])]
    assert len(on_zebra) > 0  # it really crosses there
    trace = pd.read_csv(tmp_path / "trace.csv").set_index("t")
    front = trace.loc[on_zebra["t"].min()]
    assert shapely.Point(front["bus_x"], front["bus_y"]).distance(zebra) < NEAR_M
    bus_on_zebra = trace[shapely.contains_xy(zebra, trace["bus_x"], trace["bus_y"])]
    assert len(bus_on_zebra) > 0  # the bus reaches the zebra in the run
    assert on_zebra["t"].max() < bus_on_zebra.index.min()


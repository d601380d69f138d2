"""Every test network moved to UTM-sized coordinates, and turned, gives the zones, arrivals and
runs it gives at the origin (issue: live on real streets).

Real networks sit at UTM-sized coordinates (x about 5e5, y about 5.7e6 m), where one rounding
step of a coordinate is about 1e-9 m, at any heading; our plain-XML networks sit below 340 m
along x. Each network here is copied with its nodes moved by (512345, 5712345) m, and turned
by atan2(0.6, 0.8) = 36.87 degrees about its origin (cos and sin exact in netconvert's two
decimals), and rebuilt by netconvert:

- moved only, a run is the same run: every step's command and level and the summary's
  figures (to 1e-6), on S3 (the bus and two road-side units: every set's area to 1e-6 m²) and
  on the four-arm junction over its first 40 s, in which both buses approach, give way and
  stand (two buses, four road-side units, 14 pedestrians: set areas to 0.1 m², since a
  road-side unit's local set keeps 6 generators at UTM coordinates where it keeps 8 at the
  origin at a few steps, a rounding not yet traced; its whole 100 s, run twice, was the
  suite's longest test);
- moved and turned, the route's conflict zones have the same extents along the route and the
  same ground (to 0.01 m: netconvert rounds the turned shapes to 0.01 m), and a pedestrian
  placed alike arrives at each as soon (to 0.01 s);
- moved and turned, a run stays sound and live (no violation, no collision, its route
  finished) and close: the estimator's motion model bounds each step by a box along the
  network's axes (docs/method.md), which a turn changes, so the sets differ; its average speed
  stays within 2 %.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import shapely
import tomli_w

from sse_cosim.control.picture import SceneContext, Source, assess
from sse_cosim.estimation.motion import motion_model
from sse_cosim.regions import kind
from sse_cosim.runner.run import run_scenario_file
from sse_cosim.scenario.loader import load_scenario, load_scenario_data
from sse_cosim.world.network import build_network
from sse_cosim.world.roadmap import load_roadmap

pytestmark = pytest.mark.sumo
ROOT = Path(__file__).resolve().parents[2]
OFFSET = (512345.0, 5712345.0)
TURN = (0.8, 0.6)  # cos, sin
STILL = (1.0, 0.0)
NETWORKS = {  # sources, and a route of it with conflict zones
    "paper": (ROOT / "sumo_net", ["WC", "CE"]),
    "junction": (ROOT / "sumo_net" / "junction", ["WJ", "JE"]),
    "two_zebras": (ROOT / "tests" / "networks" / "two_zebras", ["WC", "CD", "DE"]),
    "unprioritised_zebra": (ROOT / "tests" / "networks" / "unprioritised_zebra", ["WC", "CE"]),
    "two_lanes": (ROOT / "tests" / "networks" / "two_lanes", ["WJ", "JE"]),
}
K = kind("polygon")


def place(x: float, y: float, turn: tuple[float, float]) -> tuple[float, float]:
    """Point (x, y) turned about the origin and moved by :data:`OFFSET`."""
    c, s = turn
    return OFFSET[0] + c * x - s * y, OFFSET[1] + s * x + c * y


def moved_sources(sources: Path, target: Path, turn: tuple[float, float]) -> Path:
    """A copy of plain-XML network ``sources`` in ``target`` with every node placed."""
    target.mkdir(parents=True, exist_ok=True)
    for path in sources.iterdir():
        if path.is_file() and (path.suffix == ".xml" or path.name == "netconvert.cfg"):
            text = path.read_text(encoding="utf-8")
            if path.name.endswith(".nod.xml"):
                text = re.sub(r'(<node [^>]*?\bx=")([-0-9.]+)("\s+y=")([-0-9.]+)"',
                              lambda m: _placed(m, turn), text)
            (target / path.name).write_text(text, encoding="utf-8")
    return target


def _placed(node: re.Match[str], turn: tuple[float, float]) -> str:
    """A node's ``x="..." y="..."`` match with the point placed."""
    x, y = place(float(node.group(2)), float(node.group(4)), turn)
    return f'{node.group(1)}{x!r}{node.group(3)}{y!r}"'


def moved_scenario(name: str, sources: Path, target: Path, turn: tuple[float, float]) -> Path:
    """Scenario ``name`` of scenarios/ on the moved ``sources``, its road-side units placed
    and turned alike (every other actor is placed by edge)."""
    data = load_scenario_data(ROOT / "scenarios" / f"{name}.toml")
    data.pop("extends", None)
    network = data.setdefault("network", {})
    network["sources_dir"] = str(sources)
    if "route_files" in network:
        network["route_files"] = [str((ROOT / "scenarios" / f).resolve())
                                  for f in network["route_files"]]
    for rsu in data.get("rsus", {}).values():
        rsu["x_m"], rsu["y_m"] = place(rsu["x_m"], rsu["y_m"], turn)
        rsu["heading_deg"] += math.degrees(math.atan2(turn[1], turn[0]))
    path = target / f"{name}.toml"
    path.write_text(tomli_w.dumps(data), encoding="utf-8")
    return path


@pytest.mark.parametrize(("name", "sources", "area_tol_m2", "cut"), [
    ("s3_pedestrian", ROOT / "sumo_net", 1e-6, {}),
    ("junction", ROOT / "sumo_net" / "junction", 0.1, {"simulation.duration_s": 40.0}),
])
def test_a_run_moved_to_utm_coordinates_is_the_same_run(name, sources, area_tol_m2, cut,
                                                         tmp_path):
    moved = moved_sources(sources, tmp_path / "net", STILL)
    at_origin = run_scenario_file(ROOT / "scenarios" / f"{name}.toml", tmp_path / "origin", cut,
                                  plots=False)
    far = run_scenario_file(moved_scenario(name, moved, tmp_path, STILL), tmp_path / "far", cut,
                            plots=False)
    for key in ("average_speed_mps", "travel_time_s", "time_stopped_s", "collisions",
                "containment_violations", "route_completed", "longest_needless_hold_s"):
        assert far[key] == pytest.approx(at_origin[key], abs=1e-6), key
    a, b = (pd.read_csv(tmp_path / run / "trace.csv") for run in ("origin", "far"))
    assert (a["commanded_speed"] == b["commanded_speed"]).all()
    assert (a["level"] == b["level"]).all()
    for column in ("fused_area", "possible_area", "own_occluded_m2"):
        assert np.allclose(a[column].fillna(0), b[column].fillna(0), atol=area_tol_m2), column


def context(sources: Path, route: list[str]) -> SceneContext:
    scenario = load_scenario(ROOT / "scenarios" / "s1_pedestrian.toml")
    bus = scenario.automated["bus"].model_copy(update={"route_edges": route})
    model = motion_model(scenario.estimator.model_copy(update={"position_jitter_m": 0.3}), 0.1)
    return SceneContext.build(load_roadmap(build_network(sources)), route, bus,
                              scenario.controller, model, 0.3, 0.1, K)


@pytest.mark.parametrize("network", sorted(NETWORKS))
def test_zones_and_arrivals_are_the_same_moved_and_turned(network, tmp_path):
    sources, route = NETWORKS[network]
    here = context(sources, route)
    there = context(moved_sources(sources, tmp_path / "net", TURN), route)
    assert len(here.zones) == len(there.zones) > 0
    for a, b in zip(here.zones, there.zones, strict=True):
        assert b.start_m == pytest.approx(a.start_m, abs=0.01)
        assert b.end_m == pytest.approx(a.end_m, abs=0.01)
        assert b.ground.area == pytest.approx(a.ground.area, abs=0.05)
    # a pedestrian 3 m beside the first zone's centre, placed alike in both
    centre = shapely.centroid(here.zones[0].ground)
    walker = shapely.Point(centre.x + 3.0, centre.y + 1.0)
    moved = shapely.Point(*place(walker.x, walker.y, TURN))
    start = shapely.get_coordinates(here.route_line)[0]
    arrivals = [
        [z.arrival_s for z in assess(ctx, np.asarray(front), 0.0, K.empty(), Source(K.empty()),
                                     [Source(K.outer(point.buffer(0.5)))]).zones]
        for ctx, front, point in ((here, start, walker),
                                  (there, shapely.get_coordinates(there.route_line)[0], moved))]
    assert np.allclose(arrivals[0], arrivals[1], atol=0.01)


def test_a_run_moved_and_turned_stays_sound_live_and_close(tmp_path):
    moved = moved_sources(ROOT / "sumo_net", tmp_path / "net", TURN)
    at_origin = run_scenario_file(ROOT / "scenarios" / "s3_pedestrian.toml", tmp_path / "origin",
                                  {}, plots=False)
    turned = run_scenario_file(moved_scenario("s3_pedestrian", moved, tmp_path, TURN),
                               tmp_path / "turned", {}, plots=False)
    assert turned["containment_violations"] == 0 and turned["collisions"] == 0
    assert turned["route_completed"]
    assert turned["average_speed_mps"] == pytest.approx(at_origin["average_speed_mps"],
                                                        rel=0.02)

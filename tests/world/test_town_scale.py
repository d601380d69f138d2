"""The road map and the pedestrian's walk scale with the scene, not with the network: on a
network within the scene's reach the scene's road map is the whole network's, edge for edge
and bit for bit; on the whole converted town of Bad Hersfeld (../shared/networks) the road
map holds the edges near the bus's route only and the walk is planned in a few searches."""

from __future__ import annotations

import gzip
import shutil
import subprocess
import time
from pathlib import Path

import pytest
import shapely
from world_helpers import REPO, scenario

from sse_cosim.scenario.loader import load_scenario
from sse_cosim.world import demand
from sse_cosim.world.extent import jitter_scope, scene_extent
from sse_cosim.world.network import build_network, netconvert_path
from sse_cosim.world.roadmap import RoadMap, load_roadmap, load_scene_roadmap
from sse_cosim.world.walkgraph import WalkGraph

TOWN_OSM = REPO.parent / "shared" / "networks" / "bad_hersfeld.osm.xml.gz"
# docs/own_network.md, section 3, with the street names kept
CONVERT = ["--sidewalks.guess", "--crossings.guess", "--junctions.join", "--geometry.remove",
           "--no-turnarounds", "--output.street-names"]
# Goethestrasse: three edges of the bus's route, a zebra at node 338474020 on it
ROUTE = ["30610462#1", "30610462#2", "30610462#3"]
TOWN_SCENE = {
    "network.net_file": None, "automated.bus.route_edges": ROUTE,
    "automated.bus.depart_pos_m": 30.0, "automated.bus.nominal_speed_mps": 8.33,
    "parked.truck.present": False,
    "pedestrians.pedestrian.start_edge": "30610462#2",
    "pedestrians.pedestrian.start_pos_m": 56.0,
    "pedestrians.pedestrian.end_edge": "-30610462#2",
    "pedestrians.pedestrian.end_pos_m": 5.0,
    "pedestrians.pedestrian.steps_onto_crossing_s": 12.0,
    "simulation.duration_s": 30.0,
}


def _same(a: RoadMap, b: RoadMap) -> None:
    assert [c.id for c in a.crossings] == [c.id for c in b.crossings]
    assert all(x.area.wkb == y.area.wkb for x, y in zip(a.crossings, b.crossings, strict=True))
    assert shapely.to_wkb(a.sidewalks) == shapely.to_wkb(b.sidewalks)
    for group in ("driving_lanes", "parking_lanes", "sidewalk_lanes", "internal_lanes"):
        left, right = getattr(a, group), getattr(b, group)
        assert list(left) == list(right)
        assert all((left[k].shape == right[k].shape).all() for k in left)
    assert a.edge_lengths == b.edge_lengths
    assert a.lane_links == b.lane_links


@pytest.mark.parametrize("name", ["s1_pedestrian", "s3_pedestrian", "s2_no_pedestrian"])
def test_the_paper_roads_scene_map_is_the_whole_map(name: str) -> None:
    sc = scenario(name)
    net_path = build_network(REPO / "sumo_net")
    scene = load_scene_roadmap(net_path, sc)
    assert scene.net is not None
    _same(scene, load_roadmap(net_path))


def test_the_junctions_scene_map_is_the_whole_map() -> None:
    sc = load_scenario(REPO / "scenarios" / "junction.toml")
    net_path = build_network(REPO / "sumo_net" / "junction")
    _same(load_scene_roadmap(net_path, sc), load_roadmap(net_path))


def test_route_files_keep_the_whole_network() -> None:
    sc = load_scenario(REPO / "tests" / "networks" / "given_net" / "scenario.toml")
    net_path = REPO / "tests" / "networks" / "given_net" / "road.net.xml"
    map_ = load_scene_roadmap(net_path, sc)
    assert scene_extent(sc, map_.net) is None
    _same(map_, load_roadmap(net_path))


def test_a_short_scene_leaves_the_far_end_of_the_road_out() -> None:
    """A bus on the first edge of the road with two zebras (tests/networks/two_zebras), no
    pedestrian, a short run and short sensors: the second zebra and the road beyond it stay
    out of the map, the first edge's lanes are the whole map's."""
    sc = scenario("s1_no_pedestrian", **{
        "automated.bus.route_edges": ["WC"], "parked.truck.present": False,
        "simulation.duration_s": 1.0, "controller.interest_radius_m": 1.0,
        "sensors.bus_front.range_m": 1.0, "sensors.bus_near.range_m": 1.0})
    net_path = build_network(REPO / "tests" / "networks" / "two_zebras")
    whole, scene = load_roadmap(net_path), load_scene_roadmap(net_path, sc)
    assert set(scene.edge_lengths) == {"WC", "CW", "CD", "DC"} < set(whole.edge_lengths)
    assert [c.id for c in scene.crossings] == [":C_c0"]
    assert scene.route_length(["WC"]) == whole.route_length(["WC"])
    assert (scene.route_lanes(["WC"])[0].shape == whole.route_lanes(["WC"])[0].shape).all()


@pytest.fixture(scope="module")
def town(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The whole town, converted with docs/own_network.md's command (about 5 s)."""
    if not TOWN_OSM.is_file():
        pytest.skip(f"{TOWN_OSM} is not there")
    folder = tmp_path_factory.mktemp("town")
    osm = folder / "town.osm"
    with gzip.open(TOWN_OSM) as src, osm.open("wb") as dst:
        shutil.copyfileobj(src, dst)
    out = folder / "town.net.xml"
    result = subprocess.run([str(netconvert_path()), "--osm-files", str(osm), *CONVERT,
                             "--output-file", str(out)], capture_output=True, text=True,
                            timeout=300, check=False)
    assert result.returncode == 0 and out.is_file(), result.stderr[-2000:]
    return out


@pytest.mark.sumo
def test_the_whole_town_maps_the_scene_and_plans_the_walk_in_seconds(
        town: Path, capsys: pytest.CaptureFixture[str]) -> None:
    sc = scenario("s3_pedestrian", **{**TOWN_SCENE, "network.net_file": str(town)})
    began = time.perf_counter()
    roadmap = load_scene_roadmap(town, sc)
    assert roadmap.net is not None
    graph = WalkGraph(roadmap.net)
    assert len(graph.crossings) > 2500  # every crossing of the town is a candidate
    ped = sc.pedestrians["pedestrian"]
    path = demand.pedestrian_path(roadmap.net, (ped.start_edge, ped.start_pos_m),
                                  (ped.end_edge, ped.end_pos_m), graph.crossings, graph)
    elapsed = time.perf_counter() - began
    assert path == ["30610462#2", ":338474020_w0", ":338474020_c0", ":338474020_w1",
                    "-30610462#2"]
    assert graph.searches <= 4
    assert elapsed < 20.0  # generous: about 5 s here, most of it sumolib reading 26 MB
    # the map holds the scene's surroundings, not the town's 10,000 edges
    assert 20 < len(roadmap.edge_lengths) < 1000
    assert ":338474020_c0" in roadmap.crossing_ids
    assert roadmap.route_length(ROUTE) > 190.0
    err = capsys.readouterr().err
    assert "reading network town.net.xml" in err and "edges near the scene" in err


@pytest.mark.sumo
def test_a_bus_on_a_straight_lane_of_the_whole_town_drives_through(town: Path,
                                                                   tmp_path: Path) -> None:
    """Issue "live on real streets": on the straight 100.8 m lane 157537322#0_1 at (6,700,
    8,800) the bus braked as an emergency at t = 0 and stood 25 of 30 s with nobody in the
    scene (one rounding step there is more than the sweep's straightness test allowed: the
    88.8 m piece counted as turning, uncut, and three zones stretched along it), and the
    controller's own liveness figure read 0. It keeps its nominal speed now, and the truth's
    figure would have seen it."""
    from sse_cosim.runner.run import run_scenario_file

    overrides = {"network.net_file": str(town), "parked.truck.present": False,
                 "automated.bus.route_edges": ["157537322#0", "157537322#1"],
                 "automated.bus.depart_pos_m": 0.0, "automated.bus.nominal_speed_mps": 8.33,
                 "simulation.duration_s": 30.0}
    summary = run_scenario_file(REPO / "scenarios" / "s1_no_pedestrian.toml", tmp_path,
                                overrides, plots=False)
    bus = summary["vehicles"]["bus"]
    assert bus["route_completed"] and bus["time_stopped_s"] == 0.0
    assert bus["level_share"]["nominal"] == 1.0
    assert bus["longest_needless_hold_s"] == 0.0


def test_the_jitter_is_measured_near_the_route_and_where_walkers_walk(town: Path) -> None:
    """Of a long scene's extent (the whole town, 900 s), the jitter's scope holds the junctions
    near the bus's route, the junctions the pedestrian walks through, and those of a route
    file's person far away; not the rest of the town (world/extent.py, "The jitter's scope")."""
    sc = scenario("s3_pedestrian", **{**TOWN_SCENE, "network.net_file": str(town),
                                      "simulation.duration_s": 900.0})
    roadmap = load_scene_roadmap(town, sc)
    net = roadmap.net
    assert net is not None
    extent = scene_extent(sc, net)
    assert extent is not None
    areas = [e for e in net.getEdges(withInternal=True)
             if e.getFunction() == "walkingarea" and extent.holds(e)]
    walk = frozenset(["30610462#2", ":338474020_w0", ":338474020_c0", ":338474020_w1",
                      "-30610462#2"])
    route = roadmap.route_line(ROUTE)
    scope = jitter_scope(sc, roadmap, walk)
    assert scope is not None
    assert scope.seeds.covers(route.buffer(12.0))  # the bus's sweep
    zebra = next(c for c in roadmap.crossings if c.id == ":338474020_c0")
    assert scope.seeds.covers(zebra.area)  # the zebra on it
    hull = {a.getID(): shapely.convex_hull(shapely.MultiPoint(a.getLanes()[0].getShape()))
            for a in areas}
    held = scope.junctions(net, areas)
    everywhere = {a.getFromNode().getID() for a in areas}
    assert "338474020" in held  # the zebra the pedestrian crosses
    assert len(held) < len(everywhere) / 10  # the extent reaches 2.25 km around the route
    for area in areas:  # held: exactly the junctions with a walking area near the seeds
        near = shapely.distance(hull[area.getID()], scope.seeds) <= scope.reach_m
        assert (area.getFromNode().getID() in held) >= near
    assert all(shapely.distance(hull[a.getID()], scope.seeds) > scope.reach_m
               for a in areas if a.getFromNode().getID() not in held)
    far = next(e for e in net.getEdges() if e.allows("pedestrian")
               and shapely.distance(route, shapely.Point(e.getFromNode().getCoord())) > 500.0
               and shapely.distance(route, shapely.Point(e.getToNode().getCoord())) > 500.0)
    with_far = jitter_scope(sc, roadmap, walk | {far.getID()})
    assert with_far is not None
    ends = {far.getFromNode().getID(), far.getToNode().getID()}
    assert with_far.junctions(net, areas) == held | ends
    assert jitter_scope(sc, roadmap, None) is None  # a walk SUMO routes: the whole extent


@pytest.mark.sumo
def test_a_bus_along_a_bending_street_it_passes_twice_drives_on(town: Path,
                                                                 tmp_path: Path) -> None:
    """Issue "live on real streets": on bus line 300 the bus stood for good 81 m before a
    crossing with nobody in the scene. The sidewalk along the bending street before it was one
    256 m zone (the cuts along the route left three wedges outside its bends, 0.1 m² in all,
    and a strip not covered by its cuts stayed whole); cut, its pieces near the junction were
    still zones of 200 m, for the line comes back along the street's other side and passes
    them again. It drives on now, waiting only at its red light."""
    from sse_cosim.runner.run import run_scenario_file

    overrides = {"network.net_file": str(town), "parked.truck.present": False,
                 "automated.bus.route_edges": ["23979550", "240561445", "887793169",
                                               "23979552#0", "240561427#1"],
                 "automated.bus.depart_pos_m": 150.0, "automated.bus.nominal_speed_mps": 13.89,
                 "simulation.duration_s": 150.0}
    summary = run_scenario_file(REPO / "scenarios" / "s1_no_pedestrian.toml", tmp_path,
                                overrides, plots=False)
    bus = summary["vehicles"]["bus"]
    assert bus["route_completed"]
    assert bus["longest_needless_hold_s"] <= 3.0

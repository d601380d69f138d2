"""The actors against the network: checks, the pedestrian's plan, the route file (no SUMO run)."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
import shapely
from world_helpers import scenario

from sse_cosim.errors import UserError
from sse_cosim.world import demand
from sse_cosim.world.roadmap import load_roadmap

SOURCE = "scenarios/s1_pedestrian.toml"


def _plan(net_path: Path, **overrides: object) -> demand.ActorPlan:
    return demand.plan_actors(scenario("s2_pedestrian", **overrides), net_path,
                              load_roadmap(net_path), SOURCE)


WALKING_AREA_M = 2.82  # the south walking area's path from the sidewalk to the zebra
CROSSING_START_M = 198.0  # where WC's sidewalk meets the junction


def _walk_to_crossing(name: str = "s2_pedestrian") -> float:
    return CROSSING_START_M - scenario(name).pedestrian.start_pos_m + WALKING_AREA_M


def _walk_time(name: str = "s2_pedestrian") -> float:
    """Seconds the pedestrian of scenario ``name`` walks from its start to the zebra."""
    return _walk_to_crossing(name) / scenario(name).pedestrian.walking_speed_mps


def test_pedestrian_crosses_the_zebra(net_path: Path) -> None:
    plan = _plan(net_path).pedestrian
    assert plan is not None
    assert plan.path == ("WC", ":C_w1", ":C_c0", ":C_w0", "CW")
    # the sidewalk from the start to the junction, then the walking area
    assert plan.distance_to_crossing_m == pytest.approx(_walk_to_crossing())


def test_pedestrian_walk_start_derived_from_crossing_time(net_path: Path) -> None:
    plan = _plan(net_path, **{"pedestrian.steps_onto_crossing_s": 20.0}).pedestrian
    assert plan is not None
    # the last 0.1 s step from which it is on time
    latest = 20.0 - _walk_time()
    assert latest - 0.1 < plan.walk_start_s <= latest
    assert plan.crossing_time_s == 20.0


@pytest.mark.parametrize(("overrides", "expected"), [
    # east on WC's sidewalk (2 m wide, centre line y = -7): on its right-hand stripe, 0.6 m
    # south of the centre line, the centre a radius behind the front at 184 m
    ({}, (183.7, -7.6)),
    # west on CE's sidewalk (from x = 202): its right-hand stripe is CE's first, 0.68 m north
    ({"pedestrian.start_edge": "CE", "pedestrian.start_pos_m": 20.0,
      "pedestrian.end_edge": "EC", "pedestrian.end_pos_m": 90.0}, (222.3, -6.32)),
], ids=["forward", "backward"])
def test_pedestrian_stands_where_its_walk_begins(net_path: Path, overrides: dict,
                                                 expected: tuple[float, float]) -> None:
    plan = _plan(net_path, **{"pedestrian.start_pos_m": 184.0, "pedestrian.radius_m": 0.3,
                              "pedestrian.steps_onto_crossing_s": 30.0, **overrides}).pedestrian
    assert plan is not None
    assert plan.standing_xy == pytest.approx(expected)
    assert load_roadmap(net_path).sidewalks.contains(shapely.Point(plan.standing_xy))


def test_earliest_crossing_time_is_accepted(net_path: Path) -> None:
    """The earliest time the refusal names is one the plan takes: it walks at t=0."""
    walk_time = _walk_time()
    earliest = math.ceil(walk_time / 0.1) * 0.1
    plan = _plan(net_path, **{"pedestrian.steps_onto_crossing_s": earliest}).pedestrian
    assert plan is not None and plan.walk_start_s == 0.0


def test_unreachable_crossing_time_is_refused(net_path: Path) -> None:
    # asked to reach the zebra 3 s before it can walk there
    walk_time = _walk_time()
    with pytest.raises(UserError) as info:
        _plan(net_path, **{"pedestrian.steps_onto_crossing_s": walk_time - 3.0})
    err = info.value
    assert (err.source, err.field) == (SOURCE, "pedestrian.steps_onto_crossing_s")
    earliest = f"{math.ceil(walk_time / 0.1) * 0.1:.6g} s"
    assert f"at {earliest} at the earliest" in err.problem
    assert f"use {earliest} or later" in err.fix and "pedestrian.start_pos_m" in err.fix


@pytest.mark.parametrize(
    ("overrides", "field", "words"),
    [
        ({"bus.route_edges": ["WC", "XX"]}, "bus.route_edges", "no edge 'XX'"),
        ({"bus.route_edges": ["WC", "CW"]}, "bus.route_edges", "does not follow"),
        ({"bus.depart_pos_m": 250.0}, "bus.depart_pos_m", "beyond the end"),
        ({"truck.edge": "NOPE"}, "truck.edge", "no edge 'NOPE'"),
        ({"truck.lane_index": 5}, "truck.lane_index", "no lane 5"),
        ({"truck.lane_index": 2}, "truck.lane_index", "not a parking strip"),
        ({"truck.end_pos_m": 199.0}, "truck.end_pos_m", "does not fit"),
        ({"car.lane_index": 0}, "car.lane_index", "does not admit"),
        ({"car.depart_pos_m": 120.0}, "car.depart_pos_m", "beyond the end"),
        ({"car.route_edges": ["EC", "WC"]}, "car.route_edges", "does not follow"),
        ({"pedestrian.start_edge": "XX"}, "pedestrian.start_edge", "no edge 'XX'"),
        ({"pedestrian.start_pos_m": 500.0}, "pedestrian.start_pos_m", "beyond the end"),
        ({"pedestrian.end_edge": ":C_w0"}, "pedestrian.end_edge", "no edge"),
        ({"pedestrian.end_pos_m": 199.0}, "pedestrian.end_pos_m", "beyond the end"),
        ({"bus.nominal_speed_mps": 27.8}, "bus.nominal_speed_mps", "speed limit of lane 'WC_2'"),
        ({"car.speed_mps": 30.0}, "car.speed_mps", "speed limit of lane 'EC_2'"),
        ({"car.route_edges": ["WC", "CE"], "car.speed_mps": 28.0}, "car.speed_mps",
         "(27.78 m/s)"),
    ],
)
def test_bad_actor_names_file_and_field(net_path: Path, overrides: dict, field: str,
                                        words: str) -> None:
    with pytest.raises(UserError) as info:
        _plan(net_path, **overrides)
    assert info.value.source == SOURCE
    assert info.value.field == field
    assert words in info.value.problem
    assert info.value.fix


def test_absent_actors_are_not_checked(net_path: Path) -> None:
    sc = scenario("s1_pedestrian", **{"pedestrian.present": False, "pedestrian.start_edge": "XX",
                                      "car.lane_index": 0,
                                      "truck.present": False, "truck.edge": "XX"})
    assert not sc.car.present
    plan = demand.plan_actors(sc, net_path, load_roadmap(net_path), SOURCE)
    assert plan.pedestrian is None


def test_route_file(net_path: Path, tmp_path: Path) -> None:
    sc = scenario("s2_pedestrian")
    plan = demand.plan_actors(sc, net_path, load_roadmap(net_path), SOURCE)
    root = ET.parse(demand.write_route_file(sc, plan, tmp_path / "r.rou.xml")).getroot()
    types = {t.get("id"): t for t in root.iter("vType")}
    assert set(types) == {"bus", "truck", "car", "pedestrian"}
    assert all(t.get("speedDev") == "0" for t in types.values())
    bus = types["bus"]
    assert (bus.get("vClass"), bus.get("length"), bus.get("width")) == ("bus", "12", "2.55")
    assert (bus.get("accel"), bus.get("decel"), bus.get("emergencyDecel")) == ("1.5", "3", "7")
    assert types["truck"].get("vClass") == "custom1"
    assert float(types["pedestrian"].get("desiredMaxSpeed")) == sc.pedestrian.walking_speed_mps
    vehicles = {v.get("id"): v for v in root.iter("vehicle")}
    assert vehicles["bus"].get("departSpeed") == "20"
    assert vehicles["bus"].get("departLane") == "2"
    truck = vehicles["truck"]
    assert (truck.get("departLane"), float(truck.get("departPos"))) == ("1", sc.truck.end_pos_m)
    assert truck.find("stop").get("lane") == "WC_1"
    car = vehicles["car"]
    assert (float(car.get("depart")), float(car.get("departSpeed"))) == (sc.car.depart_s,
                                                                          sc.car.speed_mps)
    person = root.find("person")
    assert (person.get("depart"), float(person.get("departPos"))) == ("0",
                                                                      sc.pedestrian.start_pos_m)
    stop, walk = list(person)  # it waits at its start, then walks
    assert (stop.tag, stop.get("edge"), float(stop.get("endPos"))) == ("stop", "WC",
                                                                       sc.pedestrian.start_pos_m)
    assert float(stop.get("until")) == plan.pedestrian.walk_start_s
    assert walk.get("edges") == "WC :C_w1 :C_c0 :C_w0 CW"
    departs = [float(e.get("depart")) for e in root if e.tag in ("vehicle", "person")]
    assert departs == sorted(departs)

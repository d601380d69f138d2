"""The actors against the network: checks, the pedestrian's plan, the route file (no SUMO run)."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
import shapely
from world_helpers import scenario

from sse_cosim.errors import UserError
from sse_cosim.scenario.model import present
from sse_cosim.world import demand
from sse_cosim.world.roadmap import load_roadmap

SOURCE = "scenarios/s1_pedestrian.toml"
PED = "pedestrians.pedestrian"


def _plan(net_path: Path, **overrides: object) -> demand.ActorPlan:
    return demand.plan_actors(scenario("s2_pedestrian", **overrides), net_path,
                              load_roadmap(net_path), SOURCE)


WALKING_AREA_M = 2.82  # the south walking area's path from the sidewalk to the zebra
CROSSING_START_M = 198.0  # where WC's sidewalk meets the junction


def _walk_to_crossing(name: str = "s2_pedestrian") -> float:
    return CROSSING_START_M - scenario(name).pedestrians["pedestrian"].start_pos_m + WALKING_AREA_M


def _walk_time(name: str = "s2_pedestrian") -> float:
    """Seconds the pedestrian of scenario ``name`` walks from its start to the zebra."""
    return _walk_to_crossing(name) / scenario(name).pedestrians["pedestrian"].walking_speed_mps


def test_pedestrian_crosses_the_zebra(net_path: Path) -> None:
    plan = _plan(net_path).pedestrians["pedestrian"]
    assert plan is not None
    assert plan.path == ("WC", ":C_w1", ":C_c0", ":C_w0", "CW")
    # the sidewalk from the start to the junction, then the walking area
    assert plan.distance_to_crossing_m == pytest.approx(_walk_to_crossing())


def test_pedestrian_walk_start_derived_from_crossing_time(net_path: Path) -> None:
    plan = _plan(net_path, **{f"{PED}.steps_onto_crossing_s": 20.0}).pedestrians["pedestrian"]
    assert plan is not None
    # SUMO's walker (timed alone) takes whole steps, fewer than the lengths say: its path over
    # the walking area is shorter than the walking area's length
    steps = plan.walk_to_crossing_s / 0.1
    assert steps == pytest.approx(round(steps)) and plan.walk_to_crossing_s < _walk_time()
    assert plan.walk_start_s == pytest.approx(20.0 - plan.walk_to_crossing_s)
    assert plan.steps_on_s == pytest.approx(20.0) and plan.crossing_time_s == 20.0


def _walk_steps(net_path: Path) -> float:
    """SUMO's time (s) of the walk from the start to the zebra."""
    plan = _plan(net_path, **{f"{PED}.steps_onto_crossing_s": 30.0}).pedestrians["pedestrian"]
    return plan.walk_to_crossing_s


@pytest.mark.parametrize(("overrides", "expected"), [
    # east on WC's sidewalk (2 m wide, centre line y = -7): on its right-hand stripe, 0.6 m
    # south of the centre line, the centre a radius behind the front at 184 m
    ({}, (183.7, -7.6)),
    # west on CE's sidewalk (from x = 202): its right-hand stripe is CE's first, 0.68 m north
    ({f"{PED}.start_edge": "CE", f"{PED}.start_pos_m": 20.0, f"{PED}.end_edge": "EC",
      f"{PED}.end_pos_m": 90.0}, (222.3, -6.32)),
], ids=["forward", "backward"])
def test_pedestrian_stands_where_its_walk_begins(net_path: Path, overrides: dict,
                                                 expected: tuple[float, float]) -> None:
    plan = _plan(net_path, **{f"{PED}.start_pos_m": 184.0, f"{PED}.radius_m": 0.3,
                              f"{PED}.steps_onto_crossing_s": 30.0, **overrides})
    plan = plan.pedestrians["pedestrian"]
    assert plan is not None
    assert plan.standing_xy == pytest.approx(expected)
    assert load_roadmap(net_path).sidewalks.contains(shapely.Point(plan.standing_xy))


def test_earliest_crossing_time_is_accepted(net_path: Path) -> None:
    """The earliest time the refusal names is one the plan takes: it walks at t=0."""
    earliest = _walk_steps(net_path)
    plan = _plan(net_path, **{f"{PED}.steps_onto_crossing_s": earliest})
    plan = plan.pedestrians["pedestrian"]
    assert plan is not None and plan.walk_start_s == 0.0


def test_unreachable_crossing_time_is_refused(net_path: Path) -> None:
    # asked to reach the zebra 3 s before it can walk there
    walk_time = _walk_steps(net_path)
    with pytest.raises(UserError) as info:
        _plan(net_path, **{"pedestrians.pedestrian.steps_onto_crossing_s": walk_time - 3.0})
    err = info.value
    assert (err.source, err.field) == (SOURCE, "pedestrians.pedestrian.steps_onto_crossing_s")
    earliest = f"{walk_time:.6g} s"
    assert f"at {earliest} at the earliest" in err.problem
    assert f"use {earliest} or later" in err.fix and f"{PED}.start_pos_m" in err.fix


@pytest.mark.parametrize(
    ("overrides", "field", "words"),
    [
        ({"automated.bus.route_edges": ["WC", "XX"]}, "automated.bus.route_edges",
         "no edge 'XX'"),
        ({"automated.bus.route_edges": ["WC", "CW"]}, "automated.bus.route_edges",
         "does not follow"),
        ({"automated.bus.depart_pos_m": 250.0}, "automated.bus.depart_pos_m",
         "beyond the end"),
        ({"parked.truck.edge": "NOPE"}, "parked.truck.edge",
         "no edge 'NOPE'"),
        ({"parked.truck.lane_index": 5}, "parked.truck.lane_index",
         "no lane 5"),
        ({"parked.truck.lane_index": 2}, "parked.truck.lane_index",
         "not a parking strip"),
        ({"parked.truck.end_pos_m": 199.0}, "parked.truck.end_pos_m",
         "does not fit"),
        ({"vehicles.car.lane_index": 0}, "vehicles.car.lane_index",
         "does not admit"),
        ({"vehicles.car.depart_pos_m": 120.0}, "vehicles.car.depart_pos_m",
         "beyond the end"),
        ({"vehicles.car.route_edges": ["EC", "WC"]}, "vehicles.car.route_edges",
         "does not follow"),
        ({"pedestrians.pedestrian.start_edge": "XX"}, "pedestrians.pedestrian.start_edge",
         "no edge 'XX'"),
        ({"pedestrians.pedestrian.start_pos_m": 500.0}, "pedestrians.pedestrian.start_pos_m",
         "beyond the end"),
        ({"pedestrians.pedestrian.end_edge": ":C_w0"}, "pedestrians.pedestrian.end_edge",
         "no edge"),
        ({"pedestrians.pedestrian.end_pos_m": 199.0}, "pedestrians.pedestrian.end_pos_m",
         "beyond the end"),
        ({"automated.bus.nominal_speed_mps": 27.8}, "automated.bus.nominal_speed_mps",
         "above every speed limit on the route (the fastest, lane 'WC_2'"),
        ({"vehicles.car.speed_mps": 30.0}, "vehicles.car.speed_mps",
         "speed limit of lane 'EC_2'"),
        ({"vehicles.car.route_edges": ["WC", "CE"], "vehicles.car.speed_mps": 28.0},
         "vehicles.car.speed_mps", "(27.78 m/s)"),
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
    sc = scenario("s1_pedestrian", **{"pedestrians.pedestrian.present": False,
                                      "pedestrians.pedestrian.start_edge": "XX",
                                      "vehicles.car.present": False, "vehicles.car.lane_index": 0,
                                      "parked.truck.present": False, "parked.truck.edge": "XX"})
    assert not present(sc.vehicles)
    plan = demand.plan_actors(sc, net_path, load_roadmap(net_path), SOURCE)
    assert plan.pedestrians == {}


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
    ped = sc.pedestrians["pedestrian"]
    assert float(types["pedestrian"].get("desiredMaxSpeed")) == ped.walking_speed_mps
    vehicles = {v.get("id"): v for v in root.iter("vehicle")}
    assert vehicles["bus"].get("departSpeed") == "20"
    assert vehicles["bus"].get("departLane") == "2"
    truck = vehicles["truck"]
    assert (truck.get("departLane"), float(truck.get("departPos"))) == \
        ("1", sc.parked["truck"].end_pos_m)
    assert truck.find("stop").get("lane") == "WC_1"
    car = vehicles["car"]
    assert (float(car.get("depart")), float(car.get("departSpeed"))) == \
        (sc.vehicles["car"].depart_s, sc.vehicles["car"].speed_mps)
    person = root.find("person")
    assert (person.get("depart"), float(person.get("departPos"))) == ("0", ped.start_pos_m)
    stop, walk = list(person)  # it waits at its start, then walks
    assert (stop.tag, stop.get("edge"), float(stop.get("endPos"))) == \
        ("stop", "WC", ped.start_pos_m)
    assert float(stop.get("until")) == plan.pedestrians["pedestrian"].walk_start_s
    assert walk.get("edges") == "WC :C_w1 :C_c0 :C_w0 CW"
    departs = [float(e.get("depart")) for e in root if e.tag in ("vehicle", "person")]
    assert departs == sorted(departs)

"""Actors as collections: ids are unique, only connected vehicles carry sensors, a child file
removes an inherited actor, and the nodes follow from the tables."""

from __future__ import annotations

from pathlib import Path

import pytest

from sse_cosim.errors import UserError
from sse_cosim.scenario.loader import load_scenario, validate_scenario
from sse_cosim.scenario.model import present

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"
CAR = {"route_edges": ["EC", "CW"]}


def scene(**tables: object) -> dict:
    """Scenario data with one bus and ``tables`` on top."""
    return {"name": "t", "automated": {"bus": {}}, **tables}


@pytest.mark.parametrize(("data", "field", "words"), [
    pytest.param({"name": "t"}, "automated", "no automated vehicle", id="no automated vehicle"),
    pytest.param({"name": "t", "automated": {"bus": {"present": False}}}, "automated",
                 "no automated vehicle", id="the only one removed"),
    pytest.param(scene(pedestrians={"bus": {}}), "pedestrians.bus",
                 "the id 'bus' is taken by automated.bus", id="pedestrian named like the bus"),
    pytest.param(scene(vehicles={"car": CAR}, parked={"car": {}}), "parked.car",
                 "taken by vehicles.car", id="parked vehicle named like a car"),
    pytest.param(scene(pedestrians={"u1": {}}, rsus={"u1": {"x_m": 0.0, "y_m": 0.0}}),
                 "rsus.u1", "taken by pedestrians.u1", id="unit named like a pedestrian"),
    pytest.param(scene(vehicles={"van": {**CAR, "connected": False}},
                       sensors={"cam": {"node": "van"}}),
                 "sensors.cam.node", "set vehicles.van.connected = true", id="unconnected"),
    pytest.param(scene(sensors={"cam": {"node": "drone"}}), "sensors.cam.node",
                 "no node 'drone'; use one of bus", id="unknown node"),
    pytest.param(scene(vehicles={"car": {**CAR, "present": False}},
                       sensors={"cam": {"node": "car"}}),
                 "sensors.cam.node", "no node 'car'", id="node removed"),
    pytest.param(scene(parked={"truck": {}}, sensors={"cam": {"node": "truck"}}),
                 "sensors.cam.node", "no node 'truck'", id="parked vehicles carry no sensors"),
    pytest.param(scene(vehicles={"car": CAR},
                       faults={"link": {"l": {"node": "bus", "kind": "loss"}}}),
                 "faults.link.l.node", "no node that sends to an automated vehicle; use one of "
                 "car", id="the only automated vehicle sends to nobody"),
    pytest.param(scene(pedestrians={"p1": {}, "p2": {"walking_speed_mps": 2.8}}),
                 "pedestrians.p2.walking_speed_mps", "above estimator.max_pedestrian_speed_mps",
                 id="each pedestrian's speed is checked"),
])
def test_bad_actors_are_one_line_errors_naming_the_field(data, field, words):
    with pytest.raises(UserError) as info:
        validate_scenario(data, "t.toml")
    assert (info.value.source, info.value.field) == ("t.toml", field)
    assert words in f"{info.value.problem}; {info.value.fix}"
    assert "\n" not in info.value.one_line()


def test_a_child_file_removes_an_inherited_actor(tmp_path):
    child = tmp_path / "child.toml"
    child.write_text(f'extends = "{(SCENARIOS / "s2_pedestrian.toml").as_posix()}"\n'
                     "[vehicles.car]\npresent = false\n[pedestrians.pedestrian]\npresent = false\n"
                     '[pedestrians.p2]\nstart_pos_m = 150.0\n[sensors.car_front]\nnode = "bus"\n')
    scenario = load_scenario(child)
    assert list(present(scenario.pedestrians)) == ["p2"]
    assert present(scenario.vehicles) == {}
    assert scenario.node_ids() == ["bus"]


def test_nodes_are_the_automated_the_connected_vehicles_and_the_units():
    scenario = validate_scenario(scene(
        vehicles={"car": CAR, "van": {**CAR, "connected": False}}, parked={"truck": {}},
        rsus={"u1": {"x_m": 0.0, "y_m": 0.0}}), "t.toml")
    assert scenario.node_ids() == ["bus", "car", "u1"]
    assert scenario.sender_ids() == ["car", "u1"]


def test_the_controller_keeps_clear_of_the_largest_pedestrian():
    assert validate_scenario(scene(), "t.toml").pedestrian_radius_m() == 0.3
    wide = scene(pedestrians={"p1": {"radius_m": 0.25}, "p2": {"radius_m": 0.4},
                              "p3": {"radius_m": 0.9, "present": False}})
    assert validate_scenario(wide, "t.toml").pedestrian_radius_m() == 0.4

"""Sensors carried by every vehicle of a type (``carrier_type``): one instance per such vehicle
in the scene, named ``<sensor>@<vehicle id>``, a connected node by its vehicle id, whose
observer starts when it first appears (no SUMO)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import shapely

from sse_cosim.errors import UserError
from sse_cosim.estimation.motion import motion_model
from sse_cosim.estimation.observer import LocalObservers
from sse_cosim.estimation.settings import EstimatorSettings
from sse_cosim.pipeline.stages import detections_by_node
from sse_cosim.scenario.loader import load_scenario
from sse_cosim.scenario.model import Estimator
from sse_cosim.sensors import SensorObservation, observe, specs_from_scenario
from sse_cosim.sensors.spec import sensor_instances
from sse_cosim.sets import Strips
from sse_cosim.world.snapshot import Footprint, PersonState, Pose, Snapshot, VehicleState

ROOT = Path(__file__).resolve().parents[2]
S1 = ROOT / "scenarios" / "s1_pedestrian.toml"
CAV_CAMERA = {"carrier_type": "cav", "fov_deg": 90.0, "range_m": 50.0,
              "noise_bound_m": [0.5, 0.5]}


def vehicle(vid: str, type_id: str, x: float, heading: float = math.pi) -> VehicleState:
    return VehicleState(vid, "other", Footprint(Pose(x, 2.0, heading), 4.5, 1.8), 10.0, type_id)


def scenario_with_cav_camera(tmp_path: Path, body: str = ""):
    path = tmp_path / "cav.toml"
    path.write_text(f'extends = "{S1.as_posix()}"\n[sensors.cav_front]\ncarrier_type = "cav"\n'
                    f"fov_deg = 90.0\nrange_m = 50.0\n{body}", encoding="utf-8")
    return load_scenario(path)


def test_every_vehicle_of_the_type_carries_an_instance_in_the_templates_place(
        tmp_path: Path) -> None:
    specs = specs_from_scenario(scenario_with_cav_camera(tmp_path))
    template = specs["cav_front"]
    assert template.carrier_type == "cav" and template.node == ""
    snapshot = Snapshot(0.0, {v.id: v for v in (vehicle("c1", "cav", 230.0),
                                                vehicle("other", "background", 240.0),
                                                vehicle("c2", "cav", 260.0))})
    instances = sensor_instances(specs, snapshot)
    assert list(instances) == ["bus_front", "bus_near", "cav_front@c1", "cav_front@c2"]
    for vid in ("c1", "c2"):
        spec = instances[f"cav_front@{vid}"]
        assert (spec.name, spec.node, spec.carrier_type) == (f"cav_front@{vid}", vid, None)
        assert spec.kind == template.kind and spec.range_m == 50.0
    # no vehicle of the type in the scene: no instance, and the other sensors as they are
    assert list(sensor_instances(specs, Snapshot(0.0))) == ["bus_front", "bus_near"]


def test_an_instance_sees_from_its_vehicle_and_is_its_node(tmp_path: Path) -> None:
    specs = specs_from_scenario(scenario_with_cav_camera(tmp_path))
    # a westbound cav at x = 230 looking at a person 20 m ahead of it
    snapshot = Snapshot(0.0, {"c1": vehicle("c1", "cav", 230.0)},
                        {"p": PersonState("p", (210.0, 2.0), 0.0)})
    observations = observe(snapshot, specs, np.random.default_rng(1))
    seen = observations["cav_front@c1"]
    assert seen.node == "c1" and seen.pose is not None and list(seen.detections) == ["p"]
    assert observations["bus_front"].pose is None  # no bus in this scene
    assert detections_by_node(observations) == {"c1": {"p": {"cav_front@c1": seen.detections[
        "p"].strips}}}


def test_a_node_in_the_scene_is_a_key_even_when_it_sees_nobody() -> None:
    empty = shapely.Polygon()
    observations = {
        "cam@c1": SensorObservation("cam@c1", "c1", 0.0, Pose(0.0, 0.0, 0.0), {}, empty, empty),
        "cam@gone": SensorObservation("cam@gone", "gone", 0.0, None, {}, empty, empty),
    }
    assert detections_by_node(observations) == {"c1": {}}


def test_a_node_appearing_at_run_time_gets_an_observer_and_keeps_it() -> None:
    model = motion_model(Estimator(position_jitter_m=0.3), 0.1)
    observers = LocalObservers.labelled(["bus"], model, EstimatorSettings("enclose", "girard", 8))
    strips = Strips(np.eye(2), np.array([210.0, 2.0]), np.array([0.5, 0.5]))
    assert observers.step(0, {}) == {"bus": {}}
    tracks = observers.step(1, {"c1": {"p": {"cam@c1": strips}}})
    assert list(tracks) == ["bus", "c1"] and tracks["c1"]["p"].detected
    later = observers.step(2, {})  # c1 left the scene: its observer keeps predicting
    assert not later["c1"]["p"].detected and later["c1"]["p"].step == 2
    assert later["c1"]["p"].estimate.contains(np.array([210.0, 2.0]))


@pytest.mark.parametrize(("body", "field", "words"), [
    ('node = "bus"\n', "sensors.cav_front.node", ("exactly one of node",)),
    ("", None, ()),
    ('[faults.sensor.f]\nsensor = "cav_front"\nkind = "dropout"\n',
     "faults.sensor.f.sensor", ("carried by every vehicle of a type",)),
])
def test_a_carrier_is_one_node_or_one_type(tmp_path: Path, body: str, field: str | None,
                                           words: tuple[str, ...]) -> None:
    if field is None:
        assert scenario_with_cav_camera(tmp_path).sensors["cav_front"].node is None
        return
    with pytest.raises(UserError) as info:
        scenario_with_cav_camera(tmp_path, body)
    assert info.value.field == field
    for word in words:
        assert word in info.value.problem


def test_a_sensor_without_any_carrier_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "none.toml"
    path.write_text(f'extends = "{S1.as_posix()}"\n[sensors.loose]\nfov_deg = 90.0\n',
                    encoding="utf-8")
    with pytest.raises(UserError) as info:
        load_scenario(path)
    assert info.value.field == "sensors.loose.node"
    assert "carrier_type" in info.value.problem

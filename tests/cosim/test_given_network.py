"""A scenario on a given .net.xml with route-file actors, in real SUMO
(tests/networks/given_net/scenario.toml: S1 on the paper's road converted once by netconvert,
an oncoming vehicle of type ``cav`` that carries a front camera, a car behind it and a person
walking along the far sidewalk, all from traffic.rou.xml).

SUMO loads the net as it is and the route file beside the scenario's own; the route-file
vehicles are in the snapshot, the person is a pedestrian that the nodes estimate; the cav is a
connected node from its first step, its camera sees the pedestrian behind the truck, and its
estimates reach the bus before the bus's own sensors see the pedestrian. Every fused set holds
its person, every step.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from sse_cosim.errors import UserError
from sse_cosim.pipeline.result import StepResult
from sse_cosim.runner.run import run_scenario_file
from sse_cosim.runner.simulation import simulate
from sse_cosim.scenario.loader import load_scenario
from sse_cosim.world.sumo import CONFIG_FILE_NAME, SumoWorld

ROOT = Path(__file__).resolve().parents[2]
GIVEN = ROOT / "tests" / "networks" / "given_net"
SCENARIO = GIVEN / "scenario.toml"
CAV, CAMERA = "cav0", "cav_front@cav0"

pytestmark = pytest.mark.sumo


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[StepResult]]:
    run_dir = tmp_path_factory.mktemp("given_net")
    steps: list[StepResult] = []
    simulate(load_scenario(SCENARIO), run_dir, "given_net", steps.append)
    return run_dir, steps


def test_sumo_loads_the_given_net_and_the_route_files(
        run: tuple[Path, list[StepResult]]) -> None:
    run_dir, steps = run
    inputs = ET.parse(run_dir / CONFIG_FILE_NAME).getroot().find("input")
    net = inputs.find("net-file").get("value")
    routes = inputs.find("route-files").get("value").split(",")
    assert (run_dir / net).resolve() == GIVEN / "road.net.xml"
    assert routes[0] == "scenario.rou.xml"
    assert [(run_dir / r).resolve() for r in routes[1:]] == [GIVEN / "traffic.rou.xml"]
    assert len(steps) == 160  # the whole duration: 16 s at 0.1 s
    assert steps[-1].snapshot.vehicles["bus"].footprint.front.x > 150.0


def test_route_file_actors_are_in_the_snapshot(run: tuple[Path, list[StepResult]]) -> None:
    _, steps = run
    first, late = steps[0].snapshot, steps[50].snapshot
    assert first.vehicles[CAV].type_id == "cav" and first.vehicles[CAV].kind == "other"
    assert late.vehicles["car1"].type_id == "background"  # departs at 3 s
    assert "car1" not in first.vehicles
    assert set(first.persons) == {"pedestrian", "walker0"}


def test_the_cav_is_a_node_whose_camera_reaches_the_bus(
        run: tuple[Path, list[StepResult]]) -> None:
    _, steps = run
    assert all(CAV in r.tracks for r in steps)  # a node from its first step in the scene
    cav_sees = [r.step for r in steps
                if "pedestrian" in r.observations[CAMERA].detections]
    bus_sees = [r.step for r in steps if r.tracks["bus"].get("pedestrian") is not None
                and r.tracks["bus"]["pedestrian"].detected]
    received = [r.step for r in steps
                if CAV in r.vehicles["bus"].shared.estimates.get("pedestrian", {})]
    assert cav_sees and bus_sees and received
    assert received[0] == cav_sees[0] + 1  # one step of V2X latency
    assert received[0] < bus_sees[0] - 30  # 3 s before the bus's own sensors
    first = steps[received[0]]
    assert "pedestrian" in first.vehicles["bus"].estimate.fused
    assert first.observations[CAMERA].node == CAV


def test_every_fused_set_holds_its_person(run: tuple[Path, list[StepResult]]) -> None:
    _, steps = run
    checked = set()
    for r in steps:
        for pid, fused in r.vehicles["bus"].estimate.fused.items():
            truth = np.asarray(r.snapshot.persons[pid].position)
            assert fused.contains(truth, tol=1e-6), (r.step, pid)
            checked.add(pid)
    assert checked == {"pedestrian", "walker0"}


@pytest.mark.parametrize(("overrides", "field", "words"), [
    ({"network.net_file": str(GIVEN / "missing.net.xml")}, "network.net_file", ("not found",)),
    ({"network.route_files": []}, "sensors.cav_front.carrier_type",
     ("declares the type 'cav'",)),
])
def test_what_sumo_cannot_run_is_refused_before_it_starts(
        tmp_path: Path, overrides: dict, field: str, words: tuple[str, ...]) -> None:
    scenario = load_scenario(SCENARIO, overrides)
    with pytest.raises(UserError) as info, SumoWorld(scenario, tmp_path, "given_net"):
        pass
    assert info.value.field == field and info.value.source == "given_net"
    for word in words:
        assert word in info.value.problem


def test_a_run_records_the_route_file_person_like_the_scenarios(tmp_path: Path) -> None:
    """The recorder checks and summarises a person from a route file too (its radius is the
    one the controller keeps clear of); it used to stop the run with a KeyError."""
    summary = run_scenario_file(SCENARIO, tmp_path, {"simulation.duration_s": 4.0}, plots=False)
    assert list(summary["pedestrians"]) == ["pedestrian", "walker0"]
    rows = pd.read_csv(tmp_path / "pedestrians.csv")
    assert set(rows["pedestrian"]) == {"pedestrian", "walker0"}
    assert summary["collisions"] == 0 and summary["containment_violations"] == 0

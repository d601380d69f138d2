"""Lanes whose ``length`` is not their shape's (issue: live on real streets), in real SUMO.

SUMO drives a vehicle by a lane's ``length`` attribute and draws it along the lane's shape
scaled to it, so on a lane drawn longer than its length the bus moves along the drawn road
faster than its speed, and on one drawn shorter, slower (scenarios/town.toml's route has
lanes drawn at 0.957 to 1.026 of their length). The paper's decisive case
(tests/cosim/test_decisive_case.py) runs here on the paper's road with the bus's lane on its
approach, WC_2 (drawn 198 m), given a length of 120 m and of 250 m in the .net.xml, and the
bus a nominal speed that moves it along the drawn road at the paper's 20 m/s: the
controller's stops, passes and limits are in SUMO's distance (control/swept.py,
``RoutePath``), and the run checks every step that SUMO draws the front where its odometer
puts it on the route (world/checks/odometer.py, ``route_odometer``), so the bus gives way as
on the paper's road. Drawn and driven apart, a stop planned in drawn metres would run 1.65
times its length (the bus needed its emergency brake), and a pass would take 1.26 times its
time."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from sse_cosim.control.picture import SceneContext, Source, assess
from sse_cosim.control.swept import RoutePath
from sse_cosim.errors import AssumptionBroken
from sse_cosim.estimation.motion import motion_model
from sse_cosim.regions import kind
from sse_cosim.runner.run import run_scenario_file
from sse_cosim.scenario.loader import load_scenario
from sse_cosim.world.checks import Ledger, StepFacts
from sse_cosim.world.checks.odometer import OdometerCheck
from sse_cosim.world.network import build_network
from sse_cosim.world.roadmap import load_roadmap
from sse_cosim.world.snapshot import Footprint, Pose, Snapshot, VehicleState

pytestmark = pytest.mark.sumo
ROOT = Path(__file__).resolve().parents[2]
# the decisive case at the estimator's speed bound (tests/cosim/test_decisive_case.py)
AT_THE_BOUND = {"pedestrians.pedestrian.walking_speed_mps": 2.5,
                "pedestrians.pedestrian.steps_onto_crossing_s": 9.0}
LANE_Y = (-3.5, 0.0)  # the bus's driving lane (sumo_net/README.md)
CROSSING = (198.0, 202.0)  # the zebra along the bus's route
BUS_LENGTH_M = 12.0
K = kind("polygon")
LENGTHS_M = (120.0, 250.0)
DRAWN_M, NOMINAL_MPS = 198.0, 20.0  # WC_2's shape; the bus's nominal speed on the paper's road
DRIVEN_LANE = "WC_2"  # the bus's lane on its approach; the sidewalk and the strip stay drawn


def paper_road(folder: Path, length_m: float) -> Path:
    """The paper's road as a .net.xml in ``folder``, its lane WC_2 given ``length_m``."""
    net = build_network(ROOT / "sumo_net").read_text()
    lane = re.compile(rf'(<lane id="{DRIVEN_LANE}"[^>]*? length=")([0-9.]+)(")')
    assert len(lane.findall(net)) == 1
    path = folder / "road.net.xml"
    path.write_text(lane.sub(rf"\g<1>{length_m:.2f}\g<3>", net))
    return path


@pytest.fixture(scope="module", params=LENGTHS_M, ids=[f"WC {m:g} m" for m in LENGTHS_M])
def run(request, tmp_path_factory) -> tuple[dict, pd.DataFrame]:
    folder = tmp_path_factory.mktemp("lengths")
    # at the nominal speed scaled to the lane, the bus moves along the drawn road as on the
    # paper's, so the pedestrian steps out in front of it as in the decisive case
    nominal = round(NOMINAL_MPS * request.param / DRAWN_M, 4)
    overrides = {**AT_THE_BOUND, "automated.bus.nominal_speed_mps": nominal,
                 "network.sources_dir": None,
                 "network.net_file": paper_road(folder, request.param).as_posix()}
    summary = run_scenario_file(ROOT / "scenarios" / "s3_pedestrian.toml", folder / "out",
                                overrides, plots=False)
    truth = pd.read_csv(folder / "out" / "truth.csv").query("pedestrian == 'pedestrian'")
    truth = truth[["t", "x", "y"]].rename(columns={"x": "ped_x", "y": "ped_y"})
    return summary, pd.read_csv(folder / "out" / "trace.csv").merge(truth, on="t", how="left")


def test_the_bus_gives_way_without_contact_violation_or_emergency(run):
    summary, trace = run
    assert summary["collisions"] == summary["contact_steps"] == 0
    assert summary["containment_violations"] == 0, summary["violations"]
    assert summary["route_completed"]
    assert summary["level_share"].get("emergency", 0.0) == 0.0
    in_lane = trace[trace["ped_y"].between(*LANE_Y) & trace["ped_x"].between(*CROSSING)]
    assert not in_lane.empty  # the hard case: the pedestrian is in the bus's lane
    bus_at_zebra = trace.loc[trace["bus_x"] >= CROSSING[0], "t"].min()
    assert in_lane["t"].min() < bus_at_zebra
    on_zebra = (in_lane["bus_x"] > CROSSING[0] - 0.5) & (
        in_lane["bus_x"] - BUS_LENGTH_M < CROSSING[1] + 0.5)
    assert (in_lane.loc[on_zebra, "bus_speed"] < 1e-3).all()


@pytest.mark.parametrize("length_m", LENGTHS_M)
def test_the_picture_drives_stops_and_clears_in_sumos_distance(tmp_path: Path,
                                                               length_m: float) -> None:
    """From the front 10 drawn metres before the zebra's zone on WC_2 (within the plans'
    reach) the zone starts and is cleared at the distances SUMO drives: WC_2's drawn metres
    scaled to its length, then the junction and CE as drawn."""
    scenario = load_scenario(ROOT / "scenarios" / "s3_pedestrian.toml")
    bus = scenario.automated["bus"]
    model = motion_model(scenario.estimator.model_copy(update={"position_jitter_m": 0.3}), 0.1)
    context = SceneContext.build(load_roadmap(paper_road(tmp_path, length_m)), bus.route_edges,
                                 bus, scenario.controller, model, 0.3, 0.1, K)

    def driven(drawn_m: float) -> float:
        return drawn_m * length_m / DRAWN_M if drawn_m <= DRAWN_M else (
            drawn_m - DRAWN_M + length_m)

    nobody = Source(K.empty())
    zone = context.zones[0]
    front = zone.start_m - 10.0
    picture = assess(context, np.array([front, -1.75]), 10.0, K.empty(), nobody, [])
    assert zone.start_m <= DRAWN_M < zone.end_m + BUS_LENGTH_M
    outlook = picture.zones[0]
    assert outlook.to_start_m == pytest.approx(driven(zone.start_m) - driven(front))
    assert outlook.to_clear_m == pytest.approx(
        driven(zone.end_m + BUS_LENGTH_M) - driven(front))
    assert picture.front_s == pytest.approx(front)
    assert picture.front_drive_m == pytest.approx(driven(front))


def test_a_front_that_sumos_odometer_puts_elsewhere_stops_the_run() -> None:
    """The world's check that the controller's distance is SUMO's (``route_odometer``): a
    front within 1e-6 m of where the odometer puts it on the route is kept, one farther
    stops the run in one line naming the vehicle, its odometer and how far off it is."""
    path = RoutePath.of_lanes([(np.array([[0.0, 0.0], [100.0, 0.0]]), 80.0)])  # drawn 1.25x
    ledger = Ledger([OdometerCheck({"bus": path})], (), "scenarios/s.toml")

    def at(route_m: float) -> Snapshot:
        body = Footprint(Pose(50.0, 0.0, 0.0), BUS_LENGTH_M, 2.5)  # SUMO's front at 50 m
        return Snapshot(3.0, {"bus": VehicleState("bus", "automated", body, 5.0,
                                                  route_m=route_m)}, {})

    ledger.step(at(40.0 + 5e-7), StepFacts())  # 40 m of SUMO's distance: drawn at 50 m
    with pytest.raises(AssumptionBroken, match=r"route_odometer.*'bus' at t=3\.00 s has driven "
                       r"40\.400 m .* its front 0\.500 m from"):
        ledger.step(at(40.4), StepFacts())

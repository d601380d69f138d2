"""Two zebras on the bus's route (tests/networks/two_zebras: the paper's road with a second
zebra at D, x = 260): the road map lists both, the safe policy's conflict zones and tracked
window cover both, the paper policy looks at the nearest crossing not yet cleared, and in real
SUMO a pedestrian who steps onto the second zebra at the speed bound, from behind a truck
parked before it, in front of the bus, is given way to without contact or violation.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from sse_cosim.control.picture import SceneContext, Source, assess
from sse_cosim.estimation.motion import motion_model
from sse_cosim.regions import kind
from sse_cosim.runner.run import run_scenario_file
from sse_cosim.scenario.loader import load_scenario
from sse_cosim.world.demand import plan_actors
from sse_cosim.world.network import build_network
from sse_cosim.world.roadmap import RoadMap, load_roadmap

K = kind("polygon")

ROOT = Path(__file__).resolve().parents[2]
SOURCES = ROOT / "tests" / "networks" / "two_zebras"
SCENARIO = ROOT / "scenarios" / "s1_pedestrian.toml"
JITTER_M = 0.649  # the road's measured jitter: `sse-cosim network tests/networks/two_zebras`
ROUTE = ["WC", "CD", "DE"]
SECOND_ZEBRA_X = (258.0, 262.0)
LANE_Y = (-3.5, 0.0)  # the bus's driving lane
# S1 moved to the second zebra: the truck 6 m before it, the pedestrian behind the truck
# stepping onto it at the speed bound when the bus, at nominal speed, would be 0.9 s from it
SECOND_ZEBRA_CASE = {
    "network.sources_dir": str(SOURCES), "automated.bus.route_edges": ROUTE,
    "parked.truck.edge": "CD", "parked.truck.end_pos_m": 44.0,
    "pedestrians.pedestrian.start_edge": "CD", "pedestrians.pedestrian.start_pos_m": 42.0,
    "pedestrians.pedestrian.end_edge": "DC", "pedestrians.pedestrian.end_pos_m": 4.0,
    "pedestrians.pedestrian.walking_speed_mps": 2.5,
    "pedestrians.pedestrian.steps_onto_crossing_s": 12.0,
    # at 2.5 m/s SUMO's walker jumps 0.8 m in one step on the far walking area (:D_w0_0,
    # t = 16.9 s): the jitter measured for the road covers it
    # the bus gives way to the pedestrian in view until SUMO removes it beyond the zebra (19 s),
    # then needs about 4 s to clear the zebra from its edge
    "simulation.duration_s": 26.0,
}


@pytest.fixture(scope="module")
def roadmap() -> RoadMap:
    return load_roadmap(build_network(SOURCES))


def scene(roadmap: RoadMap, route: list[str]) -> SceneContext:
    """The static picture of S1's bus driving ``route`` on the two-zebra road."""
    sc = load_scenario(SCENARIO, {"automated.bus.route_edges": route})
    dt = sc.simulation.step_length_s
    pedestrians = motion_model(sc.estimator.model_copy(update={"position_jitter_m": JITTER_M}),
                               dt)
    return SceneContext.build(roadmap, route, sc.automated["bus"], sc.controller, pedestrians,
                              sc.pedestrian_radius_m(), dt, K)


@pytest.fixture(scope="module")
def context(roadmap: RoadMap) -> SceneContext:
    return scene(roadmap, ROUTE)


def test_the_road_map_lists_both_crossings(roadmap: RoadMap) -> None:
    assert [(c.id, c.node) for c in roadmap.crossings] == [(":C_c0", "C"), (":D_c0", "D")]
    bounds = np.array([c.area.bounds for c in roadmap.crossings])
    assert bounds == pytest.approx(np.array([[198.0, -6.0, 202.0, 6.0], [258.0, -6.0, 262.0, 6.0]]))
    assert roadmap.crossing_area.area == pytest.approx(2 * 48.0)


def test_the_pedestrian_walks_over_the_zebra_that_makes_its_walk_shortest(
        roadmap: RoadMap) -> None:
    sc = load_scenario(SCENARIO, SECOND_ZEBRA_CASE)
    plan = plan_actors(sc, roadmap.net_path, roadmap, "two_zebras").pedestrians["pedestrian"]
    assert plan is not None
    assert plan.path[0] == "CD" and plan.path[-1] == "DC"
    assert ":D_c0" in plan.path and ":C_c0" not in plan.path


def test_the_safe_policy_has_a_zone_on_each_zebra_nearest_first(
        roadmap: RoadMap, context: SceneContext) -> None:
    first, second = context.zones
    assert first.polygon.shape.within(roadmap.crossings[0].area)
    assert second.polygon.shape.within(roadmap.crossings[1].area)
    assert (first.start_m, first.end_m, second.start_m, second.end_m) == pytest.approx(
        (198.0, 202.0, 258.0, 262.0), abs=1e-6)
    # hidden ground is tracked around both, so neither counts as always occupied
    assert all(context.window.shape.contains(c.area) for c in roadmap.crossings)
    assert min(z.beyond_arrival_s for z in context.zones) > 0.0


def test_both_zones_stay_in_the_picture_until_cleared(context: SceneContext) -> None:
    empty = K.empty()
    length = context.bus.length_m
    for front_s, zones in ((100.0, [0, 1]), (202.0 + length + 0.1, [1]), (262.0 + length, [])):
        front = np.array(context.route_line.interpolate(front_s).coords[0])
        picture = assess(context, front, 10.0, empty, Source(empty), [])
        assert [z.index for z in picture.zones] == zones


def test_the_paper_policys_crossing_is_the_nearest_not_yet_cleared(context: SceneContext) -> None:
    length = context.bus.length_m
    starts = [context.crossing_at(s).start_m for s in (0.0, 201.0, 202.0 + length - 0.1,
                                                      202.0 + length + 0.1, 400.0)]
    assert starts == pytest.approx([198.0, 198.0, 198.0, 258.0, 258.0])
    empty = K.empty()
    front = np.array(context.route_line.interpolate(230.0).coords[0])
    picture = assess(context, front, 10.0, empty, Source(empty), [])
    assert picture.crossing_ahead and picture.distance_to_crossing == pytest.approx(28.0)
    assert picture.reach_radius_m > 0.0


def test_a_route_without_crossings_has_no_crossing_ahead(roadmap: RoadMap) -> None:
    context = scene(roadmap, ["DE"])  # from D, past the second zebra, to the dead end
    assert context.crossings == () and context.zones == ()
    assert context.crossing_at(10.0) is None and context.reach_radius(10.0, 10.0) == 0.0
    empty = K.empty()
    front = np.array(context.route_line.interpolate(10.0).coords[0])
    picture = assess(context, front, 10.0, empty, Source(empty), [])
    assert picture.distance_to_crossing is None and not picture.crossing_ahead


@pytest.mark.sumo
def test_a_pedestrian_on_the_second_zebra_at_the_speed_bound_is_given_way(tmp_path: Path) -> None:
    summary = run_scenario_file(SCENARIO, tmp_path, SECOND_ZEBRA_CASE, plots=False)
    trace = pd.read_csv(tmp_path / "trace.csv")
    truth = pd.read_csv(tmp_path / "truth.csv").query("pedestrian == 'pedestrian'")
    trace = trace.merge(truth[["t", "x", "y"]].rename(columns={"x": "ped_x", "y": "ped_y"}),
                        on="t", how="left")
    # the hard case: the pedestrian is in the bus's lane on the second zebra before the bus
    # reaches that zebra
    on_zebra = trace["ped_x"].between(*SECOND_ZEBRA_X) & trace["ped_y"].between(*LANE_Y)
    bus_there = trace.loc[trace["bus_x"] >= SECOND_ZEBRA_X[0], "t"].min()
    assert trace.loc[on_zebra, "t"].min() < bus_there
    assert summary["collisions"] == summary["contact_steps"] == 0
    assert summary["containment_violations"] == 0, summary["violations"]
    assert summary["level_share"]["emergency"] == 0.0
    # the bus's rear has cleared the second zebra
    bus_length = load_scenario(SCENARIO).automated["bus"].length_m
    assert trace["bus_x"].iloc[-1] - bus_length > SECOND_ZEBRA_X[1]

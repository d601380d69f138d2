"""The paper policy's levels and the situational picture on the real road map (no SUMO run
needed)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import shapely
from shapely.ops import substring

from sse_cosim.control.picture import (
    ArrivalMemory,
    ConflictZone,
    Picture,
    SceneContext,
    Source,
    _arrivals,
    arrival_floors,
    assess,
    route_piece,
    route_stations,
)
from sse_cosim.control.speed import SpeedLevel, level_speed, paper_level
from sse_cosim.estimation.motion import motion_model
from sse_cosim.regions import PolygonRegion as R
from sse_cosim.regions import kind
from sse_cosim.regions.polygon import OFFSET_MARGIN
from sse_cosim.scenario.loader import load_scenario
from sse_cosim.scenario.model import Estimator
from sse_cosim.world.network import build_network
from sse_cosim.world.roadmap import load_roadmap

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "s1_pedestrian.toml"
# a run takes the jitter measured for its network (sse_cosim/world/walker_jitter.py); the
# controller's geometry is tested with a fixed one
JITTER_M = 0.35
K = kind("polygon")
NOBODY = Source(K.empty())  # no undetected pedestrian anywhere


@pytest.fixture(scope="module")
def context() -> SceneContext:
    scenario = load_scenario(SCENARIO)
    roadmap = load_roadmap(build_network(scenario.network.sources_dir))
    bus = scenario.automated["bus"]
    dt = scenario.simulation.step_length_s
    pedestrians = motion_model(
        scenario.estimator.model_copy(update={"position_jitter_m": JITTER_M}), dt)
    return SceneContext.build(roadmap, bus.route_edges, bus, scenario.controller, pedestrians,
                              scenario.pedestrian_radius_m(), dt, K)


def picture(**changes) -> Picture:
    base = dict(front_s=100.0, front_drive_m=100.0, speed_mps=10.0, distance_to_crossing=98.0,
                crossing_ahead=False, reach_radius_m=5.0, own_occluded_m2=0.0,
                unresolved_occluded_m2=0.0,
                pedestrian_near_crossing=False, pedestrian_near_path=False,
                pedestrian_in_stopping_distance=False)
    return Picture(**{**base, **changes})


@pytest.mark.parametrize(
    ("changes", "level"),
    [
        ({}, SpeedLevel.NOMINAL),
        ({"unresolved_occluded_m2": 3.0}, SpeedLevel.CAUTIOUS),
        ({"unresolved_occluded_m2": 3.0, "crossing_ahead": True}, SpeedLevel.SLOW),
        ({"pedestrian_near_crossing": True, "crossing_ahead": True}, SpeedLevel.SLOW),
        ({"pedestrian_near_crossing": True}, SpeedLevel.NOMINAL),
        ({"own_occluded_m2": 50.0, "crossing_ahead": True}, SpeedLevel.NOMINAL),
        ({"pedestrian_near_path": True, "unresolved_occluded_m2": 3.0}, SpeedLevel.VERY_SLOW),
        ({"pedestrian_in_stopping_distance": True, "pedestrian_near_path": True},
         SpeedLevel.EMERGENCY),
    ],
)
def test_levels_follow_the_rules_most_severe_first(changes, level):
    config = load_scenario(SCENARIO).controller
    assert paper_level(picture(**changes), config, SpeedLevel.NOMINAL) is level


def test_level_speeds_are_the_configured_reductions():
    config = load_scenario(SCENARIO).controller
    speeds = [level_speed(level, 20.0, config) for level in SpeedLevel]
    assert speeds == pytest.approx([20.0, 14.0, 10.0, 4.0, 4.0, 0.0, 0.0])


def test_reach_radius_shrinks_as_the_bus_nears_and_vanishes_once_past(context):
    (crossing,) = context.crossings
    start, end = crossing.start_m, crossing.end_m
    radii = [context.reach_radius(s, context.path.drive(s))
             for s in (start - 60, start - 30, start - 5)]
    assert radii[0] > radii[1] > radii[2] > 0
    assert radii[0] <= context.config.interest_radius_m
    past = end + context.bus.length_m + 0.1
    assert context.reach_radius(past, context.path.drive(past)) == 0.0


def test_a_pedestrian_in_the_lane_ahead_triggers_an_emergency_stop(context):
    start = context.crossings[0].start_m
    front = np.array(context.route_line.interpolate(start - 20.0).coords[0])
    in_lane = shapely.Point(front + np.array([10.0, 0.0])).buffer(0.5)
    on_far_sidewalk = shapely.Point(front[0] + 10.0, 7.0).buffer(0.5)
    empty = K.empty()
    stop = assess(context, front, 14.0, empty, NOBODY, [Source(R(in_lane))])
    clear = assess(context, front, 14.0, empty, NOBODY, [Source(R(on_far_sidewalk))])
    assert stop.pedestrian_in_stopping_distance and stop.pedestrian_near_path
    assert not clear.pedestrian_near_path and not clear.pedestrian_in_stopping_distance


def test_hidden_area_counts_only_within_reach_of_the_crossing(context):
    start = context.crossings[0].start_m
    front = np.array(context.route_line.interpolate(start - 40.0).coords[0])
    near = shapely.box(196.0, -8.0, 198.0, -6.0)  # sidewalk right at the zebra
    far = shapely.box(150.0, -8.0, 152.0, -6.0)  # sidewalk 46 m before it
    for hidden, expected in ((near, True), (far, False)):
        result = assess(context, front, 20.0, R(hidden), Source(R(hidden)), [])
        assert (result.unresolved_occluded_m2 > 1.0) is expected
        assert result.own_occluded_m2 == pytest.approx(hidden.area, rel=1e-6)


def test_the_zebra_is_the_one_conflict_zone_on_the_route(context):
    (zone,) = context.zones
    (crossing,) = context.crossings
    start, end = crossing.start_m, crossing.end_m
    assert zone.start_m == pytest.approx(start, abs=1e-6)
    assert zone.end_m == pytest.approx(end, abs=1e-6)
    # the swept corridor: half the bus plus a pedestrian's radius either side of the lane
    # (and the margin every offset keeps for GEOS's shortcuts)
    lane_y = context.route_line.interpolate(start).y
    half = (0.5 * context.bus.width_m + 0.3) * (1.0 + OFFSET_MARGIN)
    assert zone.polygon.bounds[1] == pytest.approx(lane_y - half, abs=1e-6)
    assert zone.polygon.bounds[3] == pytest.approx(lane_y + half, abs=1e-6)


def test_arrival_is_the_distance_less_the_jitter_over_the_speed_bound(context):
    start = context.crossings[0].start_m
    front = np.array(context.route_line.interpolate(start - 40.0).coords[0])
    (zone,) = context.zones
    south = zone.polygon.bounds[1]
    pedestrian = shapely.Point(200.0, south - 5.0).buffer(0.5)  # 4.5 m from the zone
    empty = K.empty()
    result = assess(context, front, 10.0, empty, NOBODY, [Source(R(pedestrian))])
    (outlook,) = result.zones
    eps, speed = context.pedestrians.jitter, context.pedestrians.max_speed
    assert outlook.arrival_s == pytest.approx((4.5 - 2 * eps) / speed, abs=1e-3)
    assert outlook.to_start_m == pytest.approx(40.0, abs=1e-6)
    assert outlook.to_clear_m == pytest.approx(zone.end_m - zone.start_m + 40.0
                                               + context.bus.length_m, abs=1e-6)
    at_zebra = np.array(context.route_line.interpolate(start - 3.0).coords[0])
    # from standstill the bus needs about 5 s to clear the zebra: 1.6 s is too short
    assert not assess(context, at_zebra, 0.0, empty, NOBODY, [Source(R(pedestrian))]).path_clear
    far = shapely.Point(200.0, south - 40.0).buffer(0.5)
    assert assess(context, at_zebra, 0.0, empty, NOBODY, [Source(R(far))]).path_clear


def test_a_zone_counts_only_where_the_body_can_still_touch_it(context):
    """The bus stands with its rear 1 m onto the zebra: ground behind that is out of its way
    for good. A pedestrian on the sidewalk 3 m before the zebra arrives at the part of the
    zebra ahead of the rear, not at its near edge; so the standing bus may move on."""
    (zone,) = context.zones
    length = context.bus.length_m
    front_s = zone.start_m + length + 1.0
    front = np.array(context.route_line.interpolate(front_s).coords[0])
    rear_x = float(context.route_line.interpolate(front_s - length).x)
    south = zone.polygon.bounds[1]
    near_x = float(context.route_line.interpolate(zone.start_m).x)
    pedestrian = shapely.Point(near_x - 3.0, south - 1.0).buffer(0.3)
    empty = K.empty()
    result = assess(context, front, 0.0, empty, NOBODY, [Source(R(pedestrian))])
    (outlook,) = result.zones
    ahead = shapely.intersection(zone.ground, shapely.box(rear_x, -1e3, 1e3, 1e3))
    eps, speed = context.pedestrians.jitter, context.pedestrians.max_speed
    assert outlook.arrival_s == pytest.approx(
        (shapely.distance(pedestrian, ahead) - 2 * eps) / speed, abs=1e-3)
    whole = (shapely.distance(pedestrian, zone.ground) - 2 * eps) / speed
    assert outlook.arrival_s > whole + 0.3  # the whole zebra's near edge: 4 m nearer
    assert outlook.to_clear_m == pytest.approx(zone.end_m - zone.start_m - 1.0, abs=1e-6)


def front_before_zebra(context: SceneContext, metres: float) -> np.ndarray:
    """The point on the bus's route ``metres`` before the zebra, shape (2,)."""
    start = context.crossings[0].start_m
    return np.array(context.route_line.interpolate(start - metres).coords[0])


def test_a_pedestrian_in_view_who_may_be_beyond_the_window_arrives_as_early_as_from_beyond(
        context):
    front = front_before_zebra(context, 40.0)
    (zone,) = context.zones
    empty = K.empty()
    far = shapely.Point(200.0, zone.polygon.bounds[1] - 20.0).buffer(0.5)
    inside = assess(context, front, 10.0, empty, NOBODY, [Source(R(far))], [Source(R(far))])
    beyond = assess(context, front, 10.0, empty, NOBODY, [Source(R(far))], [Source(R(far))],
                    in_view_beyond=True)
    assert zone.beyond_arrival_s < inside.zones[0].in_view_arrival_s < np.inf
    assert beyond.zones[0].in_view_arrival_s == zone.beyond_arrival_s
    assert beyond.zones[0].arrival_s == inside.zones[0].arrival_s == zone.beyond_arrival_s


def test_an_arrival_comes_at_most_the_elapsed_time_sooner_than_the_last_picture_had_it(
        context):
    front = front_before_zebra(context, 40.0)
    (zone,) = context.zones
    empty = K.empty()
    south = zone.polygon.bounds[1]
    far = shapely.Point(200.0, south - 8.0).buffer(0.5)
    near = shapely.Point(200.0, south - 2.0).buffer(0.5)  # the set grew faster than the bound
    before = assess(context, front, 10.0, empty, NOBODY, [Source(R(far))])
    floors = arrival_floors(before, 0.1)
    assert floors == {0: pytest.approx(before.zones[0].arrival_s - 0.1)}
    now = assess(context, front, 10.0, empty, NOBODY, [Source(R(near))], floors=floors)
    assert now.zones[0].arrival_s == pytest.approx(before.zones[0].arrival_s - 0.1)
    alone = assess(context, front, 10.0, empty, NOBODY, [Source(R(near))])
    assert alone.zones[0].arrival_s < floors[0]
    nearer_later = assess(context, front, 10.0, empty, NOBODY, [Source(R(far))], floors={0: 0.0})
    assert nearer_later.zones[0].arrival_s == before.zones[0].arrival_s  # sets count too


def test_floors_come_only_from_a_picture_made_while_consistent(context):
    # ArrivalMemory: an inconsistent step gets no floors, and the picture it makes is not
    # kept: the next consistent step has no floors either, until a consistent picture is kept.
    front = front_before_zebra(context, 40.0)
    empty = K.empty()
    far = shapely.Point(200.0, context.zones[0].polygon.bounds[1] - 8.0).buffer(0.5)
    picture = assess(context, front, 10.0, empty, NOBODY, [Source(R(far))])
    memory = ArrivalMemory(0.1)
    assert memory.floors(1, inconsistent=False) == {}
    memory.keep(1, picture, inconsistent=False)
    assert memory.floors(3, inconsistent=False) == {
        0: pytest.approx(picture.zones[0].arrival_s - 0.2)}
    assert memory.floors(3, inconsistent=True) == {}
    memory.keep(3, picture, inconsistent=True)
    assert memory.floors(4, inconsistent=False) == {}
    memory.keep(4, picture, inconsistent=False)
    assert memory.floors(5, inconsistent=False) == {
        0: pytest.approx(picture.zones[0].arrival_s - 0.1)}


def test_arrivals_in_one_call_are_the_earliest_arrival_of_each_zone():
    # _arrivals measures every source to every zone in one shapely call: per zone, the same
    # earliest arrival as the nearest source's distance, minus the slack, over the speed.
    pedestrians = motion_model(Estimator(max_pedestrian_speed_mps=1.5, position_jitter_m=0.3),
                               0.1)  # slack 2 eps = 0.6 m
    rng = np.random.default_rng(3)
    for _ in range(50):
        sources = [shapely.box(x, y, x + w, y + h).buffer(rng.uniform(0.0, 1.0), quad_segs=2)
                   for x, y, w, h in rng.uniform(0.0, 20.0, size=(rng.integers(1, 4), 4))]
        zones = [shapely.box(x, y, x + 3.0, y + 2.0) for x, y in rng.uniform(0.0, 30.0, (3, 2))]
        got = _arrivals([Source(R(g)) for g in (shapely.Polygon(), *sources)],
                        [ConflictZone(R(z), 0.0, 0.0, np.inf) for z in zones], pedestrians, K)
        expected = [max(0.0, min(s.distance(z) for s in sources) - 0.6) / 1.5 for z in zones]
        assert got.tolist() == expected
    as_zones = [ConflictZone(R(z), 0.0, 0.0, np.inf) for z in zones]
    assert _arrivals([Source(K.empty())], as_zones, pedestrians, K).tolist() == [np.inf] * 3


def test_route_pieces_are_shapelys_substrings(context):
    # route_piece finds the vertices between two distances from stations computed once: the
    # same line string as shapely.ops.substring, on the real route and on random polylines
    # (distances on vertices too).
    rng = np.random.default_rng(8)
    lines = [context.route_line] + [
        shapely.LineString(np.cumsum(rng.normal(size=(rng.integers(2, 30), 2)), axis=0))
        for _ in range(20)]
    for line in lines:
        stations = route_stations(line)
        cuts = np.concatenate([rng.uniform(0.0, line.length, 20), stations, [line.length]])
        for start, end in rng.choice(cuts, size=(40, 2)):
            start, end = min(start, end), max(start, end)
            if start < end:
                got = route_piece(line, stations, start, end)
                assert shapely.to_wkb(got) == shapely.to_wkb(substring(line, start, end))


def test_the_kept_widening_of_a_crossing_is_its_dilation(context):
    crossing = context.crossings[0]
    for radius in (0.5, 3.0, 0.5):
        kept = context.relevant(crossing, radius)
        assert kept is context.relevant(crossing, radius)
        assert kept.shape.equals_exact(crossing.area.dilate(radius).shape, 0.0)
        # it holds every point within the radius of the crossing (the dilation contract)
        ring = crossing.area.shape.exterior.buffer(radius * (1 - 1e-9), quad_segs=64)
        assert kept.shape.covers(shapely.difference(ring, crossing.area.shape.buffer(-1e-9)))

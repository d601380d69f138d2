"""The swept path against SUMO: a 12 m bus turns right at the four-arm junction
(sumo_net/junction/, WJ -> JS through the internal lane :J_9_0, a 5.75 m radius), and every
step's footprint as the world reports it (an oriented rectangle from SUMO's front position and
angle) lies inside the swept region of control/swept.py, and is the model's footprint; the
centre line widened by half the width misses it by about a metre. And in the closed loop, a
pedestrian waiting on the corner's sidewalk where the bus's side sweeps (SUMO's body cuts the
corner) is given way to: no contact, no violation, and the bus turns once the pedestrian has
crossed the west zebra. (The zones before this model also held the bus there, since the
west zebra is 1.3 m away and the junction's 1.2 m jitter makes the pedestrian's arrival
there immediate; tests/control/test_swept.py shows the zone the corner now is.)
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import shapely
from swept_checks import assert_in_sweep, assert_placed_as_modelled, bus_footprints

from sse_cosim.control.swept import RoutePath, chord_footprint
from sse_cosim.runner.run import run_scenario_file
from sse_cosim.scenario.loader import load_scenario

ROOT = Path(__file__).resolve().parents[2]
TURN = ["WJ", "JS"]
SCENARIO = f"""
name = "right_turn"
description = "A bus turning right at the four-arm junction"
[simulation]
duration_s = 16.0
step_length_s = 0.1
seed = 1
[network]
sources_dir = "{ROOT / 'sumo_net' / 'junction'}"
[automated.bus]
route_edges = {TURN!r}
depart_pos_m = 120.0
nominal_speed_mps = 6.6
"""


@pytest.fixture(scope="module")
def footprints(tmp_path_factory: pytest.TempPathFactory) -> tuple[list, object, float, float]:
    """Every step's footprint corners (4, 2) of the turning bus, the road map and its size."""
    run_dir = tmp_path_factory.mktemp("right_turn")
    (run_dir / "right_turn.toml").write_text(SCENARIO)
    sc = load_scenario(run_dir / "right_turn.toml")
    bus = sc.automated["bus"]
    corners, roadmap = bus_footprints(sc, run_dir, "right_turn")
    return corners, roadmap, bus.length_m, bus.width_m


def test_every_footprint_lies_in_the_swept_region(footprints) -> None:
    corners, roadmap, length, width = footprints
    assert len(corners) > 100
    assert_in_sweep(corners, RoutePath.of_route(roadmap.route_lanes(TURN)), length, width)
    # the bus did turn: from east to south
    first, last = corners[0], corners[-1]
    assert (first[1] - first[0])[0] > 0 and (last[1] - last[0])[1] < 0
    band = roadmap.route_line(TURN).buffer(0.5 * width, cap_style="flat")
    missed = float(shapely.distance(band, shapely.points(np.vstack(corners))).max())
    assert 0.9 < missed < 1.1  # 1.01 m: the rear's outer corner swinging out


def test_the_model_places_the_body_as_sumo_does(footprints) -> None:
    corners, roadmap, length, width = footprints
    path = RoutePath.of_route(roadmap.route_lanes(TURN))
    assert_placed_as_modelled(corners, roadmap.route_line(TURN), path, length, width)


WAITING = SCENARIO.replace('duration_s = 16.0', 'duration_s = 60.0') + """
[controller]
interest_radius_m = 22.0
[estimator]
position_jitter_m = 1.2
[sensors.bus_front]
node = "bus"
fov_deg = 90.0
range_m = 60.0
noise_bound_m = [0.5, 0.5]
[sensors.bus_near]
node = "bus"
fov_deg = 360.0
range_m = 20.0
noise_bound_m = [0.3, 0.3]
[rsus.rsu_sw]
x_m = -7.0
y_m = -7.0
heading_deg = 45.0
[sensors.rsu_sw_range]
kind = "range"
node = "rsu_sw"
range_m = 35.0
range_bound_m = 0.3
bearing_bound_deg = 1.0
[pedestrians.pedestrian]
start_edge = "WJ"
start_pos_m = 172.0
end_edge = "JW"
end_pos_m = 160.0
walking_speed_mps = 1.4
steps_onto_crossing_s = 20.0
"""
CORNER_SPOT = (-8.0, -4.5)  # WJ's sidewalk, 0.5 m before its end: where the pedestrian waits


def test_a_pedestrian_waiting_where_the_body_cuts_the_corner_is_given_way_to(
        tmp_path: Path, footprints) -> None:
    _, roadmap, length, width = footprints
    path = RoutePath.of_route(roadmap.route_lanes(TURN))
    reach = min(shapely.Polygon(chord_footprint(path, s, length, width))
                .distance(shapely.Point(CORNER_SPOT)) for s in np.arange(150.0, 200.0, 0.1))
    assert reach == 0.0  # SUMO's body sweeps over the spot
    (tmp_path / "corner.toml").write_text(WAITING)
    summary = run_scenario_file(tmp_path / "corner.toml", tmp_path / "out", plots=False)
    assert summary["collisions"] == 0 and summary["containment_violations"] == 0
    assert summary["min_distance_bus_pedestrian_m"] > 1.0
    trace = pd.read_csv(tmp_path / "out" / "trace.csv")
    waiting = trace[trace["t"] < 20.0]
    assert waiting["bus_x"].max() < -10.0  # stood before the corner while the pedestrian waited
    assert trace["bus_y"].iloc[-1] < -20.0  # and turned into JS after it had crossed


# A priority junction whose left turns from the main road wait inside it: netconvert splits
# each such passage at an internal junction into two internal lanes, both driven by SUMO.
LEFT_NODES = """<nodes>
    <node id="J" x="0" y="0" type="priority"/>
    <node id="W" x="-100" y="0"/><node id="E" x="100" y="0"/>
    <node id="S" x="0" y="-100"/><node id="N" x="0" y="100"/>
</nodes>
"""
LEFT_ARMS = [("W", "J", 2, 2), ("J", "W", 2, 2), ("E", "J", 2, 2), ("J", "E", 2, 2),
             ("S", "J", 1, 1), ("J", "S", 1, 1), ("N", "J", 1, 1), ("J", "N", 1, 1)]
LEFT_EDGES = "<edges>\n" + "".join(
    f'    <edge id="{a}{b}" from="{a}" to="{b}" numLanes="{n}" priority="{p}" speed="13.89"'
    ' disallow="pedestrian"/>\n'
    for a, b, n, p in LEFT_ARMS) + "</edges>\n"
LEFT_OPTIONS = """<netconvertConfiguration>
    <processing><offset.disable-normalization value="true"/></processing>
    <junctions><no-turnarounds value="true"/></junctions>
</netconvertConfiguration>
"""


def test_a_left_turn_split_inside_the_junction_is_swept_on_both_internal_lanes(
        tmp_path: Path) -> None:
    sources = tmp_path / "left"
    sources.mkdir()
    (sources / "left.nod.xml").write_text(LEFT_NODES)
    (sources / "left.edg.xml").write_text(LEFT_EDGES)
    (sources / "netconvert.cfg").write_text(LEFT_OPTIONS)
    route = ["WJ", "JN"]
    scenario = SCENARIO.replace(str(ROOT / "sumo_net" / "junction"), str(sources)).replace(
        repr(TURN), repr(route)).replace("depart_pos_m = 120.0", "depart_pos_m = 60.0").replace(
        "nominal_speed_mps = 6.6", "nominal_speed_mps = 5.0")
    (tmp_path / "left.toml").write_text(scenario)
    sc = load_scenario(tmp_path / "left.toml")
    bus = sc.automated["bus"]
    corners, roadmap = bus_footprints(sc, tmp_path, "left")
    passage = [lane for lane in roadmap.route_lanes(route) if lane.id.startswith(":")]
    assert len(passage) == 2  # split at the internal junction
    path = RoutePath.of_route(roadmap.route_lanes(route))
    assert_in_sweep(corners, path, bus.length_m, bus.width_m)
    assert (corners[-1][1] - corners[-1][0])[1] > 0  # it turned north
    assert_placed_as_modelled(corners, roadmap.route_line(route), path, bus.length_m,
                              bus.width_m)

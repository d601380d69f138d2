"""The swept path on two tight corners of a real town, in SUMO: a 12 m, 2.55 m wide bus (the
scenario's bus type) drives the way bus lines 300, 360, 380 and 470 take through the old town
of Bad Hersfeld, cut from the OpenStreetMap extract into tests/networks/town_corner/ (its
README says how, and how the corners were found): along Hainstrasse, right into
Abt-Michael-Strasse at a priority junction (79 degrees on two internal lanes, 5.56 m and
4.10 m, split where the bus waits for the zebra), then right into Bruedergasse at a
right-before-left junction (86 degrees on one internal lane of 8.34 m).

Every step's footprint as the world reports it (SUMO's front position and angle) lies in the
swept region of control/swept.py and is the model's footprint, within 1e-6 m. The centre
line widened by half the width misses SUMO's body on these corners, but not at the front:
SUMO keeps the front bumper on the lane's centre line, so the front corners stay on that band;
the rear's outer corner swings out (0.96 m) and the side cuts in over the corners' walkable
ground (2.24 m). The front's part in it: turning into Bruedergasse, the body's right side,
within 2.5 m of the front bumper, is the first of it to reach a spot of the inner corner's
walking area 1.1 m beyond the band. A pedestrian standing there is in a conflict zone, with
no pass possible; the old zones left it out.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import shapely
from swept_checks import (
    TOLERANCE_M,
    assert_in_sweep,
    assert_in_the_way,
    assert_placed_as_modelled,
    bus_footprints,
)

from sse_cosim.control.picture import SceneContext
from sse_cosim.control.swept import RoutePath, body_sweep, swept_region
from sse_cosim.estimation.motion import motion_model
from sse_cosim.regions import kind
from sse_cosim.scenario.loader import load_scenario
from sse_cosim.scenario.model import Scenario
from sse_cosim.world.roadmap import RoadMap

K = kind("polygon")

ROOT = Path(__file__).resolve().parents[2]
NET = ROOT / "tests" / "networks" / "town_corner" / "corner.net.xml"
ROUTE = ["124416783#1", "25946390#1", "25946391"]  # Hainstrasse, Abt-Michael-Str., Bruedergasse
SCENARIO = f"""
name = "town_corner"
description = "A bus through two tight corners of Bad Hersfeld's old town"
[simulation]
duration_s = 40.0
step_length_s = 0.1
seed = 1
[network]
net_file = "{NET}"
[automated.bus]
route_edges = {ROUTE!r}
depart_pos_m = 13.0
nominal_speed_mps = 6.0
"""
# on the walking area at the inner corner of Abt-Michael-Strasse and Bruedergasse (the cut's
# coordinates; the whole converted town's are these plus (6755.85, 7524.71))
CUT_IN_SPOT = (169.1, 133.0)
FRONT_PART_M = 2.5  # the body's first 2.5 m behind the front bumper


@pytest.fixture(scope="module")
def town_run(tmp_path_factory: pytest.TempPathFactory,
             ) -> tuple[list[np.ndarray], RoadMap, Scenario]:
    """Every step's footprint corners (4, 2) of the bus, the road map and the scenario."""
    run_dir = tmp_path_factory.mktemp("town_corner")
    (run_dir / "town_corner.toml").write_text(SCENARIO)
    sc = load_scenario(run_dir / "town_corner.toml")
    corners, roadmap = bus_footprints(sc, run_dir, "town_corner")
    return corners, roadmap, sc


def body_offsets(rectangle: np.ndarray, point: np.ndarray) -> tuple[float, float]:
    """How far ``point`` (2,) lies behind the front bumper of the footprint ``rectangle``
    (4, 2) and left of its axis (m)."""
    left = (rectangle[2] - rectangle[1]) / np.linalg.norm(rectangle[2] - rectangle[1])
    ahead = np.array([left[1], -left[0]])
    offset = point - 0.5 * (rectangle[1] + rectangle[2])
    return float(-offset @ ahead), float(offset @ left)


def test_every_footprint_on_the_town_corners_lies_in_the_swept_region(town_run) -> None:
    corners, roadmap, sc = town_run
    bus = sc.automated["bus"]
    passage = [lane for lane in roadmap.route_lanes(ROUTE[:2]) if lane.id.startswith(":")]
    assert len(passage) == 2  # split before the zebra
    path = RoutePath.of_route(roadmap.route_lanes(ROUTE))
    assert_in_sweep(corners, path, bus.length_m, bus.width_m)
    line = roadmap.route_line(ROUTE)
    assert_placed_as_modelled(corners, line, path, bus.length_m, bus.width_m)
    # the bus drove the whole route: west along Hainstrasse first, east along Bruedergasse last
    last = corners[-1]
    assert (corners[0][1] - corners[0][0])[0] < 0 and (last[1] - last[0])[0] > 0
    assert line.project(shapely.Point(0.5 * (last[1] + last[2]))) > line.length - 1.0


def test_the_front_stays_on_the_band_the_rear_swings_out_and_the_side_cuts_in(
        town_run) -> None:
    corners, roadmap, sc = town_run
    band = roadmap.route_line(ROUTE).buffer(0.5 * sc.automated["bus"].width_m,
                                            cap_style="flat")
    rectangles = np.array(corners)  # (k, 4, 2): rear right, front right, front left, rear left
    front = shapely.distance(band, shapely.points(rectangles[:, 1:3].reshape(-1, 2)))
    rear = shapely.distance(band, shapely.points(rectangles[:, [0, 3]].reshape(-1, 2)))
    assert float(front.max()) <= TOLERANCE_M  # SUMO's front corners never leave the band
    assert 0.9 < float(rear.max()) < 1.0  # 0.96 m: the rear's outer corner swinging out
    walkable = roadmap.ground
    over = shapely.intersection(shapely.polygons(rectangles), walkable)  # (k,)
    cut_in = shapely.distance(band, shapely.points(shapely.get_coordinates(over)))
    assert 2.1 < float(cut_in.max()) < 2.4  # 2.24 m: the side over the corners' walkable ground


def test_a_pedestrian_where_the_front_cuts_the_corner_is_in_the_way(town_run) -> None:
    corners, roadmap, sc = town_run
    bus = sc.automated["bus"]
    spot = shapely.Point(CUT_IN_SPOT)
    radius = sc.pedestrian_radius_m()
    line = roadmap.route_line(ROUTE)
    band = line.buffer(0.5 * bus.width_m, cap_style="flat")
    assert spot.within(roadmap.ground)
    beyond = band.distance(spot)
    assert 1.0 < beyond < 1.2  # 1.11 m beyond the band: the old zones missed it
    # SUMO's body covers the spot, and the first footprint to reach it holds it within the
    # body's first 2.5 m, on its right side (the inside of the right turn)
    covering = [c for c in corners if shapely.Polygon(c).contains(spot)]
    assert covering
    behind, left = body_offsets(covering[0], np.array(CUT_IN_SPOT))
    assert 0.0 < behind <= FRONT_PART_M and left < 0.0
    path = RoutePath.of_route(roadmap.route_lanes(ROUTE))
    assert spot.within(swept_region(body_sweep(path, bus.length_m, bus.width_m)))
    # the controller's zones: in one, with every front station at which SUMO's body touches
    # the pedestrian, and a pedestrian standing there leaves no pass (whatever the jitter: it
    # stands in the zone)
    dt = sc.simulation.step_length_s
    pedestrians = motion_model(sc.estimator.model_copy(update={"position_jitter_m": 0.3}), dt)
    context = SceneContext.build(roadmap, ROUTE, bus, sc.controller, pedestrians, radius, dt,
                                 K)
    touching = [line.project(shapely.Point(0.5 * (c[1] + c[2]))) for c in corners
                if shapely.Polygon(c).distance(spot) <= radius]
    assert_in_the_way(context, spot, radius, touching, min(touching) - 20.0)


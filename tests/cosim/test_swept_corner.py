"""The swept path against SUMO: a 12 m bus turns right at the four-arm junction
(sumo_net/junction/, WJ -> JS through the internal lane :J_9_0, a 5.75 m radius), and every
step's footprint as the world reports it (an oriented rectangle from SUMO's front position and
angle) lies inside the swept region of control/swept.py, and is the model's footprint; the
centre line widened by half the width misses it by about a metre.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import shapely

from sse_cosim.control.picture import route_lanes
from sse_cosim.control.swept import RoutePath, body_sweep, chord_footprint, swept_region
from sse_cosim.scenario.loader import load_scenario
from sse_cosim.world.sumo import SumoWorld

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
    with SumoWorld(sc, run_dir, "right_turn") as world:
        corners = []
        for _ in range(round(sc.simulation.duration_s / sc.simulation.step_length_s)):
            vehicle = world.step().vehicles.get("bus")
            if vehicle is not None:
                corners.append(vehicle.footprint.corners())
        return corners, world.roadmap, bus.length_m, bus.width_m


def test_every_footprint_lies_in_the_swept_region(footprints) -> None:
    corners, roadmap, length, width = footprints
    path = RoutePath.of_lanes(route_lanes(roadmap, TURN))
    region = swept_region(body_sweep(path, length, width))
    points = shapely.points(np.vstack(corners))
    assert len(corners) > 100
    assert float(shapely.distance(region, points).max()) <= 1e-6
    # the bus did turn: from east to south
    first, last = corners[0], corners[-1]
    assert (first[1] - first[0])[0] > 0 and (last[1] - last[0])[1] < 0
    band = roadmap.route_line(TURN).buffer(0.5 * width, cap_style="flat")
    missed = float(shapely.distance(band, points).max())
    assert 0.9 < missed < 1.1  # 1.01 m: the rear's outer corner swinging out


def test_the_model_places_the_body_as_sumo_does(footprints) -> None:
    corners, roadmap, length, width = footprints
    path = RoutePath.of_lanes(route_lanes(roadmap, TURN))
    line = roadmap.route_line(TURN)
    for rectangle in corners:
        front = 0.5 * (rectangle[1] + rectangle[2])
        sigma = float(np.interp(line.project(shapely.Point(front)), path.station, path.sigma))
        assert np.abs(chord_footprint(path, sigma, length, width) - rectangle).max() <= 1e-6

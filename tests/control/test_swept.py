"""The body's swept path (control/swept.py) and the conflict zones built on it (no SUMO run):
on a straight road the sweep is the old corridor, bit for bit in the zones; on the four-arm
junction's right turn (sumo_net/junction/, WJ -> JS, a 5.75 m radius) a 12 m bus's rear swings
out over the west zebra and its side cuts over the corner, and a pedestrian standing where only
the swinging rear reaches is a conflict for the controller. tests/cosim/test_swept_corner.py
checks the model against SUMO's own footprints.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import shapely
from swept_checks import assert_in_the_way

from sse_cosim.control.picture import SceneContext
from sse_cosim.control.swept import (
    MAX_PIECE_M,
    RoutePath,
    ahead_cover,
    body_sweep,
    chord_footprint,
    footprint,
    swept_region,
    touch_intervals,
)
from sse_cosim.estimation.motion import motion_model
from sse_cosim.regions import kind
from sse_cosim.regions.polygon import OFFSET_MARGIN
from sse_cosim.scenario.loader import load_scenario
from sse_cosim.scenario.model import Estimator
from sse_cosim.world.network import build_network
from sse_cosim.world.roadmap import RoadMap, load_roadmap

K = kind("polygon")

ROOT = Path(__file__).resolve().parents[2]
JUNCTION = ROOT / "scenarios" / "junction.toml"
TURN = ["WJ", "JS"]  # east along WJ, then right into JS
LENGTH, WIDTH = 12.0, 2.55
# on the west zebra (x -7.5 .. -3.5), left of the bus's lane (y = -1.75): the corridor around
# the centre line (half the width plus the pedestrian's radius, 0.3 m) ends at y = -0.175, the
# rear's left corner swings out to y = 0.43 at the zebra's edge
SWING_SPOT = (-7.4, 0.2)


@pytest.fixture(scope="module")
def roadmap() -> RoadMap:
    return load_roadmap(build_network(ROOT / "sumo_net" / "junction"))


def turn_context(roadmap: RoadMap) -> SceneContext:
    sc = load_scenario(JUNCTION, {"automated.bus_we.route_edges": TURN})
    dt = sc.simulation.step_length_s
    return SceneContext.build(roadmap, TURN, sc.automated["bus_we"], sc.controller,
                              motion_model(sc.estimator, dt), sc.pedestrian_radius_m(), dt, K)


def test_a_straight_route_sweeps_the_centre_line_widened_by_half_the_width() -> None:
    path = RoutePath.of_lanes([(np.array([[0.0, -1.75], [100.0, -1.75]]), 100.0),
                               (np.array([[100.0, -1.75], [300.0, -1.75]]), 200.0)])
    pieces = body_sweep(path, LENGTH, WIDTH)
    region = swept_region(pieces)
    line = shapely.LineString(path.points)
    corridor = line.buffer(0.5 * WIDTH, cap_style="flat")
    behind = shapely.box(-LENGTH, -1.75 - 0.5 * WIDTH, 0.0, -1.75 + 0.5 * WIDTH)  # the start
    assert shapely.symmetric_difference(region, shapely.union(corridor, behind)).area < 1e-9
    assert all(p.straight for p in pieces)
    zebra = shapely.box(198.0, -6.0, 202.0, 6.0)
    [touched] = touch_intervals(pieces, zebra, LENGTH)
    assert touched == pytest.approx((198.0, 202.0), abs=1e-12)
    assert chord_footprint(path, 150.0, LENGTH, WIDTH) == pytest.approx(
        footprint(np.array([150.0, -1.75]), np.array([1.0, 0.0]), LENGTH, WIDTH))
    # from a front at 150 m on, the body covers the band from its rear (138 m) to the end
    ahead = ahead_cover(pieces, 150.0, LENGTH, WIDTH)
    band = shapely.box(150.0 - LENGTH, -1.75 - 0.5 * WIDTH, 300.0, -1.75 + 0.5 * WIDTH)
    assert shapely.symmetric_difference(ahead, band).area < 1e-9


@pytest.mark.parametrize("offset", [(0.0, 0.0), (6_700.0, 8_800.0), (500_000.0, 5_600_000.0)])
@pytest.mark.parametrize("heading", [0.0, 0.3, 1.0, 2.5])
def test_a_straight_route_anywhere_at_any_heading_keeps_its_exact_zone(
        offset: tuple[float, float], heading: float) -> None:
    """The same route moved to a town's coordinates and to UTM-sized ones, turned to any
    heading: one rounding step there (9e-13 m at 6,700 m, 9e-10 m at 5,600 km) is more than
    the straight test's 1e-12 m, yet the pieces are worked out about a point of the route, so
    a piece on one lane stays straight and every piece that does not is cut to at most
    MAX_PIECE_M; the zebra's touch extent and the cover ahead are those at the origin.
    Before, a 88.8 m piece at (6,700, 8,800) counted as turning uncut, and the zones around
    it stretched over its whole length (issue: live on real streets)."""
    c, s_ = np.cos(heading), np.sin(heading)
    turn = np.array([[c, -s_], [s_, c]])
    at = np.asarray(offset)

    def place(xy: np.ndarray) -> np.ndarray:
        return np.asarray(xy, dtype=float) @ turn.T + at

    def placed(geometry: shapely.Geometry) -> shapely.Geometry:
        return shapely.transform(geometry, place)

    path = RoutePath.of_lanes([(place([[0.0, -1.75], [100.0, -1.75]]), 100.0),
                               (place([[100.0, -1.75], [300.0, -1.75]]), 200.0)])
    pieces = body_sweep(path, LENGTH, WIDTH)
    assert all(p.straight or p.end_m - p.start_m <= MAX_PIECE_M + 1e-9 for p in pieces)
    assert sum(p.end_m - p.start_m for p in pieces if p.straight) > 280.0  # all but joints
    zebra = placed(shapely.box(198.0, -6.0, 202.0, 6.0))
    [touched] = touch_intervals(pieces, zebra, LENGTH)
    assert touched == pytest.approx((198.0, 202.0), abs=1e-6)
    ahead = ahead_cover(pieces, 150.0, LENGTH, WIDTH)
    band = placed(shapely.box(150.0 - LENGTH, -1.75 - 0.5 * WIDTH, 300.0,
                              -1.75 + 0.5 * WIDTH))
    assert shapely.symmetric_difference(ahead, band).area < 1e-4


def test_the_straight_routes_of_the_junction_keep_their_zones(roadmap: RoadMap) -> None:
    """bus_we and bus_sn drive straight across: their zones are the corridor's, as before."""
    sc = load_scenario(JUNCTION)
    pedestrians = motion_model(Estimator(max_pedestrian_speed_mps=2.5, position_jitter_m=1.2),
                               0.1)
    for bus_id in ("bus_we", "bus_sn"):
        bus = sc.automated[bus_id]
        context = SceneContext.build(roadmap, bus.route_edges, bus, sc.controller, pedestrians,
                                     sc.pedestrian_radius_m(), 0.1, K)
        zones = [(z.polygon.area, z.start_m, z.end_m) for z in context.zones]
        area = 12.6 * (1.0 + OFFSET_MARGIN)  # a corridor widened by GEOS's margin
        assert np.array(zones) == pytest.approx(np.array([(area, 172.5, 176.5),
                                                          (area, 183.5, 187.5)]))


def test_on_the_right_turn_the_sweep_covers_every_footprint(roadmap: RoadMap) -> None:
    """Footprints with the front at 4,000 stations along the turn (not the pieces' ends) lie in
    the swept region; the old band misses the rear corner by about a metre."""
    path = RoutePath.of_route(roadmap.route_lanes(TURN))
    pieces = body_sweep(path, LENGTH, WIDTH)
    region = swept_region(pieces)
    band = roadmap.route_line(TURN).buffer(0.5 * WIDTH, cap_style="flat")
    sigmas = np.linspace(150.0, 200.0, 4001) + 1e-3 / 3.0
    corners = np.vstack([chord_footprint(path, s, LENGTH, WIDTH) for s in sigmas])  # (4k, 2)
    points = shapely.points(corners)
    assert float(shapely.distance(region, points).max()) <= 1e-9
    missed = float(shapely.distance(band, points).max())
    assert 0.9 < missed < 1.1  # the old zone's miss: about 1.0 m


def test_the_cover_ahead_holds_every_footprint_to_come_and_none_left_behind(
        roadmap: RoadMap) -> None:
    """From a front station inside the turn, the footprints with the front there or beyond
    (4,000, off the pieces' ends) lie in the cover ahead; the first footprints of the route do
    not, nor does the rear's position a few metres back."""
    path = RoutePath.of_route(roadmap.route_lanes(TURN))
    pieces = body_sweep(path, LENGTH, WIDTH)
    sigma = 170.0
    front_m = float(np.interp(sigma, path.sigma, path.station))
    ahead = ahead_cover(pieces, front_m, LENGTH, WIDTH)
    sigmas = np.linspace(sigma, float(path.sigma[-1]), 4001)[:-1] + 1e-3 / 3.0
    corners = np.vstack([chord_footprint(path, s, LENGTH, WIDTH) for s in sigmas])  # (4k, 2)
    assert float(shapely.distance(ahead, shapely.points(corners)).max()) <= 1e-9
    behind = chord_footprint(path, float(path.sigma[0]) + LENGTH, LENGTH, WIDTH)
    assert not shapely.intersects(ahead, shapely.Polygon(behind))
    rear_then = chord_footprint(path, sigma - 3.0, LENGTH, WIDTH)[0]  # its rear right corner
    assert not shapely.intersects(ahead, shapely.Point(rear_then))


def test_a_pedestrian_where_only_the_swinging_rear_reaches_is_a_conflict(
        roadmap: RoadMap) -> None:
    context = turn_context(roadmap)
    spot = shapely.Point(SWING_SPOT)
    radius = 0.3
    # a footprint reaches the pedestrian there: the rear corner, while the bus turns; the old
    # zones (corridor and walkable) left it out, and a pedestrian standing there arrives in
    # its zone at once: no pass is possible
    path = RoutePath.of_route(roadmap.route_lanes(TURN))
    touching = [float(np.interp(s, path.sigma, path.station))
                for s in np.arange(150.0, 200.0, 0.05)
                if shapely.Polygon(chord_footprint(path, s, LENGTH, WIDTH)).distance(spot)
                <= radius]
    assert_in_the_way(context, spot, radius, touching, 150.0)


def test_on_the_right_turn_the_side_cutting_in_reaches_the_corner(roadmap: RoadMap) -> None:
    """The body's side cuts over the sidewalk at the corner's inside: a zone there, which
    the old corridor did not have."""
    context = turn_context(roadmap)
    corner = shapely.box(-7.5, -7.5, -3.5, -3.5)  # the walking area inside the turn
    assert any(z.polygon.shape.intersects(corner)
               and not z.polygon.shape.within(roadmap.crossing_area)
               for z in context.zones)


def test_ground_the_route_passes_twice_is_touched_along_two_stretches():
    """Out along a street and back along its other side, around a block: a median between both
    directions is touched on the way out and on the way back, and not in between (the body is
    around the block); each stretch is exact on the straight pieces."""
    out = np.array([[0.0, -1.75], [100.0, -1.75]])
    around = np.array([[100.0, -1.75], [100.0, -40.0], [140.0, -40.0], [140.0, 1.75]])
    back = np.array([[140.0, 1.75], [0.0, 1.75]])
    path = RoutePath.of_lanes([(out, 100.0), (around, 120.0), (back, 140.0)])
    pieces = body_sweep(path, LENGTH, WIDTH)
    median = shapely.box(40.0, -0.6, 44.0, 0.6)  # within half the width of both passes
    first, second = touch_intervals(pieces, median, LENGTH)
    assert first == pytest.approx((40.0, 44.0), abs=1e-9)
    assert second == pytest.approx((220.0 + 96.0, 220.0 + 100.0), abs=1e-9)


def test_a_lane_drawn_shorter_than_sumos_position_eps_is_walked_as_sumo_does():
    """SUMO maps lane positions onto a lane's shape with the factor max(0.1 m, shape length) /
    length (``MSLane``), stopping at the shape's end: on line 300's junction lane of 0.10 m
    drawn 0.089 m long, the front at 0.055 m into it is 0.055 m along the shape (not 0.049 m,
    as a plain stretch has it: 6 mm off, which stopped the run), and from 0.089 m on it stands
    at the shape's end until the next lane."""
    before = np.array([[7067.15, 7899.82], [7067.33, 7899.92]])
    short = np.array([[7067.33, 7899.92], [7067.41, 7899.96]])
    after = np.array([[7067.41, 7899.96], [7088.19, 7909.77]])
    path = RoutePath.of_lanes([(before, 0.21), (short, 0.10), (after, 22.98)])
    heading = (short[1] - short[0]) / np.hypot(*(short[1] - short[0]))
    assert path.point_at(0.21 + 0.055)[0] == pytest.approx(short[0] + 0.055 * heading, abs=1e-12)
    for into in (0.0895, 0.095, 0.0999):
        assert path.point_at(0.21 + into)[0] == pytest.approx(short[1], abs=1e-12)
    stretch = (after[1] - after[0]) / 22.98  # a lane drawn longer: a plain stretch
    assert path.point_at(0.31 + 1.0)[0] == pytest.approx(after[0] + stretch, abs=1e-9)

"""Properties of the sector, line-of-sight and region machinery on random scenes.

The compiled kernels (sensors/kernels.py) call libm's sin, cos, atan2 and hypot; the NumPy
references NumPy's, which on CPUs with AVX-512 are SIMD code that may differ in the last bits.
Their coordinates are compared within bounds built from :data:`TRIG_ATOL` and
:data:`ANGLE_ATOL`, their decisions where such a difference cannot turn them. Products, sums
and comparisons that both sides do alike (the box frames, the separating axes, the range
test) are IEEE arithmetic, the same bits on every CPU, and are compared exactly.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import given
from hypothesis import strategies as st
from sensors_scene import SETTINGS

from sse_cosim.sensors import (
    Boxes,
    box_distances,
    box_distances_reference,
    in_sector,
    kernels,
    line_of_sight,
    sector_polygon,
    shadow_points_reference,
    shadow_polygons,
    sight_masks,
    sight_masks_reference,
    visibility_regions,
)
from sse_cosim.sensors.geometry import FAR_STEPS, sector_polygon_reference
from sse_cosim.world.snapshot import Footprint, Pose

EPS = float(np.finfo(np.float64).eps)
TRIG_ATOL = 4 * EPS
"""How far apart two implementations' sin or cos may be: glibc's are within 1 ulp, NumPy's SIMD
ones (AVX-512) within a few; an ulp of a value in [-1, 1] is <= eps/2, so 4 eps allows 8."""
ANGLE_ATOL = 16 * EPS
"""The same for arctan2, whose values in [-pi, pi] have ulps <= 2 eps: 16 eps allows 8."""

coord = st.floats(-30.0, 30.0)
angle = st.floats(-math.pi, math.pi)
poses = st.builds(Pose, coord, coord, angle)
footprints = st.builds(Footprint, poses, st.floats(1.0, 12.0), st.floats(0.8, 3.0))
fovs = st.one_of(st.floats(math.radians(10), math.radians(350)), st.just(2 * math.pi))
ranges = st.floats(5.0, 50.0)
seeds = st.integers(0, 2**32 - 1)


def wrapped(a: np.ndarray) -> np.ndarray:
    return (a + np.pi) % (2 * np.pi) - np.pi


def bearing_is_clear(origins: np.ndarray, headings: np.ndarray, fovs: np.ndarray,
                     targets: np.ndarray) -> np.ndarray:
    """(s, k): whether the sector's angular test dᵀ(cos h, sin h) >= |d| cos(fov/2) on each
    target (d = target - origin) holds or fails by more than two implementations' cos and sin
    can move its sides (TRIG_ATOL on each factor, and the roundings of the sums); a disc
    (fov = 2 pi) has none. The range test |d|² <= reach² is the same IEEE arithmetic on both
    sides and needs no margin."""
    dx = targets[None, :, 0] - origins[:, 0:1]
    dy = targets[None, :, 1] - origins[:, 1:2]
    dist = np.sqrt(dx * dx + dy * dy)
    heading, half = headings[:, None], 0.5 * fovs[:, None]
    along = dx * np.cos(heading) + dy * np.sin(heading)
    room = 4 * (TRIG_ATOL + EPS) * (np.abs(dx) + np.abs(dy) + dist)
    return (np.abs(along - dist * np.cos(half)) > room) | (fovs[:, None] >= 2 * np.pi)


@SETTINGS
@given(poses, fovs, ranges, seeds)
def test_in_sector_matches_bearings(pose, fov, reach, seed):
    rng = np.random.default_rng(seed)
    pts = pose.position + rng.uniform(-1.2 * reach, 1.2 * reach, size=(300, 2))
    d = pts - pose.position
    dist = np.hypot(d[:, 0], d[:, 1])
    off = np.abs(wrapped(np.arctan2(d[:, 1], d[:, 0]) - pose.heading))
    want = (dist <= reach) & ((off <= 0.5 * fov) | (fov >= 2 * math.pi))
    clear = (np.abs(dist - reach) > 1e-9) & (np.abs(off - 0.5 * fov) > 1e-9)
    got = in_sector(pose, fov, reach, pts)
    assert got.shape == (300,) and got.dtype == bool
    assert np.array_equal(got[clear], want[clear])


@SETTINGS
@given(st.lists(footprints, max_size=5), poses, seeds)
def test_line_of_sight_matches_shapely_segments(feet, origin_pose, seed):
    rng = np.random.default_rng(seed)
    origin = origin_pose.position
    targets = rng.uniform(-40.0, 40.0, size=(60, 2))
    got = line_of_sight(origin, targets, feet)
    assert got.shape == (60,)
    polygons = np.array([f.polygon() for f in feet], dtype=object)
    segments = shapely.linestrings(np.stack([np.broadcast_to(origin, targets.shape), targets], 1))
    # Decide robustly with shapely: blocked if the segment meets the box shrunk by 1e-7,
    # clear if it stays 1e-7 away from it; grazing pairs (neither) may go either way.
    shrunk = shapely.buffer(polygons, -1e-7, join_style="mitre")
    blocked = shapely.intersects(segments[:, None], shrunk[None, :]).any(axis=1)
    clear = (shapely.distance(segments[:, None], polygons[None, :]) > 1e-7).all(axis=1)
    assert not np.any(blocked & clear)
    assert np.all(got[blocked] == False)  # noqa: E712
    assert np.all(got[clear])


def test_line_of_sight_edge_cases():
    boxes = Boxes.from_footprints([Footprint(Pose(10.0, 0.0, 0.0), 4.0, 2.0)])  # x 6..10, y -1..1
    o = np.array([0.0, 0.0])
    pts = np.array([[20.0, 0.0], [18.0, 3.0], [18.0, 3.05], [5.0, 0.0], [8.0, 0.0], [0.0, 0.0]])
    # through; grazing the corner (6, 1) (closed: blocked); just above; short; inside; itself
    assert line_of_sight(o, pts, boxes).tolist() == [False, False, True, True, False, True]
    assert line_of_sight(o, pts, Boxes.empty()).all()
    assert line_of_sight(o, np.zeros((0, 2)), boxes).shape == (0,)


@SETTINGS
@given(st.lists(footprints, max_size=5), poses, fovs, ranges, seeds)
def test_regions_partition_the_sector_and_agree_with_line_of_sight(feet, pose, fov, reach, seed):
    boxes = Boxes.from_footprints(feet)
    sector = sector_polygon(pose, fov, reach, 16)
    visible, occluded = visibility_regions(pose, fov, reach, boxes, resolution=16)
    assert visible.area + occluded.area == pytest.approx(sector.area, rel=1e-6)
    assert visible.intersection(occluded).area <= 1e-6 * sector.area

    rng = np.random.default_rng(seed)
    pts = pose.position + rng.uniform(-1.1 * reach, 1.1 * reach, size=(400, 2))
    # Away from every region boundary by more than the arc's sagitta (< 0.06 m here): the
    # inscribed polygon and the exact sector agree there.
    margin = 0.1
    far = (shapely.distance(shapely.points(pts), visible.boundary) > margin) & (
        shapely.distance(shapely.points(pts), occluded.boundary) > margin
    )
    seen = in_sector(pose, fov, reach, pts) & line_of_sight(pose.position, pts, boxes)
    in_visible = shapely.contains_xy(visible, pts[:, 0], pts[:, 1])
    in_occluded = shapely.contains_xy(occluded, pts[:, 0], pts[:, 1])
    assert np.array_equal(in_visible[far], seen[far])
    assert np.array_equal(in_occluded[far], (in_sector(pose, fov, reach, pts) & ~seen)[far])


def test_regions_with_no_occluder_are_the_sector():
    pose = Pose(0.0, 0.0, 0.5)
    far_box = Boxes.from_footprints([Footprint(Pose(100.0, 0.0, 0.0), 4.0, 2.0)])
    visible, occluded = visibility_regions(pose, math.radians(90), 30.0, far_box)
    assert visible.equals(sector_polygon(pose, math.radians(90), 30.0)) and occluded.is_empty


def test_shadow_reaches_beyond_the_range_even_when_wide():
    # Origin 1 cm from a long box's side: the silhouette spans nearly 180°.
    boxes = Boxes.from_footprints([Footprint(Pose(20.0, 0.0, 0.0), 40.0, 2.0)])
    origin = np.array([0.0, 1.01])
    (shadow,) = shadow_polygons(origin, boxes, 30.0)
    disc = shapely.Point(origin).buffer(30.0, quad_segs=32)
    behind = disc.intersection(shapely.box(-40.0, -40.0, 40.0, 0.9))  # wholly behind the box
    assert shadow.contains(behind.difference(shapely.box(-0.1, -40.0, 40.1, 40.0)))


@pytest.mark.kernels
@SETTINGS
@given(st.lists(footprints, min_size=1, max_size=5), st.lists(poses, min_size=1, max_size=4), seeds)
def test_sight_masks_match_the_per_sensor_tests(feet, sensor_poses, seed):
    rng = np.random.default_rng(seed)
    boxes = Boxes.from_footprints(feet)
    s, m = len(sensor_poses), len(feet)
    fov = rng.uniform(0.2, 2 * np.pi, size=s)
    reach = rng.uniform(5.0, 50.0, size=s)
    carriers = rng.integers(-1, m, size=s)
    targets = rng.uniform(-40.0, 40.0, size=(30, 2))
    origins = np.array([p.position for p in sensor_poses])
    headings = np.array([p.heading for p in sensor_poses])
    seen, occluders = sight_masks(origins, headings, fov, reach, carriers, targets, boxes)
    assert seen.shape == (s, 30) and occluders.shape == (s, m)
    for j, pose in enumerate(sensor_poses):
        others = np.arange(m) != carriers[j]
        assert not occluders[j, carriers[j]] if carriers[j] >= 0 else True
        clear = line_of_sight(pose.position, targets, boxes.subset(others))
        want = in_sector(pose, fov[j], reach[j], targets) & clear
        # The sector's angle by NumPy's cos here, libm's in the kernel: compared where the
        # rounding cannot turn it; elsewhere seen only within range and in sight.
        decided = bearing_is_clear(pose.position[None, :], np.array([pose.heading]),
                                   fov[j:j + 1], targets)[0]
        assert np.array_equal(seen[j][decided], want[decided])
        assert not np.any(seen[j] & ~(in_sector(pose, 2 * np.pi, reach[j], targets) & clear))


@pytest.mark.kernels
@SETTINGS
@given(st.lists(footprints, min_size=1, max_size=5), poses)
def test_shadow_hulls_are_the_hulls_of_their_points_as_multipoints(feet, origin):
    # shadow_polygons hands GEOS each box's points as a line string (no Point objects): the
    # hull must be the one of the same points as a multipoint, coordinate for coordinate.
    # The same points: the kernel's, which shadow_polygons uses (the reference's may differ
    # in the last bits, see the next test), so both hulls are GEOS's on the same input.
    boxes = Boxes.from_footprints(feet)
    outside = boxes.distances(origin.position) > 0.0
    o = origin.position
    points = kernels.shadow_points(o, boxes.centers, boxes.axes, boxes.half, 30.0,
                                   FAR_STEPS)[0][outside]
    expected = shapely.convex_hull(shapely.multipoints(points))
    hulls = shadow_polygons(origin.position, boxes, 30.0)[outside]
    assert list(shapely.to_wkb(hulls)) == list(shapely.to_wkb(expected))


@pytest.mark.kernels
@SETTINGS
@given(st.lists(footprints, min_size=1, max_size=6), poses, ranges)
def test_compiled_shadow_points_are_the_reference_within_rounding(feet, origin, reach):
    # Origins anywhere, inside boxes too (the disc case): points, reach and inside agree.
    boxes = Boxes.from_footprints(feet)
    o = origin.position
    points, far, inside = kernels.shadow_points(o, boxes.centers, boxes.axes, boxes.half, reach,
                                                FAR_STEPS)
    want_points, want_far, want_inside = shadow_points_reference(o, boxes, reach)
    assert points.shape == want_points.shape and far.shape == want_far.shape
    # inside: the same products, differences and comparisons on both sides (exact).
    assert np.array_equal(inside, want_inside)
    # far: 2 (range + the farthest corner's distance), a square root of two-term sums.
    np.testing.assert_allclose(far, want_far, rtol=8 * EPS, atol=0)
    # The far points lie at ``far`` from the origin along rays base + lo + (hi - lo)·t of
    # three arctan2s, each within ANGLE_ATOL (4 ANGLE_ATOL with the roundings of those sums),
    # then a cos and a sin (TRIG_ATOL): within far·(4 ANGLE_ATOL + TRIG_ATOL), plus a few
    # roundings of the coordinates' magnitude. The corners, sums of products, within those.
    magnitude = np.abs(o).max() + want_far
    atol = want_far * (4 * ANGLE_ATOL + TRIG_ATOL) + 8 * EPS * magnitude
    assert np.all(np.abs(points - want_points) <= atol[:, None, None])


@pytest.mark.kernels
def test_compiled_shadow_points_flag_an_origin_inside_or_on_a_box():
    boxes = Boxes.from_footprints([Footprint(Pose(10.0, 0.0, 0.0), 4.0, 2.0)])  # x in [6, 10]
    for x, inside in [(8.0, True), (10.0, True), (6.0, True), (10.5, False), (5.9, False)]:
        got = kernels.shadow_points(np.array([x, 1.0]), boxes.centers, boxes.axes, boxes.half,
                                    30.0, FAR_STEPS)[2]
        assert got.tolist() == [inside]


@pytest.mark.kernels
@SETTINGS
@given(poses, fovs, ranges, st.integers(1, 32))
def test_compiled_sector_is_the_reference_within_rounding(pose, fov, reach, resolution):
    got = sector_polygon(pose, fov, reach, resolution)
    expected = sector_polygon_reference(pose, fov, reach, resolution)
    assert got.geom_type == expected.geom_type == "Polygon" and not got.interiors
    coordinates, want = shapely.get_coordinates(got), shapely.get_coordinates(expected)
    assert coordinates.shape == want.shape
    # The apex exactly; the arc's points (x + r cos a, y + r sin a), the same angles a, within
    # r·TRIG_ATOL of each other plus the rounding of the sums.
    atol = reach * TRIG_ATOL + 4 * EPS * (np.abs(pose.position).max() + reach)
    np.testing.assert_allclose(coordinates, want, rtol=0, atol=atol)


@pytest.mark.kernels
@SETTINGS
@given(st.lists(footprints, min_size=0, max_size=6), st.lists(poses, min_size=1, max_size=4),
       seeds)
def test_compiled_sight_masks_are_the_reference(feet, sensor_poses, seed):
    # Targets scattered, on box corners and on sector edges; full discs among the fields.
    rng = np.random.default_rng(seed)
    boxes = Boxes.from_footprints(feet)
    s, m = len(sensor_poses), len(feet)
    fov = np.where(rng.random(s) < 0.3, 2 * np.pi, rng.uniform(0.2, 2 * np.pi, size=s))
    reach = rng.uniform(5.0, 50.0, size=s)
    carriers = rng.integers(-1, max(m, 1), size=s) if m else np.full(s, -1)
    origins = np.array([p.position for p in sensor_poses])
    headings = np.array([p.heading for p in sensor_poses])
    edges = origins + reach[:, None] * np.stack([np.cos(headings + fov / 2),
                                                  np.sin(headings + fov / 2)], axis=1)
    targets = np.vstack([rng.uniform(-40.0, 40.0, size=(30, 2)),
                         boxes.corners().reshape(-1, 2), edges])
    args = (origins, headings, fov, reach, carriers, targets, boxes)
    seen, occluders = sight_masks(*args)
    want_seen, want_occluders = sight_masks_reference(*args)
    assert seen.shape == want_seen.shape and occluders.shape == want_occluders.shape
    # Occluders: box frames and distances, the same IEEE arithmetic on both sides (exact).
    assert np.array_equal(occluders, want_occluders)
    # Seen: the reference's sector angle by NumPy's cos and sin, the kernel's by libm's. Where
    # their rounding cannot turn it (not on the sector edges' targets) the same answer; every
    # target seen is within range and in sight (the reference's disc of the same range).
    decided = bearing_is_clear(origins, headings, fov, targets)
    assert np.array_equal(seen[decided], want_seen[decided])
    disc = sight_masks_reference(origins, headings, np.full(s, 2 * np.pi), *args[3:])[0]
    assert not np.any(seen & ~disc)


@pytest.mark.kernels
@SETTINGS
@given(st.lists(footprints, min_size=0, max_size=6), st.lists(poses, min_size=1, max_size=4))
def test_compiled_box_distances_are_the_reference_within_rounding(feet, points):
    boxes = Boxes.from_footprints(feet)
    origins = np.vstack([[p.position for p in points], boxes.corners().reshape(-1, 2)])
    got, expected = box_distances(origins, boxes), box_distances_reference(origins, boxes)
    assert got.shape == expected.shape
    # hypot of the same two gaps (the same IEEE arithmetic): libm's against NumPy's, each
    # within an ulp or so; 0 (an origin on or in a box) exactly on both sides.
    np.testing.assert_allclose(got, expected, rtol=4 * EPS, atol=0)

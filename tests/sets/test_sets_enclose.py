"""The ``enclose`` correction and fusion: exact 2-D intersection, then a zonotope enclosure.

Soundness is checked against shapely's exact polygons by methods independent of the code
under test: every vertex of the exact polygon by an LP of this file (∃ β, |β|∞ <= 1 + 1e-9,
Gβ = x - c), points sampled inside it by ``Zonotope.contains``, and shapely's own
containment of the exact polygon in the zonotope's polygon.
"""

from functools import reduce

import numpy as np
import pytest
import shapely
from hypothesis import given
from hypothesis import strategies as st
from scipy.optimize import linprog
from sets_strategies import (
    SETTINGS,
    overlapping_zonotopes,
    polygon_points,
    tolerance,
    zonotope_with_strips,
)

from sse_cosim.sets import (
    Strips,
    Zonotope,
    enclosure,
    fuse,
    intersect_strips,
    strip_disjoint,
    zonotopes_disjoint,
)
from sse_cosim.sets.exact import intersect_strips_exact, zonotope_polygon


def in_zonotope_lp(z: Zonotope, point: np.ndarray, slack: float = 1e-9) -> bool:
    """∃ β with |β|∞ <= 1 + slack and Gβ = x - c (HiGHS on the problem scaled to unit size)."""
    offset = point - z.center
    scale = max(np.abs(z.generators).max(), np.abs(offset).max())
    result = linprog(np.zeros(z.n_generators), A_eq=z.generators / scale, b_eq=offset / scale,
                     bounds=[(-1 - slack, 1 + slack)] * z.n_generators, method="highs",
                     options={"primal_feasibility_tolerance": 1e-10})
    return result.status == 0


def assert_encloses(result: Zonotope, exact, rng: np.random.Generator, tol: float) -> None:
    for vertex in shapely.get_coordinates(exact):
        assert in_zonotope_lp(result, vertex), vertex
    assert result.contains(polygon_points(exact, rng), tol=tol).all()
    assert zonotope_polygon(result).buffer(tol).covers(exact)


def exact_intersection(sets):
    return reduce(lambda a, b: a.intersection(b), [zonotope_polygon(z) for z in sets])


# --- correction ---------------------------------------------------------------------------


@SETTINGS
@given(zonotope_with_strips(2), st.integers(0, 2**32 - 1))
def test_enclose_contains_the_exact_intersection(case, seed):
    z, strips = case
    exact = intersect_strips_exact(zonotope_polygon(z), strips)
    assert not exact.is_empty
    result = intersect_strips(z, strips, "enclose")
    assert_encloses(result, exact, np.random.default_rng(seed), tolerance(z))


@SETTINGS
@given(zonotope_with_strips(2))
def test_enclose_is_never_larger_than_volume(case):
    z, strips = case
    exact = intersect_strips_exact(zonotope_polygon(z), strips).area
    enclosed = intersect_strips(z, strips, "enclose").volume()
    # ``volume`` is only skipped when the enclosure is exact up to EXACT_RTOL
    assert enclosed <= intersect_strips(z, strips, "volume").volume() * (
        1 + enclosure.EXACT_RTOL)
    assert enclosed <= z.volume() * (1 + enclosure.EXACT_RTOL)
    assert enclosed >= exact * (1 - 1e-9)  # an enclosure: never below the exact area


def test_enclose_of_covering_strips_is_the_input():
    z = Zonotope([1.0, 2.0], [[1.0, 0.3, -0.2], [0.2, 1.0, 0.4]])
    wide = Strips([[1.0, 0.0], [0.6, 0.8]], [1.0, 2.2], [5.0, 6.0])
    result = intersect_strips(z, wide, "enclose")
    assert np.array_equal(result.center, z.center)
    assert np.array_equal(result.generators, z.generators)


def test_enclose_is_exact_for_a_centrally_symmetric_intersection():
    """A square cut by a diagonal strip through its centre: a hexagon whose edges lie along
    the square's and the strip's directions, recovered exactly (``volume`` gives 2.0)."""
    square = Zonotope([3.0, -1.0], np.eye(2))
    strip = Strips([1.0, 1.0], 2.0, 0.5)  # |x + y - 2| <= 0.5
    exact = intersect_strips_exact(zonotope_polygon(square), strip).area
    assert exact == pytest.approx(1.75)
    assert intersect_strips(square, strip, "volume").volume() == pytest.approx(2.0)
    assert intersect_strips(square, strip, "enclose").volume() == pytest.approx(exact, rel=1e-8)


def test_enclose_of_an_empty_intersection_is_the_volume_result():
    """An inconsistent measurement: like every gain method, ``enclose`` returns Prop. 1's set
    (sound for ∅); the consistency tests are what flag it."""
    square = Zonotope([0.0, 0.0], np.eye(2))
    far = Strips([0.0, 1.0], 5.0, 1.0)
    # each strip meets the square, but not both: they cross at (1.5, 0), outside it
    apart = Strips([[1.0, -1.0], [1.0, 1.0]], [1.5, 1.5], [0.2, 0.2])
    for strips, flagged in ((far, True), (apart, False)):
        assert intersect_strips_exact(zonotope_polygon(square), strips).is_empty
        assert strip_disjoint(square, strips).any() == flagged
        result = intersect_strips(square, strips, "enclose")
        volume = intersect_strips(square, strips, "volume")
        assert np.array_equal(result.center, volume.center)
        assert np.array_equal(result.generators, volume.generators)


@pytest.mark.parametrize("n", [3, 4])
def test_enclose_is_the_volume_result_outside_2d(n):
    rng = np.random.default_rng(n)
    z = Zonotope(rng.normal(size=n), rng.normal(size=(n, n + 3)))
    strips = Strips(rng.normal(size=(2, n)), [0.1, -0.2], [0.5, 0.7])
    result, volume = intersect_strips(z, strips, "enclose"), intersect_strips(z, strips, "volume")
    assert np.array_equal(result.center, volume.center)
    assert np.array_equal(result.generators, volume.generators)


def test_enclose_of_a_segment_is_the_volume_result():
    segment = Zonotope([0.0, 0.0], [[2.0, 1.0], [2.0, 1.0]])
    strip = Strips([[1.0, 0.0]], [1.2], [0.5])
    result, volume = intersect_strips(segment, strip, "enclose"), intersect_strips(
        segment, strip, "volume")
    assert np.array_equal(result.generators, volume.generators)


# --- fusion -------------------------------------------------------------------------------


@SETTINGS
@given(overlapping_zonotopes(2), st.integers(0, 2**32 - 1))
def test_enclose_fusion_contains_the_exact_intersection(sets, seed):
    exact = exact_intersection(sets)
    assert not exact.is_empty
    fused = fuse(sets, "enclose")
    assert_encloses(fused, exact, np.random.default_rng(seed), tolerance(*sets))
    assert fused.volume() <= min(z.volume() for z in sets)
    assert fused.volume() >= exact.area * (1 - 1e-9)


def test_enclose_fusion_is_exact_for_an_octagon():
    """Two concentric squares, one turned by 45°: their intersection is a regular octagon,
    centrally symmetric with the squares' edge directions; every other method returns one of
    the squares (area 4)."""
    turn = np.array([[1.0, -1.0], [1.0, 1.0]]) / np.sqrt(2)
    a, b = Zonotope([1.0, 2.0], np.eye(2)), Zonotope([1.0, 2.0], turn)
    exact = exact_intersection([a, b]).area
    assert exact == pytest.approx(8 * (np.sqrt(2) - 1))
    assert fuse([a, b], "enclose").volume() == pytest.approx(exact, rel=1e-8)
    for method in ("volume", "strips"):
        assert fuse([a, b], method).volume() == pytest.approx(4.0)


def test_enclose_fusion_is_much_tighter_than_the_smallest_input():
    """On the seeded 2-D cases of ``test_sets_fusion`` (2-4 inputs), mean area relative to
    ``frobenius``: enclose 0.226, strips 0.316, exact intersection 0.195."""
    ratios = {"enclose": [], "strips": [], "exact": []}
    for seed in range(40):
        rng = np.random.default_rng(seed)
        common = rng.uniform(-5, 5, 2)
        sets = []
        for _ in range(int(rng.integers(2, 5))):
            g = rng.normal(size=(2, int(rng.integers(2, 6))))
            sets.append(Zonotope(common - g @ rng.uniform(-1, 1, g.shape[1]), g))
        base = fuse(sets, "frobenius").volume()
        for method in ("enclose", "strips"):
            ratios[method].append(fuse(sets, method).volume() / base)
        ratios["exact"].append(exact_intersection(sets).area / base)
    means = {k: float(np.mean(v)) for k, v in ratios.items()}
    assert means["exact"] <= means["enclose"] < means["strips"]
    assert means["enclose"] < 0.24


def test_enclose_fusion_of_disjoint_inputs_is_the_smallest_input():
    small, large = Zonotope([0.0, 0.0], np.eye(2) * 0.5), Zonotope([5.0, 0.0], np.eye(2))
    assert zonotopes_disjoint(small, large)
    assert fuse([large, small], "enclose") is small


def test_enclose_fusion_with_a_degenerate_input_is_the_smallest_input():
    segment = Zonotope([0.0, 0.0], [[1.0], [1.0]])
    box = Zonotope([0.0, 0.0], np.eye(2))
    assert fuse([box, segment], "enclose") is segment


# --- the geometry -------------------------------------------------------------------------


def test_clip_polygon_matches_shapely():
    rng = np.random.default_rng(3)
    for _ in range(300):
        z = Zonotope(rng.normal(size=2), rng.normal(size=(2, int(rng.integers(1, 6)))))
        vertices = z.vertices()
        normal = rng.normal(size=2)
        bound = float(normal @ z.center + rng.uniform(-1.5, 1.5) * np.abs(normal @ z.generators)
                      .sum())
        clipped = enclosure.clip_polygon(vertices, normal, bound)
        half_plane = Strips(normal, bound - 1e3, 1e3)  # nᵀx <= bound, bounded far below
        expected = intersect_strips_exact(zonotope_polygon(z), half_plane)
        if expected.is_empty:
            assert len(clipped) == 0
            continue
        assert (clipped @ normal <= bound + 1e-9).all()
        got = shapely.MultiPoint(clipped).convex_hull
        assert got.area == pytest.approx(expected.area, rel=1e-9, abs=1e-12)
        assert got.buffer(1e-9).covers(expected) and expected.buffer(1e-9).covers(got)


def test_unit_directions_merge_parallel_and_opposite_columns():
    g = np.array([[1.0, -2.0, 0.0, 0.0, 3.0, 1e-12], [0.0, 0.0, 1.0, -4.0, 3.0, -1.0]])
    d = enclosure.unit_directions(g)
    assert d.shape == (2, 3)  # x (twice), y (three times: 1e-12 is within the merge angle), 45°
    assert np.allclose(np.linalg.norm(d, axis=0), 1.0)
    assert np.allclose(d, [[1.0, np.sqrt(0.5), 0.0], [0.0, np.sqrt(0.5), 1.0]])
    assert enclosure.unit_directions(np.zeros((2, 2))).shape == (2, 0)
    with np.errstate(all="raise"):  # residue columns (squares underflow) give no direction
        tiny = enclosure.unit_directions(np.array([[1.0, 1e-160, 0.0], [0.0, -1e-167, 2.0]]))
    assert np.allclose(tiny, [[1.0, 0.0], [0.0, 1.0]])


@SETTINGS
@given(st.integers(0, 2**32 - 1))
def test_enclose_polygon_contains_every_vertex_for_any_directions(seed):
    """Directions that match no edge of the polygon still give a sound enclosure."""
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(int(rng.integers(1, 9)), 2)) * 10 ** rng.uniform(-2, 2)
    angles = rng.uniform(0, np.pi, int(rng.integers(2, 7)))
    directions = enclosure.unit_directions(np.stack([np.cos(angles), np.sin(angles)]))
    found = enclosure.enclose_polygon(points, directions, float(np.abs(points).max()))
    assert found is not None
    z = Zonotope(*found)
    assert all(in_zonotope_lp(z, p) for p in points)


@SETTINGS
@given(zonotope_with_strips(2))
def test_least_perimeter_reaches_the_lp_optimum(case):
    """The solver-free least-perimeter enclosure against the LP (scipy HiGHS): never below it
    (the LP is the optimum), and equal to it whenever every direction is an edge (then the
    weighted-L1 bound is attained: a certificate)."""
    z, strips = case
    unit = strips.normalized()
    polygon = enclosure.clip_to_strips(z.vertices(), unit.normals, unit.values, unit.radii)
    edges = np.stack([-unit.normals[:, 1], unit.normals[:, 0]])
    directions = enclosure.unit_directions(np.hstack([z.generators, edges]))
    _, alpha = enclosure.least_perimeter(polygon, directions)
    _, reference = enclosure.least_perimeter_lp(polygon, directions)
    assert alpha.sum() >= reference.sum() * (1 - 1e-7)
    if (alpha > 0).all():
        assert alpha.sum() <= reference.sum() * (1 + 1e-7)


def test_least_perimeter_equals_the_lp_on_random_intersections():
    """Measured: on these 200 cases the two agree to 1e-7 (redundant directions included)."""
    rng = np.random.default_rng(11)
    for _ in range(200):
        z = Zonotope(rng.normal(size=2), rng.normal(size=(2, int(rng.integers(2, 9)))))
        normals = rng.normal(size=(int(rng.integers(1, 4)), 2))
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        radii = np.abs(normals @ z.generators).sum(axis=1) * rng.uniform(0.05, 0.8, len(normals))
        point = z.center + z.generators @ rng.uniform(-1, 1, z.n_generators)
        values = normals @ point + rng.uniform(-1, 1, len(normals)) * radii
        polygon = enclosure.clip_to_strips(z.vertices(), normals, values, radii)
        directions = enclosure.unit_directions(
            np.hstack([z.generators, np.stack([-normals[:, 1], normals[:, 0]])]))
        _, alpha = enclosure.least_perimeter(polygon, directions)
        _, reference = enclosure.least_perimeter_lp(polygon, directions)
        assert alpha.sum() == pytest.approx(reference.sum(), rel=1e-7)


@SETTINGS
@given(st.integers(0, 2**32 - 1))
def test_symmetric_scales_give_the_polygon_of_the_half_widths(seed):
    """{x : |n_iᵀx| <= h_i} with random h (often redundant strips) is the zonotope of
    ``symmetric_scales``: same set as shapely's clipping of a large box."""
    rng = np.random.default_rng(seed)
    angles = rng.uniform(0, np.pi, int(rng.integers(2, 9)))
    directions = enclosure.unit_directions(np.stack([np.cos(angles), np.sin(angles)]))
    normals = np.stack([-directions[1], directions[0]], axis=1)
    half = rng.uniform(0.1, 2.0, directions.shape[1])
    alpha = enclosure.symmetric_scales(directions, half)
    z = Zonotope(np.zeros(2), directions * alpha)
    region = shapely.box(-100, -100, 100, 100)
    for normal, h in zip(normals, half, strict=True):
        region = intersect_strips_exact(region, Strips(normal, 0.0, h))
    assert z.volume() == pytest.approx(region.area, rel=1e-9)
    assert zonotope_polygon(z).symmetric_difference(region).area <= 1e-9 * region.area


def test_containment_repair_raises_alpha_until_every_half_width_holds():
    angles = np.array([0.0, 1.0, 2.0])
    directions = np.stack([np.cos(angles), np.sin(angles)])
    normals = np.stack([-directions[1], directions[0]], axis=1)
    widths = np.abs(normals @ directions)
    upper, lower = np.array([1.0, 2.0, 0.5]), np.array([-1.0, -0.5, -2.0])
    alpha = np.array([0.1, 0.0, 0.2])  # far too small, and one direction unused
    repaired = enclosure._contain(alpha, widths, np.zeros(3), upper, lower, 1e-10)
    assert repaired is not None and repaired[1] == 0.0
    assert (widths @ repaired >= np.maximum(upper, -lower) + 1e-10).all()
    one = np.array([0.5, 0.0, 0.0])  # a segment cannot widen along its own normal: all grow
    repaired = enclosure._contain(one, widths, np.zeros(3), upper, lower, 1e-10)
    assert repaired is not None and (repaired > 0).all()
    assert (widths @ repaired >= np.maximum(upper, -lower) + 1e-10).all()

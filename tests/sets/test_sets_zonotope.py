"""Zonotope operations against independent exact computations (shapely, qhull, brute force)."""

import warnings
from itertools import combinations, product

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.spatial import ConvexHull
from sets_strategies import SETTINGS, tolerance, zonotopes
from shapely.geometry import Point, Polygon

from sse_cosim.sets import REDUCTION_METHODS, Zonotope, zonotope_facet_strips
from sse_cosim.sets.exact import zonotope_polygon
from sse_cosim.sets.zonotope import cofactor_vectors, generator_volume, subset_indices


def directions(n: int, count: int = 200, seed: int = 0) -> np.ndarray:
    d = np.random.default_rng(seed).normal(size=(count, n))
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def test_arrays_are_read_only_float64_and_validated():
    z = Zonotope([1, 2], [[1, 0, 3], [0, 1, 4]])
    assert z.center.dtype == np.float64 and z.generators.dtype == np.float64
    assert (z.dim, z.n_generators) == (2, 3)
    with pytest.raises(ValueError, match="read-only"):
        z.center[0] = 5.0
    assert Zonotope([1.0, 2.0], []).generators.shape == (2, 0)
    with pytest.raises(ValueError, match="shape"):
        Zonotope([1.0, 2.0], [[1.0, 0.0]])
    with pytest.raises(ValueError, match="finite"):
        Zonotope([np.nan, 0.0], np.eye(2))


@SETTINGS
@given(zonotopes(2, min_generators=2, max_generators=9))
def test_volume_equals_shapely_area_of_ccw_vertices(z):
    polygon = Polygon(z.vertices())
    assert polygon.is_valid
    assert polygon.exterior.is_ccw
    assert z.volume() == pytest.approx(polygon.area, rel=1e-9)


@pytest.mark.parametrize(("n", "e"), [(3, 3), (3, 6), (4, 4), (4, 7)])
def test_volume_matches_convex_hull_of_all_sign_vertices(n, e):
    rng = np.random.default_rng(n * 10 + e)
    z = Zonotope(rng.normal(size=n), rng.normal(size=(n, e)))
    corners = z.center + np.array(list(product([-1, 1], repeat=e))) @ z.generators.T
    assert z.volume() == pytest.approx(ConvexHull(corners).volume, rel=1e-9)


def test_volume_of_degenerate_sets_is_zero():
    assert Zonotope([0.0, 0.0, 0.0], np.ones((3, 2))).volume() == 0.0
    assert Zonotope([0.0, 0.0], [[1.0, 2.0], [1.0, 2.0]]).volume() == 0.0


def test_vertices_of_point_segment_and_parallel_generators():
    assert Zonotope([1.0, 2.0], np.zeros((2, 2))).vertices().tolist() == [[1.0, 2.0]]
    segment = Zonotope([0.0, 0.0], [[1.0, -2.0, 0.0], [1.0, -2.0, 0.0]]).vertices()
    assert segment.tolist() == [[-3.0, -3.0], [3.0, 3.0]]
    square = Zonotope([0.0, 0.0], [[1.0, 0.0, 2.0, 0.0], [0.0, 1.0, 0.0, -1.0]])
    assert Polygon(square.vertices()).equals(Polygon([(-3, -2), (3, -2), (3, 2), (-3, 2)]))
    assert len(square.vertices()) == 4


@SETTINGS
@given(zonotopes(2, max_generators=5), zonotopes(2, max_generators=5))
def test_minkowski_sum_and_linear_map_support_functions(z1, z2):
    d = directions(2)
    total = z1 + z2
    assert np.allclose(total.support(d), z1.support(d) + z2.support(d), rtol=1e-12)
    m = np.array([[1.0, 2.0], [-0.5, 3.0], [0.0, 1.0]])
    mapped = m @ z1
    assert mapped.dim == 3
    d3 = directions(3)
    assert np.allclose(mapped.support(d3), z1.support(d3 @ m), rtol=1e-12)
    v = np.array([3.0, -4.0])
    assert np.allclose((z1 + v).center, z1.center + v)
    assert np.allclose((v + z1).center, z1.center + v)
    assert np.allclose(z1.scale(-2.0).support(d), 2.0 * z1.support(-d))


@SETTINGS
@given(zonotopes(2, max_generators=8))
def test_interval_hull_is_the_polygon_bounding_box(z):
    lo, hi = z.interval_hull()
    assert np.allclose([*lo, *hi], zonotope_polygon(z).bounds, atol=tolerance(z))


@SETTINGS
@given(
    st.one_of(zonotopes(2, max_generators=12), zonotopes(4, max_generators=12)),
    st.sampled_from(sorted(REDUCTION_METHODS)),
    st.integers(0, 4),
)
def test_reduction_is_sound_and_bounded(z, method, extra):
    order = z.dim + extra
    reduced = z.reduce(order, method)
    assert reduced.n_generators <= order
    assert np.array_equal(reduced.center, z.center)
    d = directions(z.dim)
    assert np.all(reduced.support(d) >= z.support(d) - tolerance(z))


def test_pca_reduction_is_tighter_for_an_elongated_rotated_set():
    angle = np.pi / 5
    rotation = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    z = Zonotope([0.0, 0.0], rotation @ np.array([[5.0, 4.0, 6.0, 3.0], [0.1, -0.2, 0.1, 0.0]]))
    girard, pca = z.reduce(2, "girard").volume(), z.reduce(2, "pca").volume()
    assert pca < 0.5 * girard


def test_reduction_rejects_orders_below_dimension_and_unknown_methods():
    z = Zonotope(np.zeros(3), np.eye(3))
    with pytest.raises(ValueError, match="max_generators"):
        z.reduce(2)
    with pytest.raises(ValueError, match="available: girard, pca"):
        z.reduce(3, "nope")


@SETTINGS
@given(
    st.one_of(
        zonotopes(2, max_generators=8),
        zonotopes(2, min_generators=0, max_generators=1),
    ),
    st.integers(0, 2**32 - 1),
)
def test_contains_agrees_with_shapely_covers(z, seed):
    """Full-rank sets use the half-space test, points and segments the LP; points closer than
    1e-7 (relative) to the boundary are ambiguous and skipped."""
    rng = np.random.default_rng(seed)
    geometry = zonotope_polygon(z)
    lo, hi = z.interval_hull()
    size = max(*(hi - lo), *np.abs(z.center), 1e-3)
    outside_or_in = rng.uniform(lo - 0.3 * size, hi + 0.3 * size, size=(40, 2))
    inside = z.center + rng.uniform(-1, 1, (10, z.n_generators)) @ z.generators.T
    points = np.vstack([outside_or_in, inside, z.vertices()])
    answers = z.contains(points, tol=tolerance(z))
    full = geometry.geom_type == "Polygon"
    checked = 0
    for point, answer in zip(points, answers, strict=True):
        p = Point(point)
        if full:
            if geometry.exterior.distance(p) < 1e-7 * size:
                continue
            expected = geometry.covers(p)
        else:
            distance = geometry.distance(p)
            if 1e-12 * size < distance < 1e-7 * size:
                continue
            expected = distance <= 1e-12 * size
        assert answer == expected
        checked += 1
    assert checked >= 40


@SETTINGS
@given(zonotopes(4, max_generators=7), st.integers(0, 2**32 - 1))
def test_contains_lp_agrees_with_facet_strips_in_4d(z, seed):
    """Points within 1e-7 (relative) of the boundary are ambiguous and skipped."""
    rng = np.random.default_rng(seed)
    points = z.center + rng.uniform(-1.3, 1.3, size=(15, z.n_generators)) @ z.generators.T
    facets = zonotope_facet_strips(z)
    size = np.abs(z.generators).sum(axis=1).max()
    excess = np.abs(points @ facets.normals.T - facets.values) - facets.radii
    clear = np.all(excess < -1e-7 * size, axis=1) | np.any(excess > 1e-7 * size, axis=1)
    tol = 1e-12 * size
    assert np.array_equal(z.contains(points[clear], tol), facets.contains(points[clear], tol))


@pytest.mark.parametrize("n", [1, 2, 3, 4])
def test_cofactor_vectors_give_determinants(n):
    rng = np.random.default_rng(n)
    g = rng.normal(size=(n, n + 2))
    x = rng.normal(size=n)
    subsets = combinations(range(n + 2), n - 1)
    expected = [np.linalg.det(np.column_stack([g[:, list(s)], x])) for s in subsets]
    assert np.allclose(cofactor_vectors(g) @ x, expected)


@pytest.mark.parametrize("e", [0, 3])
def test_json_round_trip(e):
    z = Zonotope([1.5, -2.0], np.arange(2.0 * e).reshape(2, e))
    data = z.to_json()
    assert data == {"center": [1.5, -2.0], "generators": z.generators.tolist()}
    back = Zonotope.from_json(data)
    assert np.array_equal(back.center, z.center) and np.array_equal(back.generators, z.generators)
    with pytest.raises(ValueError, match="lacks"):
        Zonotope.from_json({"center": [0.0]})


def test_from_interval_and_remove_zero_generators():
    box = Zonotope.from_interval([0.0, 1.0, 2.0], [2.0, 1.0, 6.0])
    assert np.array_equal(box.center, [1.0, 1.0, 4.0])
    assert np.array_equal(box.generators, [[1.0, 0.0], [0.0, 0.0], [0.0, 2.0]])
    with pytest.raises(ValueError, match="lo <= hi"):
        Zonotope.from_interval([1.0], [0.0])


def test_volume_of_a_degenerate_4d_set_warns_of_nothing():
    """A constant-velocity set whose velocity generators have shrunk to subnormal numbers:
    ``np.linalg.det`` warned "divide by zero" on it; the volume is still the sum of |det|."""
    generators = np.array([
        [-6.16452880e-01, -1.65178051e-01, 6.22522714e-322, 1.09229576e-16, 1.0],
        [1.65178051e-01, -6.16452880e-01, 2.48515020e-321, -8.62924100e-33, 0.0],
        [2.27978136e-01, 6.10865575e-02, -2.32210854e-322, -4.03955532e-17, 0.0],
        [-6.10865575e-02, 2.27978136e-01, -9.18962101e-322, 1.08028620e-34, 0.5],
    ])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        volume = generator_volume(generators)
    with np.errstate(all="ignore"):
        blocks = generators[:, subset_indices(5, 4)].transpose(1, 0, 2)
        expected = 16.0 * np.abs(np.linalg.det(blocks)).sum()
    assert volume == pytest.approx(expected, abs=1e-12)  # both ~1e-25: the set is flat

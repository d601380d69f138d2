"""Strips (eq. strip) and the facet-strip description of zonotopes."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from sets_strategies import SETTINGS, tolerance, zonotopes
from shapely.geometry import box

from sse_cosim.sets import Strips, Zonotope, zonotope_facet_strips
from sse_cosim.sets.exact import intersect_strips_exact, zonotope_polygon


def test_validation_messages():
    with pytest.raises(ValueError, match="radii must be > 0"):
        Strips([[1.0, 0.0]], [0.0], [0.0])
    with pytest.raises(ValueError, match="nonzero"):
        Strips([[0.0, 0.0]], [0.0], [1.0])
    with pytest.raises(ValueError, match=r"normals \(m, n\)"):
        Strips([[1.0, 0.0]], [0.0, 1.0], [1.0, 1.0])
    with pytest.raises(ValueError, match="empty list"):
        Strips.stack([])


def test_rows_equal_one_constructor_call_per_row_and_check_the_same():
    h, r = np.array([[0.6, 0.8], [-0.8, 0.6]]), np.array([0.5, 0.25])
    values = np.array([[1.0, 2.0], [-3.0, 0.5], [0.0, 7.25]])
    for made, expected in zip(Strips.rows(h, values, r), [Strips(h, y, r) for y in values],
                              strict=True):
        for name in ("normals", "values", "radii"):
            assert np.array_equal(getattr(made, name), getattr(expected, name))
            assert not getattr(made, name).flags.writeable
    assert Strips.rows(h, np.empty((0, 2)), r) == []
    with pytest.raises(ValueError, match="finite"):
        Strips.rows(h, [[1.0, np.nan]], r)
    with pytest.raises(ValueError, match="radii must be > 0"):
        Strips.rows(h, values, [0.5, 0.0])
    with pytest.raises(ValueError, match=r"shape \(k, 2\)"):
        Strips.rows(h, [1.0, 2.0], r)
    first = Strips.rows(h, values, r)[0]
    values[0, 0], h[0, 0], r[0] = 99.0, 99.0, 99.0  # the strips hold copies
    assert (first.values[0], first.normals[0, 0], first.radii[0]) == (1.0, 0.6, 0.5)


def test_single_strip_shorthand_contains_len_select_stack():
    one = Strips([1.0, 1.0], 2.0, 0.5)
    assert len(one) == 1 and one.dim == 2
    assert one.contains([1.0, 1.0]) and one.contains([1.25, 1.25])
    assert not one.contains([1.3, 1.3])
    two = Strips.stack([one, Strips([[0.0, 1.0]], [0.0], [1.0])])
    assert len(two) == 2
    assert two.contains(np.array([[1.0, 1.0], [1.5, 0.9], [0.0, 0.0]])).tolist() == [
        True,
        True,
        False,
    ]
    assert np.array_equal(two.select([False, True]).normals, [[0.0, 1.0]])
    assert np.array_equal(two.select([1, 0]).values, [0.0, 2.0])


def test_pullback_and_normalized_describe_the_same_sets():
    strips = Strips([[2.0, 0.0], [1.0, -1.0]], [1.0, 0.5], [0.4, 0.3])
    output_map = np.array([[1.0, 0.0, 2.0, 0.0], [0.0, 1.0, 0.0, 1.0]])
    pulled = strips.pullback(output_map)
    unit = strips.normalized()
    assert np.allclose(np.linalg.norm(unit.normals, axis=1), 1.0)
    points = np.random.default_rng(0).uniform(-2, 2, size=(500, 4))
    assert np.array_equal(pulled.contains(points), strips.contains(points @ output_map.T))
    assert np.array_equal(unit.contains(points[:, :2]), strips.contains(points[:, :2]))


@SETTINGS
@given(zonotopes(2, max_generators=8))
def test_facet_strips_equal_the_zonotope_in_2d(z):
    facets = zonotope_facet_strips(z)
    polygon = zonotope_polygon(z)
    assert len(facets) <= np.count_nonzero(np.any(z.generators != 0, axis=0))
    clipped = intersect_strips_exact(box(*polygon.buffer(1.0).bounds), facets)
    rounding = 1e-13 * polygon.length * (1.0 + np.abs(z.center).max())
    assert clipped.symmetric_difference(polygon).area <= 1e-9 * polygon.area + rounding


def test_facet_strips_merge_parallel_generators_and_skip_zero_ones():
    z = Zonotope([1.0, 2.0], [[1.0, 0.0, -3.0, 0.0, 1.0], [0.0, 0.0, 0.0, 2.0, 1.0]])
    facets = zonotope_facet_strips(z)
    assert len(facets) == 3  # directions (1, 0), (0, 1), (1, 1)
    assert np.allclose(np.sort(facets.radii), np.sort([3.0, 5.0, 2 * np.sqrt(2) + 2 / np.sqrt(2)]))


@SETTINGS
@given(zonotopes(4, max_generators=7), st.integers(0, 2**32 - 1))
def test_facet_strips_contain_every_vertex_and_are_tight_in_4d(z, seed):
    facets = zonotope_facet_strips(z)
    rng = np.random.default_rng(seed)
    signs = rng.choice([-1.0, 1.0], size=(64, z.n_generators))
    assert facets.contains(z.center + signs @ z.generators.T, tol=tolerance(z)).all()
    # every strip is a supporting slab: its bound is attained at a vertex of Z
    extreme = np.sign(facets.normals @ z.generators)
    reached = np.einsum("ij,ij->i", facets.normals, z.center + extreme @ z.generators.T)
    assert np.allclose(reached - facets.values, facets.radii, atol=tolerance(z))


def test_rank_deficient_zonotopes_have_no_facet_strips():
    segment = Zonotope([0.0, 0.0], [[1.0, 2.0], [1.0, 2.0]])
    flat = Zonotope(np.zeros(3), [[1.0, 0.0, 1.0], [0.0, 1.0, 1.0], [0.0, 0.0, 0.0]])
    for z in (segment, flat, Zonotope([1.0, 1.0], [])):
        facets = zonotope_facet_strips(z)
        assert len(facets) == 0 and facets.dim == z.dim

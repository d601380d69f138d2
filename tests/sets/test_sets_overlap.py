"""The overlap tests (sensor-failure detection) against shapely, and the common point of
many sets."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from sets_strategies import SETTINGS, zonotopes
from shapely.geometry import box

from sse_cosim.sets import (
    Strips,
    Zonotope,
    have_common_point,
    strip_covers,
    strip_disjoint,
    zonotopes_disjoint,
)
from sse_cosim.sets.exact import intersect_strips_exact, zonotope_polygon
from sse_cosim.sets.overlap import zonotopes_disjoint_reference


@SETTINGS
@given(zonotopes(2, max_generators=6), st.integers(0, 2**32 - 1))
def test_strip_disjoint_and_covers_agree_with_shapely(z, seed):
    rng = np.random.default_rng(seed)
    polygon = zonotope_polygon(z)
    normals = rng.normal(size=(12, 2))
    width = np.abs(normals @ z.generators).sum(axis=1)
    radii = width * rng.uniform(0.05, 1.5, 12)
    values = normals @ z.center + width * rng.uniform(-3, 3, 12)
    strips = Strips(normals, values, radii)
    disjoint, covers = strip_disjoint(z, strips), strip_covers(z, strips)
    frame = box(*polygon.buffer(1.0).bounds)
    for j in range(len(strips)):
        one = strips.select([j])
        slab = intersect_strips_exact(frame, one)
        gap = polygon.distance(slab)
        overlap = polygon.intersection(slab).area
        if gap > 1e-7 * width[j] or overlap > 1e-7 * polygon.area:  # away from touching
            assert disjoint[j] == (gap > 0)
        outside = polygon.difference(slab).area / polygon.area
        if outside > 1e-7:
            assert not covers[j]
        if covers[j]:
            assert outside <= 1e-9


@SETTINGS
@given(zonotopes(2, max_generators=5), zonotopes(2, max_generators=5), st.floats(0.0, 1.5))
def test_zonotopes_disjoint_agrees_with_shapely(z1, z2, spread):
    lo1, hi1 = z1.interval_hull()
    lo2, hi2 = z2.interval_hull()
    # move Z2 so the sets range from overlapping to clearly apart
    z2 = z2.translate((z1.center - z2.center) + spread * ((hi1 - lo1) + (hi2 - lo2)) / 2)
    p1, p2 = zonotope_polygon(z1), zonotope_polygon(z2)
    gap = p1.distance(p2)
    size = max(*(hi1 - lo1), *(hi2 - lo2))
    if gap == 0 and p1.intersection(p2).area < 1e-7 * min(p1.area, p2.area):
        return  # touching
    if 0 < gap < 1e-7 * size:
        return  # touching
    assert zonotopes_disjoint(z1, z2) == (gap > 0)
    assert zonotopes_disjoint(z2, z1) == (gap > 0)


@pytest.mark.kernels
@SETTINGS
@given(zonotopes(2, max_generators=5), zonotopes(2, min_generators=0, max_generators=5),
       st.floats(0.0, 1.5), st.sampled_from([0.0, 1e-9, 1e-6]), st.booleans())
def test_compiled_disjointness_is_the_reference(z1, z2, spread, tol, parallel):
    """The 2-D kernel gives the NumPy reference's answer, also at the touching distance ``tol``
    and for parallel (rank-deficient) generators, where both take the LP.

    Exact even at touching: in 2-D the reference is ``Zonotope.contains`` on ⟨0, [G1, -G2]⟩,
    which runs the same compiled ``full_rank_2d`` and ``contains_2d`` on the same arrays as
    ``meet_2d`` does (and the same LP where they are rank-deficient)."""
    if parallel:  # every generator along one direction: [G1, -G2] is rank-deficient
        z1 = Zonotope(z1.center, np.outer([0.6, 0.8], np.abs(z1.generators).sum(axis=0)))
        z2 = Zonotope(z2.center, np.outer([0.6, 0.8], np.abs(z2.generators).sum(axis=0)))
    gap = z1.support(np.array([1.0, 0.0])) + z2.support(np.array([-1.0, 0.0]))
    z2 = z2.translate(np.array([gap * spread, 0.0]))
    for first, second in ((z1, z2), (z2, z1)):
        assert zonotopes_disjoint(first, second, tol) \
            == zonotopes_disjoint_reference(first, second, tol)


def test_zonotopes_disjoint_in_4d_and_for_points():
    """Z meets Z + v iff v ∈ ⟨0, 2G⟩; a shift beyond twice the support along v separates them."""
    rng = np.random.default_rng(1)
    z = Zonotope(np.zeros(4), rng.normal(size=(4, 6)))
    for _ in range(10):
        shift = 2 * z.generators @ rng.uniform(-0.95, 0.95, 6)
        assert not zonotopes_disjoint(z, z.translate(shift))
        d = rng.normal(size=4)
        d /= np.linalg.norm(d)
        assert zonotopes_disjoint(z, z.translate(2.01 * z.support(d) * d))
    inside = Zonotope(z.generators @ rng.uniform(-1, 1, 6), [])
    assert not zonotopes_disjoint(inside, z)
    assert zonotopes_disjoint(Zonotope(z.interval_hull()[1] + 1.0, []), z)


def square(x: float, y: float, half: float = 1.0) -> Zonotope:
    return Zonotope(np.array([x, y]), np.eye(2) * half)


def test_common_point_of_three_sets_that_meet_pairwise_only():
    """Three strips of a triangle meet two by two but share no point (2-D Helly needs three)."""
    t = 0.05  # half-thickness; triangle (-2, 0), (2, 0), (0, 2)
    sides = [Zonotope(np.array([0.0, 0.0]), np.array([[2.0, 0.0], [0.0, t]])),
             Zonotope(np.array([1.0, 1.0]), np.array([[1.0, t], [-1.0, t]])),
             Zonotope(np.array([-1.0, 1.0]), np.array([[1.0, -t], [1.0, t]]))]
    for a in range(3):
        for b in range(a + 1, 3):
            assert have_common_point([sides[a], sides[b]])
    assert not have_common_point(sides)
    assert have_common_point([square(0, 0), square(1.5, 0), square(0.7, 1.5)])


def test_touching_sets_count_as_meeting_and_a_gap_above_the_tolerance_does_not():
    assert have_common_point([square(0, 0), square(2.0, 0), square(1.0, 2.0)])
    assert not have_common_point([square(0, 0), square(2.0 + 1e-4, 0)])

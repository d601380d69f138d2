"""The compiled kernels (sets/kernels.py) against their NumPy references, and their soundness.

The two sides are different code: numba's loops and libm's atan2 against NumPy's reductions,
BLAS and (on CPUs with AVX-512) SIMD transcendentals. Their numbers are compared within the
rounding those differences allow (stated at each bound), their decisions where the rounding
cannot turn them; exact equality only where both sides do the same IEEE operations in the
same order. ``make test`` runs these tests a second time with NumPy's AVX-512 code and numba's
host CPU features switched off (the ``kernels`` marker).
"""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from sets_strategies import (
    EPS,
    SETTINGS,
    point_in,
    random_generators,
    rank_decision_is_clear,
    sum_rtol,
    zonotope_with_strips,
    zonotopes,
)

from sse_cosim.sets import Strips, Zonotope, gains, intersect_strips, kernels
from sse_cosim.sets.reduction import girard_reduce, girard_reduce_reference
from sse_cosim.sets.zonotope import (
    contains_2d_reference,
    full_rank,
    generator_volume,
    generator_volume_reference,
    vertices_2d_reference,
)

pytestmark = pytest.mark.kernels

KINDS = ("well", "elongated", "near-parallel", "zero-and-parallel")


@st.composite
def generator_matrices(draw: st.DrawFn, n: int = 2, max_generators: int = 24) -> np.ndarray:
    """(n, e) generators, e >= 0, of every kind of sets_strategies plus all-zero columns, at
    scales 1e-3 .. 1e3."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    e = draw(st.integers(0, max_generators))
    g = random_generators(rng, n, e, draw(st.sampled_from(KINDS))) if e else np.zeros((n, 0))
    if draw(st.booleans()):
        g = np.hstack([g, np.zeros((n, draw(st.integers(1, 3))))])
    return g * draw(st.sampled_from([1e-3, 1.0, 1e3]))


@SETTINGS
@given(generator_matrices())
def test_compiled_area_is_the_reference_up_to_summation_order(g):
    # The same |g_i × g_j| on both sides (elementwise products and differences), summed by
    # numba's copy of numpy's pairwise order and by numpy: within the rounding of any order.
    k = int(np.any(g != 0, axis=0).sum())
    expected = generator_volume_reference(g)
    assert abs(generator_volume(g) - expected) <= sum_rtol(k * k) * expected


def numpys_pairwise_sum(values: list[float]) -> float:
    """numpy's pairwise summation (``pairwise_sum`` in numpy/_core/src/umath/loops_utils.h.src:
    below 8 terms one by one, up to 128 in eight interleaved running sums combined as a tree,
    longer runs split in two with the first half a multiple of 8), in Python floats."""
    n = len(values)
    if n < 8:
        total = 0.0
        for value in values:
            total += value
        return total
    if n <= 128:
        r = values[:8]
        i = 8
        while i < n - n % 8:
            r = [r[j] + values[i + j] for j in range(8)]
            i += 8
        total = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]))
        for value in values[i:]:
            total += value
        return total
    half = n // 2
    half -= half % 8
    return numpys_pairwise_sum(values[:half]) + numpys_pairwise_sum(values[half:])


@SETTINGS
@given(st.integers(0, 2**32 - 1), st.integers(0, 3000))
def test_pairwise_sum_follows_numpys_pairwise_order(seed, count):
    values = np.abs(np.random.default_rng(seed).normal(size=count)) * 10.0 ** (seed % 7 - 3)
    got = kernels.pairwise_sum(values, 0, count)
    # Exact against the order written out in Python: the same IEEE additions in the same order.
    assert got == numpys_pairwise_sum(values.tolist())
    # numpy's own sum (another build may add in another order): within any order's rounding.
    assert abs(got - values.sum()) <= sum_rtol(count) * values.sum()


def assert_girard_reduction_is_the_reference(g: np.ndarray, order: int) -> None:
    """The compiled reduction against the reference: the same columns kept (their scores
    |g|₁ - |g|∞ are the same few IEEE operations on both sides, so the same ranking), and the
    box's radii, sums of |g_ij| over the rest, within the rounding of any summation order."""
    got, expected = girard_reduce(g, order), girard_reduce_reference(g, order)
    assert got.shape == expected.shape
    rest = max(int(np.any(g != 0, axis=0).sum()) - (order - g.shape[0]), 0)
    np.testing.assert_allclose(got, expected, rtol=sum_rtol(rest), atol=0)


@SETTINGS
@given(generator_matrices(n=2), st.integers(2, 12))
def test_compiled_girard_reduction_is_the_reference_up_to_summation_order(g, order):
    assert_girard_reduction_is_the_reference(g, order)


@SETTINGS
@given(generator_matrices(n=3, max_generators=16), st.integers(3, 10))
def test_compiled_girard_reduction_matches_in_3d(g, order):
    assert_girard_reduction_is_the_reference(g, order)


def _barely_touching(zonotope: Zonotope, strips: Strips) -> Strips:
    """The same normals, each strip moved so that it only just touches Z's boundary."""
    support = np.abs(strips.normals @ zonotope.generators).sum(axis=1)
    values = strips.normals @ zonotope.center + support + strips.radii * (1 - 1e-9)
    return Strips(strips.normals, values, strips.radii)


@SETTINGS
@given(zonotope_with_strips(2), st.booleans(), st.integers(0, 2**32 - 1))
def test_compiled_frobenius_intersection_matches_the_reference_and_is_sound(case, touch, seed):
    zonotope, strips = case
    if touch:
        strips = _barely_touching(zonotope, strips)
    unit = strips.normalized()
    reference = gains.apply_gain(zonotope, unit, gains.frobenius_gain_reference(zonotope, unit))
    compiled = intersect_strips(zonotope, strips, "frobenius")
    scale = max(np.abs(zonotope.generators).max(), np.abs(zonotope.center).max())
    np.testing.assert_allclose(gains.frobenius_gain(zonotope, unit),
                               gains.frobenius_gain_reference(zonotope, unit),
                               rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(compiled.center, reference.center, rtol=0, atol=1e-9 * scale)
    assert compiled.generators.shape == reference.generators.shape
    np.testing.assert_allclose(compiled.generators, reference.generators,
                               rtol=0, atol=1e-9 * scale)
    rng = np.random.default_rng(seed)
    points = np.array([point_in(zonotope, rng) for _ in range(200)])
    inside = np.abs(points @ unit.normals.T - unit.values) <= unit.radii
    assert compiled.contains(points[inside.all(axis=1)], tol=1e-9 * scale).all()


@SETTINGS
@given(zonotopes(2, max_generators=12), st.integers(0, 2**32 - 1),
       st.sampled_from([0.0, 1e-9, 1e-7, 1e-6]))
def test_compiled_containment_matches_the_reference(zonotope, seed, tol):
    # Points inside, outside, and on the boundary shifted by ±(tol or a hair) along a facet
    # normal: the compiled test gives the reference's answer for each of them.
    rng = np.random.default_rng(seed)
    c, g = zonotope.center, zonotope.generators
    if rank_decision_is_clear(g):
        assert kernels.full_rank_2d(g) == full_rank(g)
    scale = np.abs(g).sum()
    normals = np.stack([-g[1], g[0]], axis=1)[np.any(g != 0, axis=0)]
    normals = normals / np.linalg.norm(normals, axis=1)[:, None]
    support = np.abs(normals @ g).sum(axis=1)
    edge = c + normals * support[:, None]  # a point on each facet
    shift = normals * (tol + 1e-6 * scale)[..., None] if tol else normals * 1e-6 * scale
    points = np.vstack([
        [point_in(zonotope, rng) for _ in range(50)],
        c + scale * rng.normal(size=(50, 2)),
        edge + shift, edge - shift,
    ])
    expected = contains_2d_reference(c, g, points, tol)
    # The kernel's two-term dot products and numpy's (BLAS, or another order) may round apart:
    # decisions are compared where every facet's test is decided by more than that rounding,
    # a few eps of the terms' magnitudes (the shifted facet points all are, by 1e-6 scale).
    offsets = np.abs((points - c) @ normals.T)
    room = 16 * EPS * (scale + np.abs(points - c).sum(axis=1) + tol)[:, None]
    excess = offsets - (support + tol)
    clear = (excess < -room).all(axis=1) | (excess > room).any(axis=1)
    assert clear[-2 * len(normals):-len(normals)].all()
    assert np.array_equal(kernels.contains_2d(c, g, points, tol)[clear], expected[clear])
    assert np.array_equal(zonotope.contains(points, tol)[clear], expected[clear])
    assert expected[:50].all() and not expected[-2 * len(normals):-len(normals)].any()


@SETTINGS
@given(generator_matrices(n=2), st.integers(0, 2**32 - 1))
def test_compiled_vertices_are_the_reference_within_rounding(g, seed):
    rng = np.random.default_rng(seed)
    center = rng.uniform(-100.0, 100.0, 2)
    # and with runs of parallel columns (multiples of the first), merged before the walk
    parallel = np.hstack([g, np.outer(g[:, 0], rng.uniform(-2.0, 2.0, 5))]) if g.shape[1] else g
    for generators in (g, parallel):
        expected = vertices_2d_reference(center, generators)
        got = Zonotope(center, generators).vertices()
        # The same vertices: parallel columns here are parallel to rounding and the others
        # 1e-4 apart or more, far on either side of PARALLEL_RTOL, so both merge the same runs.
        assert got.shape == expected.shape
        # The angles that sort the columns come from libm's atan2 and NumPy's (SIMD on
        # AVX-512): columns a few ulps apart in angle, parallel and in one run, may be summed
        # in another order. Each vertex is c - Σg plus a walk over 2g_i: every sum within
        # e·eps of |c| + 2Σ|g_i| in either order, with a few roundings of slack.
        atol = (2 * generators.shape[1] + 4) * EPS * (
            np.abs(center).max() + 2 * np.abs(generators).sum())
        np.testing.assert_allclose(got, expected, rtol=0, atol=atol)


@SETTINGS
@given(generator_matrices(n=2, max_generators=12), st.integers(0, 2**32 - 1),
       st.sampled_from([1e-3, 0.5, 20.0]))
def test_compiled_vertex_gain_is_the_reference_or_ties_with_it(g, seed, radius):
    # Normals random, along a generator and across one (hᵀg = 0 for it: not a candidate).
    rng = np.random.default_rng(seed)
    normals = [rng.normal(size=2)]
    if g.shape[1] and np.any(g[:, 0]):
        normals += [g[:, 0] / np.linalg.norm(g[:, 0]), np.array([-g[1, 0], g[0, 0]])]
    k = int(np.any(g != 0, axis=0).sum())
    for h in normals:
        got = gains.volume_gain_vertices(g, h, radius)
        expected = gains.volume_gain_vertices_reference(g, h, radius)
        if np.array_equal(got, expected):  # the same candidate: the same IEEE division
            continue
        # Another candidate: only a tie allows it (parallel columns give the same λ up to
        # rounding, and a flat set scores every λ alike). Both sides score each candidate with
        # sums of k² and g.shape[1] nonnegative terms, in numpy's pairwise order or another
        # one: a choice may flip only between values within those sums' rounding; the score
        # below adds its own, and base·eps for the cancellation in 1 - hᵀλ.
        scores = gains.strip_gain_volume(g, h, radius, np.vstack([got, expected]))
        base = generator_volume(g) / 4.0
        assert abs(scores[0] - scores[1]) <= 4 * sum_rtol(k * k + g.shape[1] + 4) \
            * scores.max() + 8 * EPS * base, (got, expected, scores)


@SETTINGS
@given(zonotope_with_strips(2), st.booleans(), st.booleans(), st.integers(0, 2**32 - 1))
def test_compiled_volume_correction_matches_the_reference_and_is_sound(case, touch, flat, seed):
    # volume_correction_2d against gains.volume_correction_reference (the volume gain applied
    # by apply_gain), on full-rank and flat (rank-1) sets, strips that cut, cover or barely
    # touch: the same set up to rounding, holding every point of Z ∩ S. A flat set's
    # candidates all have area 0 up to rounding, so there only the area must agree.
    zonotope, strips = case
    if flat:  # every generator along the first: the one-strip Frobenius branch
        g = zonotope.generators
        zonotope = Zonotope(zonotope.center, np.outer(g[:, 0], np.linspace(0.5, 1.5, g.shape[1])))
    if touch:
        strips = _barely_touching(zonotope, strips)
    unit = strips.normalized()
    reference = gains.volume_correction_reference(zonotope, unit)
    compiled = intersect_strips(zonotope, strips, "volume")
    scale = max(np.abs(zonotope.generators).max(), np.abs(zonotope.center).max())
    assert abs(compiled.volume() - reference.volume()) <= 1e-9 * scale * scale
    if not flat:  # the same set: the same support in every direction (a column that cancels
        # exactly in one may keep a rounding's length in the other)
        angles = np.linspace(0.0, 2.0 * np.pi, 64, endpoint=False)
        directions = np.stack([np.cos(angles), np.sin(angles)], axis=1)
        support = [directions @ z.center + np.abs(directions @ z.generators).sum(axis=1)
                   for z in (compiled, reference)]
        np.testing.assert_allclose(*support, rtol=0, atol=1e-9 * scale)
    rng = np.random.default_rng(seed)
    points = np.array([point_in(zonotope, rng) for _ in range(200)])
    inside = np.abs(points @ unit.normals.T - unit.values) <= unit.radii
    assert compiled.contains(points[inside.all(axis=1)], tol=1e-9 * scale).all()


@SETTINGS
@given(zonotope_with_strips(2), st.booleans())
def test_compiled_normalization_is_the_reference_bit_for_bit(case, unit):
    # Strips.normalized (kernels.unit_strips) against Strips.normalized_reference, on strips
    # of any scale and on strips whose normals already have norm 1.0 (the same object back).
    _, strips = case
    if unit:
        k = min(len(strips), 2)
        strips = Strips(np.array([[1.0, 0.0], [0.0, -1.0]])[:k], strips.values[:k],
                        strips.radii[:k])
    compiled, reference = strips.normalized(), strips.normalized_reference()
    assert (compiled is strips) == (reference is strips) == unit
    # Exact: both sides do the same IEEE operations (two squares, their sum, a square root,
    # divisions), each correctly rounded, with no library function and no longer sum.
    for name in ("normals", "values", "radii"):
        np.testing.assert_array_equal(getattr(compiled, name), getattr(reference, name))

"""Proposition 1 (eqs. C_lambda, G_lambda): soundness and optimality of every gain method."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from sets_strategies import (
    SETTINGS,
    polygon_points,
    strip_intersection_points,
    tolerance,
    zonotope_with_strips,
    zonotopes,
)

from sse_cosim.sets import (
    GAIN_METHODS,
    Strips,
    Zonotope,
    apply_gain,
    available_gain_methods,
    gains,
    intersect_strips,
    zonotope_facet_strips,
)
from sse_cosim.sets.exact import intersect_strips_exact, zonotope_polygon

METHODS = sorted(available_gain_methods())  # the gains and the ``enclose`` correction


def test_registry_lists_the_four_gains_and_enclose():
    assert set(GAIN_METHODS) == {"frobenius", "cvxpy-frobenius", "volume", "cvxpy-volume"}
    assert set(available_gain_methods()) == {*GAIN_METHODS, "enclose"}
    with pytest.raises(ValueError, match="unknown gain method 'nope'"):
        intersect_strips(Zonotope([0.0, 0.0], np.eye(2)), Strips([1.0, 0.0], 0.0, 1.0), "nope")


@SETTINGS
@given(zonotope_with_strips(2), st.integers(0, 2**32 - 1))
def test_every_method_contains_the_exact_intersection_2d(case, seed):
    z, strips = case
    exact = intersect_strips_exact(zonotope_polygon(z), strips)
    assert not exact.is_empty
    points = polygon_points(exact, np.random.default_rng(seed))
    for method in METHODS:
        result = intersect_strips(z, strips, method)
        assert result.contains(points, tol=tolerance(z)).all(), method


@SETTINGS
@given(zonotope_with_strips(4), st.integers(0, 2**32 - 1))
def test_every_method_contains_the_exact_intersection_4d(case, seed):
    z, strips = case
    points = strip_intersection_points(z, strips, np.random.default_rng(seed))
    for method in METHODS:
        result = intersect_strips(z, strips, method)
        assert zonotope_facet_strips(result).contains(points, tol=tolerance(z)).all(), method


@SETTINGS
@given(zonotope_with_strips(2), st.integers(0, 2**32 - 1))
def test_any_gain_is_sound(case, seed):
    """Prop. 1 holds for an arbitrary Λ, not only for optimized ones."""
    z, strips = case
    rng = np.random.default_rng(seed)
    gain = rng.normal(size=(2, len(strips))) * rng.choice([1e-3, 1.0, 1e2])
    exact = intersect_strips_exact(zonotope_polygon(z), strips)
    result = apply_gain(z, strips, gain)
    points = polygon_points(exact, rng)
    assert result.contains(points, tol=tolerance(z, result)).all()


@pytest.mark.parametrize("n", [2, 3, 4])
def test_strip_gain_volume_is_the_exact_volume_of_the_update(n):
    """vol/2ⁿ = |1 - hᵀλ|·V + r·Σ_S |d_Sᵀλ| (derivation in docs/method.md)."""
    rng = np.random.default_rng(n)
    g = rng.normal(size=(n, n + 3))
    h = rng.normal(size=n)
    h /= np.linalg.norm(h)
    r = 0.7
    lams = rng.normal(size=(20, n))
    predicted = gains.strip_gain_volume(g, h, r, lams)
    strip = Strips(h, 0.0, r)
    for lam, value in zip(lams, predicted, strict=True):
        updated = Zonotope(np.zeros(n), gains.updated_generators(g, strip, lam[:, None]))
        assert updated.volume() / 2**n == pytest.approx(value, rel=1e-9)


@SETTINGS
@given(st.one_of(zonotope_with_strips(2), zonotope_with_strips(4)))
def test_frobenius_closed_form_equals_cvxpy(case):
    z, strips = case
    closed = intersect_strips(z, strips, "frobenius")
    solved = intersect_strips(z, strips, "cvxpy-frobenius")
    size = np.abs(z.generators).max()
    assert np.linalg.norm(solved.generators) == pytest.approx(
        np.linalg.norm(closed.generators), rel=1e-6
    )
    assert np.allclose(solved.center, closed.center, rtol=0, atol=1e-6 * size)
    assert np.allclose(solved.generators, closed.generators, rtol=0, atol=1e-6 * size)


@SETTINGS
@given(zonotope_with_strips(4), st.integers(0, 2**32 - 1))
def test_frobenius_gain_is_a_minimum_of_the_generator_norm(case, seed):
    z, strips = case
    unit = strips.normalized()
    gain = gains.frobenius_gain(z, unit)
    best = np.linalg.norm(gains.updated_generators(z.generators, unit, gain))
    rng = np.random.default_rng(seed)
    for _ in range(10):
        other = gain + 1e-3 * rng.normal(size=gain.shape)
        assert np.linalg.norm(gains.updated_generators(z.generators, unit, other)) >= best


@SETTINGS
@given(st.one_of(zonotope_with_strips(2), zonotope_with_strips(4)))
def test_volume_is_never_larger_than_frobenius_or_the_input(case):
    z, strips = case
    volume = intersect_strips(z, strips, "volume").volume()
    assert volume <= intersect_strips(z, strips, "frobenius").volume()
    assert volume <= z.volume()
    assert intersect_strips(z, strips, "cvxpy-volume").volume() <= z.volume()


@SETTINGS
@given(zonotopes(2, max_generators=8), st.integers(0, 2**32 - 1))
def test_2d_fast_path_reaches_the_lp_optimum(z, seed):
    rng = np.random.default_rng(seed)
    h = rng.normal(size=2)
    h /= np.linalg.norm(h)
    r = float(np.abs(h @ z.generators).sum() * rng.uniform(0.05, 1.2))
    fast = gains.volume_gain_vertices(z.generators, h, r)
    lp = gains.volume_gain_lp(z.generators, h, r)
    values = gains.strip_gain_volume(z.generators, h, r, np.vstack([fast, lp]))
    assert values[0] == pytest.approx(values[1], rel=1e-6)
    strip = Strips(h, h @ z.center, r)
    fast_set = intersect_strips(z, strip, "volume")
    assert fast_set.volume() == pytest.approx(intersect_strips(z, strip, "cvxpy-volume").volume(),
                                              rel=1e-6)


def test_volume_lp_guard_falls_back_to_zero_for_an_uncut_zonotope():
    """A strip twice as wide as Z: λ = 0 is optimal, the LP must not return anything worse."""
    g = np.array([[1.0, 0.5, 0.0], [0.0, 1.0, 1.0], [0.0, 0.0, 1.0]])
    lam = gains.volume_gain_lp(g, np.array([1.0, 0.0, 0.0]), 10.0)
    assert np.array_equal(lam, np.zeros(3))


@pytest.mark.parametrize("method", METHODS)
def test_points_and_segments(method):
    point = Zonotope([1.0, 2.0], [])
    strip = Strips([[1.0, 0.0]], [1.2], [0.5])
    assert intersect_strips(point, strip, method) is point
    segment = Zonotope([0.0, 0.0], [[2.0, 1.0], [2.0, 1.0]])
    result = intersect_strips(segment, strip, method)
    assert result.contains(np.array([[0.7, 0.7], [1.7, 1.7], [1.2, 1.2]]), tol=1e-9).all()
    assert np.abs(result.generators).sum() < np.abs(segment.generators).sum()


@pytest.mark.parametrize("method", METHODS)
def test_strip_normal_scaling_does_not_change_the_result(method):
    z = Zonotope([0.5, -0.2], [[1.0, 0.3, -0.4], [0.2, 1.0, 0.5]])
    strips = Strips([[1.0, 0.4], [-0.3, 1.0]], [0.6, 0.1], [0.3, 0.4])
    scaled = Strips(strips.normals * [[3.0], [0.2]], strips.values * [3.0, 0.2],
                    strips.radii * [3.0, 0.2])
    a, b = intersect_strips(z, strips, method), intersect_strips(z, scaled, method)
    assert np.allclose(a.center, b.center, atol=1e-7)
    assert a.volume() == pytest.approx(b.volume(), rel=1e-6)


def test_dpp_problem_is_compiled_once_per_shape():
    z = Zonotope([0.0, 0.0, 0.0], np.diag([1.0, 2.0, 3.0]) + 0.1)
    strips = Strips([[1.0, 0.0, 0.0], [0.0, 1.0, 1.0]], [0.2, 0.1], [0.5, 0.4])
    key = ("frobenius", 3, 2, 3)
    gains.PROBLEM_CACHE.pop(key, None)
    intersect_strips(z, strips, "cvxpy-frobenius")
    first = gains.PROBLEM_CACHE[key].problem
    intersect_strips(z.translate([1.0, 0.0, 0.0]), strips, "cvxpy-frobenius")
    assert gains.PROBLEM_CACHE[key].problem is first
    assert sum(k[:1] == ("frobenius",) and k[1:] == key[1:] for k in gains.PROBLEM_CACHE) == 1
    assert first.is_dcp(dpp=True)
    assert all(entry.problem.is_dcp(dpp=True) for entry in gains.PROBLEM_CACHE.values())


@pytest.mark.kernels
@SETTINGS
@given(zonotopes(4), st.integers(0, 2**32 - 1))
def test_a_block_cut_is_sound_and_keeps_the_other_coordinates_exactly(z, seed):
    """Strips on coordinates 2 and 3 alone (a velocity bound): the block cut holds Z ∩ S, keeps
    the set of coordinates 0 and 1 as it was (centre, and support in every direction), and
    its block is no larger in area than Z's (Λ = 0 is one of the candidates)."""
    rng = np.random.default_rng(seed)
    m = int(rng.integers(1, 5))
    block = rng.normal(size=(m, 2)) * rng.uniform(0.5, 3.0, (m, 1))
    normals = np.hstack([np.zeros((m, 2)), block])
    width = np.abs(normals @ z.generators).sum(axis=1)
    radii = width * rng.uniform(0.05, 0.8, m)
    point = z.center + z.generators @ rng.uniform(-1, 1, z.n_generators)
    strips = Strips(normals, normals @ point + rng.uniform(-1, 1, m) * radii, radii)
    result = gains.intersect_block_strips(z, strips, 2)
    points = strip_intersection_points(z, strips, rng)
    assert zonotope_facet_strips(result).contains(points, tol=tolerance(z)).all()
    directions = np.array([[np.cos(a), np.sin(a)] for a in np.linspace(0, np.pi, 16)])
    before = np.abs(directions @ z.generators[:2]).sum(axis=1)
    after = np.abs(directions @ result.generators[:2]).sum(axis=1)
    assert np.allclose(after, before, rtol=1e-12, atol=0.0)
    assert np.array_equal(result.center[:2], z.center[:2])
    block_area = Zonotope(z.center[2:], z.generators[2:]).volume()
    assert Zonotope(result.center[2:], result.generators[2:]).volume() <= block_area * (1 + 1e-9)


def test_a_block_cut_refuses_strips_outside_its_block():
    z = Zonotope(np.zeros(4), np.eye(4))
    with pytest.raises(ValueError, match="zero outside the block"):
        gains.intersect_block_strips(z, Strips([1.0, 0.0, 1.0, 0.0], 0.0, 1.0), 2)
    with pytest.raises(ValueError, match="no 2-D block starts at coordinate 3"):
        gains.intersect_block_strips(z, Strips([0.0, 0.0, 1.0, 0.0], 0.0, 1.0), 3)

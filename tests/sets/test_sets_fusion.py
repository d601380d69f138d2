"""Proposition 2 (eqs. cdiff, gdiff) and the fusion methods built on it."""

from functools import reduce

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sets_strategies import (
    SETTINGS,
    overlapping_zonotopes,
    polygon_points,
    tolerance,
    zonotope_intersection_points,
)

from sse_cosim.sets import (
    FUSION_METHODS,
    Zonotope,
    available_fusion_methods,
    fuse,
    fuse_with_weights,
    zonotope_facet_strips,
)
from sse_cosim.sets.exact import zonotope_polygon
from sse_cosim.sets.fusion import EXACT_SIZE_GENERATORS
from sse_cosim.sets.zonotope import generator_volume_reference

METHODS = sorted(FUSION_METHODS)


def exact_intersection_2d(sets):
    return reduce(lambda a, b: a.intersection(b), [zonotope_polygon(z) for z in sets])


def test_registry_and_input_validation():
    assert set(available_fusion_methods()) == {"frobenius", "volume", "strips", "enclose"}
    z = Zonotope([0.0, 0.0], np.eye(2))
    assert fuse([z], "volume") is z
    with pytest.raises(ValueError, match="unknown fusion method"):
        fuse([z, z], "nope")
    with pytest.raises(ValueError, match="dimensions"):
        fuse([z, Zonotope([0.0], [[1.0]])])
    with pytest.raises(ValueError, match="sum to zero"):
        fuse_with_weights([z, z], [1.0, -1.0])


@SETTINGS
@given(overlapping_zonotopes(2), st.integers(0, 2**32 - 1))
def test_any_weights_with_nonzero_sum_are_sound(sets, seed):
    rng = np.random.default_rng(seed)
    weights = rng.normal(size=len(sets))
    weights[0] += 0.5 - weights.sum()  # keep the sum away from zero, signs mixed
    fused = fuse_with_weights(sets, weights)
    points = polygon_points(exact_intersection_2d(sets), rng)
    assert fused.contains(points, tol=tolerance(*sets, fused)).all()


@SETTINGS
@given(
    st.one_of(overlapping_zonotopes(2), overlapping_zonotopes(3), overlapping_zonotopes(4)),
    st.integers(0, 2**32 - 1),
)
def test_no_weights_beat_the_smallest_input(sets, seed):
    """Brunn-Minkowski: Prop. 2 with any weights (mixed signs too) is never smaller than the
    smallest input, so ``volume`` weights (one-hot on it) are the exact optimum."""
    rng = np.random.default_rng(seed)
    smallest = min(z.volume() for z in sets)
    weights = np.vstack([rng.dirichlet(np.ones(len(sets)) * 0.3, size=15),
                         rng.normal(size=(15, len(sets)))])
    for w in weights[np.abs(weights.sum(axis=1)) > 1e-3]:
        assert fuse_with_weights(sets, w).volume() >= smallest * (1 - 1e-9)
    assert fuse(sets, "volume").volume() == smallest


@SETTINGS
@given(st.one_of(overlapping_zonotopes(2), overlapping_zonotopes(4, max_inputs=3)))
def test_volume_strips_and_enclose_never_exceed_the_smallest_input(sets):
    smallest = min(z.volume() for z in sets)
    for method in ("volume", "strips", "enclose"):
        assert fuse(sets, method).volume() <= smallest, method


@SETTINGS
@given(overlapping_zonotopes(2), st.integers(0, 2**32 - 1))
def test_every_method_contains_the_exact_intersection_2d(sets, seed):
    points = polygon_points(exact_intersection_2d(sets), np.random.default_rng(seed))
    for method in METHODS:
        fused = fuse(sets, method)
        assert fused.contains(points, tol=tolerance(*sets)).all(), method


@settings(SETTINGS, max_examples=12)
@given(overlapping_zonotopes(4, max_inputs=3), st.integers(0, 2**32 - 1))
def test_every_method_contains_the_exact_intersection_4d(sets, seed):
    points = zonotope_intersection_points(sets, np.random.default_rng(seed))
    for method in METHODS:
        facets = zonotope_facet_strips(fuse(sets, method))
        assert facets.contains(points, tol=tolerance(*sets)).all(), method


def test_strips_fusion_is_much_tighter_than_frobenius_weights():
    """Measured on these 40 seeded 2-D cases (2-4 inputs), mean area relative to frobenius:
    strips 0.316, volume (= smallest input) 0.378, exact intersection 0.195."""
    ratios = {"strips": [], "volume": [], "exact": []}
    for seed in range(40):
        sets = _seeded_sets(seed)
        base = fuse(sets, "frobenius").volume()
        ratios["strips"].append(fuse(sets, "strips").volume() / base)
        ratios["volume"].append(fuse(sets, "volume").volume() / base)
        ratios["exact"].append(exact_intersection_2d(sets).area / base)
    means = {k: float(np.mean(v)) for k, v in ratios.items()}
    assert means["exact"] <= means["strips"] < means["volume"] < 1.0
    assert means["strips"] < 0.5


def _seeded_sets(seed, count=None):
    """2-4 (or ``count``) random 2-D zonotopes sharing a point."""
    rng = np.random.default_rng(seed)
    common = rng.uniform(-5, 5, 2)
    sets = []
    for _ in range(count or int(rng.integers(2, 5))):
        g = rng.normal(size=(2, int(rng.integers(2, 6))))
        sets.append(Zonotope(common - g @ rng.uniform(-1, 1, g.shape[1]), g))
    return sets


def test_a_point_input_is_the_frobenius_fusion():
    point = Zonotope([0.2, 0.1], [])
    box = Zonotope([0.0, 0.0], np.eye(2))
    fused = fuse([box, point], "frobenius")
    assert fused.n_generators == 0 and np.array_equal(fused.center, point.center)
    assert fuse([box, point], "volume").n_generators == 0


def test_an_input_of_many_generators_is_sized_by_an_upper_bound_and_lost_to_a_smaller_one():
    """4-D: a shared estimate aged 30 steps (8 + 60 generators) is sized by its reduction to
    EXACT_SIZE_GENERATORS, whose volume is at least the exact one (an enclosure); the volume
    fusion still picks the input of least volume, and one within the exact bound is sized
    exactly."""
    rng = np.random.default_rng(7)
    aged = Zonotope(np.zeros(4), rng.normal(size=(4, 8 + 60)))
    small = Zonotope(np.zeros(4), 0.1 * rng.normal(size=(4, 8)))
    bound = aged.reduce(EXACT_SIZE_GENERATORS).volume()
    assert bound >= generator_volume_reference(aged.generators) * (1 - 1e-12)
    assert np.array_equal(fuse([aged, small], "volume").generators, small.generators)
    few = Zonotope(np.zeros(4), rng.normal(size=(4, EXACT_SIZE_GENERATORS)))
    assert np.array_equal(fuse([aged, few], "volume").generators,
                          (aged if bound < few.volume() else few).generators)

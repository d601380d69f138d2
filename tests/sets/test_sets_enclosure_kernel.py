"""The compiled ``enclose`` intersection (sets/enclosure_kernels.py) against its NumPy reference
(sets/enclosure.py), piece by piece and whole, and its soundness on hard inputs."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from sets_strategies import (
    EPS,
    SETTINGS,
    overlapping_zonotopes,
    point_in,
    rank_decision_is_clear,
    zonotope_with_strips,
    zonotopes,
)

from sse_cosim.sets import Strips, Zonotope, enclosure, fusion, gains, zonotope_facet_strips
from sse_cosim.sets import enclosure_kernels as kernels
from sse_cosim.sets.zonotope import full_rank

pytestmark = pytest.mark.kernels


def _directions_of(zonotope: Zonotope, strips: Strips) -> np.ndarray:
    """The directions ``enclose_correction`` encloses along: Z's generators, the strips' edges."""
    unit = strips.normalized()
    edges = np.stack([-unit.normals[:, 1], unit.normals[:, 0]])
    return np.hstack([zonotope.generators, edges])


def _compiled_intersection(zonotope: Zonotope, strips: Strips, directions: np.ndarray
                           ) -> tuple[Zonotope, np.ndarray] | None:
    """The kernel's answer shaped like the reference's: (enclosure, polygon about Z's
    center), or None."""
    found, center, generators, polygon = kernels.enclose_intersection(
        zonotope.generators, strips.normals, strips.values - strips.normals @ zonotope.center,
        strips.radii, directions)
    if not found:
        return None
    return Zonotope(zonotope.center + center, generators), polygon


def _area_tolerance(zonotope: Zonotope) -> float:
    """Areas may differ by the containment margin along the perimeter: flat sets (near-parallel
    generators) have areas far below their size squared, so a relative bound alone is too
    tight."""
    return 1e-9 * np.abs(zonotope.generators).sum() ** 2


def _barely_touching(zonotope: Zonotope, strips: Strips) -> Strips:
    """The same normals, each strip moved so that it only just reaches into Z."""
    support = np.abs(strips.normals @ zonotope.generators).sum(axis=1)
    values = strips.normals @ zonotope.center + support + strips.radii * (1 - 1e-9)
    return Strips(strips.normals, values, strips.radii)


@SETTINGS
@given(zonotopes(2, max_generators=12))
def test_compiled_vertices_are_the_zonotopes_vertices(zonotope):
    scale = np.abs(zonotope.generators).sum()
    expected = Zonotope.unchecked(np.zeros(2), zonotope.generators).vertices()
    np.testing.assert_allclose(kernels.zonotope_vertices(zonotope.generators), expected,
                               rtol=0, atol=1e-12 * scale)


@SETTINGS
@given(zonotope_with_strips(2), st.booleans())
def test_compiled_clipping_is_the_reference_clipping(case, touch):
    zonotope, strips = case
    if touch:
        strips = _barely_touching(zonotope, strips)
    unit = strips.normalized()
    corners = zonotope.vertices()
    compiled = kernels.clip_to_strips(corners, unit.normals, unit.values, unit.radii)
    reference = enclosure.clip_to_strips(corners, unit.normals, unit.values, unit.radii)
    assert compiled.shape == reference.shape
    np.testing.assert_allclose(compiled, reference, rtol=0,
                               atol=1e-12 * np.abs(corners).max())


@SETTINGS
@given(zonotopes(2, max_generators=12))
def test_compiled_directions_are_the_reference_directions(zonotope):
    np.testing.assert_allclose(kernels.unit_directions(zonotope.generators),
                               enclosure.unit_directions(zonotope.generators), rtol=0, atol=1e-15)


@SETTINGS
@given(zonotope_with_strips(2), st.booleans(), st.integers(0, 2**32 - 1))
def test_compiled_enclosure_matches_the_reference_and_holds_the_intersection(case, touch, seed):
    """Same polygon, same enclosure up to rounding (the area within 1e-8: the weighted L1
    centre may tie, and rounding then picks another optimum of the same cost), and every point
    of Z ∩ S inside the compiled enclosure."""
    zonotope, strips = case
    if touch:
        strips = _barely_touching(zonotope, strips)
    unit = strips.normalized()
    directions = _directions_of(zonotope, strips)
    compiled = _compiled_intersection(zonotope, unit, directions)
    reference = enclosure.enclose_intersection_reference(zonotope, unit, directions)
    assert (compiled is None) == (reference is None)
    if compiled is None:
        return
    (enclosed, polygon), (expected, expected_polygon) = compiled, reference
    scale = np.abs(zonotope.generators).sum()
    np.testing.assert_allclose(polygon, expected_polygon, rtol=0, atol=1e-12 * scale)
    assert enclosed.volume() == pytest.approx(expected.volume(), rel=1e-8, abs=1e-12 * scale**2)
    rng = np.random.default_rng(seed)
    points = np.array([point_in(zonotope, rng) for _ in range(300)])
    inside = (np.abs(points @ unit.normals.T - unit.values) <= unit.radii).all(axis=1)
    candidates = np.vstack([points[inside], zonotope.center + polygon])
    assert enclosed.contains(candidates, tol=0.0).all()


def test_compiled_enclosure_of_a_sliver_polygon_is_sound():
    """A strip that leaves only a sliver along an edge of the square (a near-segment
    polygon), enclosed with room."""
    square = Zonotope(np.array([3.0, -2.0]), np.eye(2))
    strips = Strips(np.array([[1.0, 0.0]]), np.array([4.0]), np.array([1e-12]))
    found = _compiled_intersection(square, strips, np.hstack([np.eye(2), [[0.0], [1.0]]]))
    assert found is not None
    enclosed, polygon = found
    assert enclosed.contains(square.center + polygon, tol=0.0).all()
    assert enclosed.contains(np.array([[4.0, -3.0], [4.0, -1.0]]), tol=0.0).all()


def test_compiled_enclosure_of_disjoint_strips_is_none():
    square = Zonotope(np.zeros(2), np.eye(2))
    strips = Strips(np.array([[1.0, 0.0]]), np.array([5.0]), np.array([0.5]))
    assert _compiled_intersection(square, strips, np.eye(2)) is None
    assert enclosure.enclose_intersection_reference(square, strips, np.eye(2)) is None


@SETTINGS
@given(zonotope_with_strips(2), st.booleans())
def test_compiled_enclose_correction_matches_the_reference(case, touch):
    zonotope, strips = case
    if touch:
        strips = _barely_touching(zonotope, strips)
    unit = strips.normalized()
    compiled = gains.enclose_correction(zonotope, unit)
    reference = gains.enclose_correction_reference(zonotope, unit)
    assert compiled.volume() == pytest.approx(reference.volume(), rel=1e-8,
                                              abs=_area_tolerance(zonotope))


@SETTINGS
@given(overlapping_zonotopes(2))
def test_compiled_enclose_fusion_matches_the_reference(sets):
    compiled = fusion.enclose_fusion(sets)
    reference = fusion.enclose_fusion_reference(sets)
    assert compiled.volume() == pytest.approx(reference.volume(), rel=1e-8,
                                              abs=max(_area_tolerance(z) for z in sets))


@SETTINGS
@given(zonotopes(2, max_generators=12))
def test_compiled_facet_strips_are_the_reference_strips(zonotope):
    expected = zonotope_facet_strips(zonotope)
    normals, values, radii = kernels.facet_strips(zonotope.center, zonotope.generators)
    np.testing.assert_allclose(normals, expected.normals, rtol=0, atol=1e-15)
    np.testing.assert_allclose(values, expected.values, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(radii, expected.radii, rtol=1e-12)


def shoelace_tolerance(vertices: np.ndarray) -> float:
    """How far apart two shoelace areas of the same polygon (m, 2) may be: the kernel sums the
    m terms x_i y_{i+1} - y_i x_{i+1} in a loop, the reference x·roll(y) - y·roll(x) as two
    dot products (BLAS, or another order). Each sums 2m rounded products, within m·eps of
    Σ|x_i y_{i+1}| + |y_i x_{i+1}|; half of that, twice. A degenerate polygon (a segment, a
    sliver) has an area of rounding size, 0.0 on one side and 1e-19 on the other."""
    x, y = vertices[:, 0], vertices[:, 1]
    terms = np.abs(x * np.roll(y, -1)) + np.abs(y * np.roll(x, -1))
    return (len(vertices) + 1) * EPS * terms.sum()


@SETTINGS
@given(zonotopes(2, min_generators=0, max_generators=12))
def test_compiled_full_rank_and_area_are_the_references(zonotope):
    if rank_decision_is_clear(zonotope.generators):
        assert kernels.full_rank_2d(zonotope.generators) == full_rank(zonotope.generators)
    vertices = zonotope.vertices()
    assert abs(kernels.polygon_area(vertices) - enclosure.polygon_area(vertices)) \
        <= shoelace_tolerance(vertices)


def _enclose_points_reference(points: np.ndarray, generators: np.ndarray) -> Zonotope | None:
    """``enclose_points`` from the NumPy reference's pieces: about the points' mean, along the
    generators' and the axes' directions."""
    origin = points.mean(axis=0)
    found = enclosure.enclose_polygon(points - origin, enclosure.unit_directions(
        np.hstack([generators, np.eye(2)])), float(np.abs(points - origin).max()) or 1.0)
    return None if found is None else Zonotope(origin + found[0], found[1])


@pytest.mark.parametrize("seed", range(30))
def test_compiled_enclosure_of_points_matches_the_reference_and_holds_them(seed):
    """Far from the origin too (UTM-sized): the area within 1e-8 of the reference's, and
    every point inside, with no slack."""
    rng = np.random.default_rng(seed)
    offset = (0.0, 5.7e6)[seed % 2] * np.array([0.09, 1.0])
    points = rng.normal(size=(int(rng.integers(1, 25)), 2)) * rng.uniform(0.1, 5) + offset
    generators = rng.normal(size=(2, int(rng.integers(0, 6))))
    found, center, enclosure_generators = kernels.enclose_points(points, generators)
    reference = _enclose_points_reference(points, generators)
    assert found == (reference is not None)
    if not found:
        return
    compiled = Zonotope(center, enclosure_generators)
    scale = float(np.abs(points - points.mean(axis=0)).max()) or 1.0
    assert compiled.volume() == pytest.approx(reference.volume(), rel=1e-8, abs=1e-12 * scale**2)
    assert compiled.contains(points, tol=0.0).all()

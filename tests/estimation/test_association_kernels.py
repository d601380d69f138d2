"""The association's compiled candidate test (``association_kernels.candidate_tests``) gives
the decisions of its references, ``association.meets_reference`` and
``association.inside_reference`` (after the box tests), on random predictions and detections:
the same, except where the reference's own answer turns within 1e-9 m of its tolerance (a
vertex within rounding of an edge)."""

from __future__ import annotations

import numpy as np
import pytest

from sse_cosim.estimation import association
from sse_cosim.estimation.association import MEET_TOL, AnonymousDetection, _Detections
from sse_cosim.estimation.motion import motion_model
from sse_cosim.scenario.model import Estimator
from sse_cosim.sets import Strips, Zonotope
from sse_cosim.sets.kernels import full_rank_2d

pytestmark = pytest.mark.kernels

NEAR = 1e-9  # m: a reference answer that turns within this of its tolerance is a tie


def random_detections(rng: np.random.Generator, count: int) -> list[AnonymousDetection]:
    """Detections about the origin: two strips each, turned at random, 0.2-2 m wide."""
    found = []
    for i in range(count):
        angle = rng.uniform(0, np.pi)
        turn = rng.uniform(0.4, np.pi - 0.4)
        normals = np.array([[np.cos(angle), np.sin(angle)],
                            [np.cos(angle + turn), np.sin(angle + turn)]]) * rng.uniform(0.5, 2)
        values = normals @ rng.uniform(-6, 6, size=2)
        found.append(AnonymousDetection(f"s{i % 3}", Strips(normals, values,
                                                            rng.uniform(0.1, 1.0, size=2))))
    return found


def reference(found: _Detections, path: Zonotope, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """The references as ``_candidates`` called them before the kernel, box tests first."""
    lo, hi = path.interval_hull()
    meets = np.zeros(len(found.items), dtype=bool)
    inside = np.zeros(len(found.items), dtype=bool)
    for d, strips in enumerate(found.paths):
        near = (found.lo[d] <= hi + tol).all() and (found.hi[d] >= lo - tol).all()
        unit = strips.normalized()
        meets[d] = near and association.meets_reference(path, Strips.unchecked(
            unit.normals, unit.values, unit.radii + tol - MEET_TOL))
        inside[d] = meets[d] and (found.lo[d] >= lo).all() and (found.hi[d] <= hi).all() \
            and _inside(found.parallelograms[d], path, tol)
    return meets, inside


def _inside(inner: Zonotope, path: Zonotope, tol: float) -> bool:
    if tol == MEET_TOL:
        return association.inside_reference(inner, path)
    return full_rank_2d(path.generators) and bool(
        np.all(path.contains(inner.vertices(), tol=-tol)))


@pytest.mark.parametrize("seed", range(40))
def test_the_compiled_candidate_test_decides_as_its_references(seed):
    rng = np.random.default_rng(seed)
    model = motion_model(Estimator(position_jitter_m=float(rng.uniform(0, 1))), 0.1)
    found = _Detections.of(random_detections(rng, int(rng.integers(1, 30))), model)
    generators = rng.normal(size=(2, int(rng.integers(1, 9)))) * rng.uniform(0.2, 4)
    if seed % 5 == 0:
        generators[:, 1:] = 0.0  # a segment: nothing is inside it
    path = Zonotope(rng.uniform(-3, 3, size=2), generators)
    meets, inside = found.tests(path)
    want_meets, want_inside = reference(found, path, MEET_TOL)
    assert want_meets.any() or seed % 5 == 0  # the draws test something
    tighter, looser = reference(found, path, MEET_TOL - NEAR), reference(found, path,
                                                                        MEET_TOL + NEAR)
    ties = tighter[0] != looser[0]
    assert ((meets == want_meets) | ties).all()
    inner_ties = tighter[1] != looser[1]
    assert ((inside == want_inside) | inner_ties | ties).all()

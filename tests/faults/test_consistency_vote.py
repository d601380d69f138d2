"""The consistency vote, the hull, probation and negative information (the exact tests:
tests/sets/test_sets_overlap.py)."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from sse_cosim.estimation.bus_screen import contradicted
from sse_cosim.estimation.motion import motion_model
from sse_cosim.estimation.occupancy import ClearRegion
from sse_cosim.estimation.vote import (
    READMIT_STEPS,
    Probation,
    interval_hull,
    largest_consistent_groups,
    vote,
)
from sse_cosim.regions import PolygonRegion as R
from sse_cosim.regions import kind
from sse_cosim.scenario.model import Estimator
from sse_cosim.sets import Zonotope

# jitter 0.3 m; reach 2.5 m/s x 0.1 s = 0.25 m per step
MODEL = motion_model(Estimator(max_pedestrian_speed_mps=2.5, position_jitter_m=0.3), 0.1)
K = kind("polygon")


def box(x: float, y: float, half: float = 1.0) -> Zonotope:
    return Zonotope(np.array([x, y]), np.eye(2) * half)


def test_unique_majority_leaves_out_the_odd_one():
    result = vote([box(0, 0), box(0.5, 0), box(0.2, 0.4), box(9, 9)])
    assert result.accepted == {0, 1, 2} and result.suspects == {3} and not result.conflict


def test_two_disagreeing_sets_are_a_conflict_with_both_suspect():
    result = vote([box(0, 0), box(5, 0)])
    assert result.conflict and result.suspects == {0, 1} and not result.accepted


def test_a_tie_is_a_conflict_unless_one_side_holds_a_proven_source():
    sets = [box(0, 0, 2.0), box(-1.5, 0), box(1.5, 0)]  # 1 and 2 each meet 0, not each other
    tie = vote(sets)
    assert tie.conflict and tie.suspects == {1, 2}
    broken = vote(sets, proven=frozenset({2}))
    assert not broken.conflict and broken.accepted == {0, 1} and broken.suspects == {2}


def test_a_majority_smaller_than_all_but_one_is_a_conflict():
    sets = [box(0, 0), box(0.5, 0), box(10, 0), box(20, 0)]
    assert largest_consistent_groups(sets) == [frozenset({0, 1})]
    assert vote(sets).conflict


def test_interval_hull_holds_every_set():
    sets = [box(0, 0), Zonotope(np.array([4.0, 1.0]), np.array([[1.0, 0.5], [0.5, -1.0]]))]
    hull = interval_hull(sets)
    for z in sets:
        assert hull.contains(z.vertices()).all()


def test_probation_counts_agreement_in_a_row():
    probation = Probation().update(["a", "b"], ["a"])
    assert "b" in probation and probation.proven == {"b"}
    for _ in range(READMIT_STEPS - 1):
        probation = probation.update(["a", "b"], ["a", "b"])
        assert "b" in probation
    assert "b" in probation.update(["a", "b"], ["a"])  # disagreeing again starts over
    assert "b" not in probation.update(["a", "b"], ["a", "b"])
    assert "b" in probation.update(["a"], ["a"])  # not voting: still waiting


def test_conflict_suspects_wait_but_are_not_proven():
    probation = Probation().suspect(["a", "b"])
    assert "a" in probation and "b" in probation and probation.proven == frozenset()


@pytest.mark.parametrize("gap", [1e-3, 0.2, 1.0])
def test_negative_information_never_contradicts_a_set_that_holds_the_path(gap):
    """Clear views that just miss p: a set holding s (|p - s| <= eps) is never contradicted."""
    rng = np.random.default_rng(3)
    eps = MODEL.jitter
    for _ in range(200):
        s = rng.uniform(-5, 5, 2)
        p = s + eps * rng.uniform(-1, 1, 2) / np.sqrt(2)
        estimate = Zonotope(s + rng.uniform(-0.2, 0.2, 2), np.eye(2) * 0.2)
        direction = rng.normal(size=2)
        direction /= np.linalg.norm(direction)
        size = rng.uniform(2, 20)
        centre = p + direction * (gap + size / np.sqrt(2))
        region = shapely.box(*(centre - size / 2), *(centre + size / 2))
        assert not contradicted(estimate, [ClearRegion(R(region), 0)], MODEL, K)


def test_a_set_inside_a_clear_view_is_contradicted():
    view = R(shapely.box(-10, -10, 10, 10))
    assert contradicted(box(0, 0), [ClearRegion(view, 0)], MODEL, K)
    assert not contradicted(box(9.5, 0), [ClearRegion(view, 0)], MODEL, K)
    assert not contradicted(box(0, 0), [ClearRegion(view, 40)], MODEL, K)  # seen long ago


def test_a_region_keeps_its_erosions():
    # a region serves the erosion it computed before at the same distance, equal to one
    # computed afresh; another distance, or an equal region that is another object, computes
    view = R(shapely.box(-10, -10, 10, 10).union(shapely.box(5, 5, 20, 8)))
    first = view.erode(0.7)
    assert view.erode(0.7) is first
    twin = R(shapely.box(-10, -10, 10, 10).union(shapely.box(5, 5, 20, 8)))
    assert twin.erode(0.7) is not first
    assert twin.erode(0.7).shape.equals_exact(first.shape, 0.0)
    assert view.erode(1.2).area < first.area

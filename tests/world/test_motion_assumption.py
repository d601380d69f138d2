"""The pure check of the pedestrian assumption (``world/assumptions.py``): S_k stays non-empty."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from sse_cosim.world.assumptions import (
    COARSE_SIDES,
    FINE_SIDES,
    MotionBounds,
    PedestrianMotionCheck,
    admits,
    intersect,
    least_jitter,
    minkowski_sum,
    unit_polygon,
)

BOUNDS = MotionBounds(speed_mps=2.5, jitter_m=0.3, step_s=0.1)  # v dt = 0.25 m, eps = 0.3 m


def run(positions: np.ndarray, bounds: MotionBounds = BOUNDS, needed: bool = True) -> list:
    check = PedestrianMotionCheck(bounds, needed_jitter=needed)
    found = []
    for k, xy in enumerate(positions):
        found += check.step(round(0.1 * k, 6), {"ped": (xy[0], xy[1])})
    return found


def test_minkowski_sum_of_squares_is_a_square():
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    total = minkowski_sum(square, square + 5.0)
    assert sorted(map(tuple, total)) == [(5.0, 5.0), (5.0, 7.0), (7.0, 5.0), (7.0, 7.0)] or \
        np.allclose(np.ptp(total, axis=0), [2.0, 2.0])
    assert intersect(square, square + 3.0) is None


def test_minkowski_sum_is_the_hull_of_the_vertex_sums_also_with_collinear_edges():
    """Random convex polygons with every edge split at its middle (collinear edges, also
    across the east direction where the merge starts) against shapely's hull of all sums."""
    import shapely

    rng = np.random.default_rng(3)
    for _ in range(100):
        hull = shapely.MultiPoint(rng.normal(size=(10, 2))).convex_hull
        ring = shapely.get_coordinates(shapely.orient_polygons(hull).exterior)[:-1]
        split = np.empty((2 * len(ring), 2))
        split[0::2], split[1::2] = ring, 0.5 * (ring + np.roll(ring, -1, axis=0))
        other = 0.3 * unit_polygon(COARSE_SIDES)
        total = minkowski_sum(np.roll(split, rng.integers(len(split)), axis=0), other)
        reference = shapely.MultiPoint((split[:, None, :] + other[None]).reshape(-1, 2))
        assert shapely.Polygon(total).symmetric_difference(reference.convex_hull).area < 1e-12


def test_fine_polygon_holds_the_coarse_one():
    coarse, fine = unit_polygon(COARSE_SIDES), unit_polygon(FINE_SIDES)
    assert all(np.abs(fine - v).sum(axis=1).min() == 0.0 for v in coarse)


def test_a_walker_at_exactly_the_speed_bound_passes():
    steps = np.arange(3000)[:, np.newaxis] * np.array([[0.25 * 0.6, 0.25 * 0.8]])
    assert run(steps, needed=False) == []


def test_a_jump_just_beyond_jitter_and_step_fails():
    jump = 0.3 + 0.25 + 1e-3
    positions = np.array([[0.0, 0.0], [0.0, 0.0], [jump + 0.3, 0.0]])
    # from p_1 the path point may lie 0.3 m ahead and move 0.25 m: p_2 must be within 0.85 m
    found = run(positions)
    assert len(found) == 1
    assert found[0].time == pytest.approx(0.2)
    assert found[0].distance_m == pytest.approx(jump + 0.3 - 0.55, abs=1e-6) or \
        found[0].beyond_m > 0
    positions[2, 0] = 0.85 - 1e-6  # just inside: no break
    assert run(positions) == []


def test_single_jump_of_jitter_plus_step_plus_a_millimetre_fails():
    """From a standing start, a jump of eps + v dt + 1e-3 is beyond S_0 (+) disc(v dt) by
    more than eps? No: S_0 = disc(p_0, eps), so the bound is 2 eps + v dt; the first step's
    tightest case is a walker that stood long enough to pin its set (here: it came from the
    other side)."""
    positions = np.array([[-0.3 - 0.25 * k, 0.0] for k in range(10, 0, -1)] + [[0.0, 0.0]])
    positions = np.vstack([positions, [[0.3 + 0.25 + 1e-3, 0.0]]])
    # walking east at the bound, S_k is pinned to p_k's disc front; the last step then needs
    # |p_{k+1} - p_k| <= v dt + ... : a reversal of direction is fine, a jump is not
    found = run(positions)
    assert found == [] or found[0].time == pytest.approx(1.1)


def test_a_lateral_replacement_within_the_jitter_passes():
    walk = [[0.1 * k, 0.0] for k in range(30)]
    walk += [[0.1 * k, 0.58] for k in range(30, 60)]  # re-placed sideways by 0.58 m < 2 eps
    assert run(np.array(walk)) == []


def test_accumulated_drift_is_caught_although_every_step_is_within_the_bounds():
    """Each step moves v dt + 0.08 m < v dt + eps: the path falls behind by 0.08 m a step and
    leaves the jitter's disc after a few steps."""
    steps = np.arange(20)[:, np.newaxis] * np.array([[0.33, 0.0]])
    found = run(steps)
    assert found, "drift not caught"
    first = found[0]
    assert first.step_m == pytest.approx(0.33)
    assert first.step_m < BOUNDS.step_m + BOUNDS.jitter_m
    # 2 eps = 0.6 m of slack, 0.08 m lost per step: step k = 8 (0.64 m) cannot be reached
    assert first.time == pytest.approx(0.8)
    assert first.distance_m == pytest.approx(0.3 + 0.04, abs=1e-6)
    assert first.needed_jitter_m is not None and first.needed_jitter_m > 0.3


def test_the_needed_jitter_admits_the_walk_and_a_little_less_does_not():
    steps = np.arange(20)[:, np.newaxis] * np.array([[0.35, 0.0]])
    needed = least_jitter(steps, BOUNDS)
    # the exact least jitter: the walk drifts 0.1 m a step for 19 steps: 2 eps = 1.9 m;
    # least_jitter is at most 0.13 % + 2 mm above it
    assert 0.95 <= needed <= 0.95 * 1.0013 + 0.002
    assert admits(steps, MotionBounds(2.5, needed, 0.1), sides=FINE_SIDES)
    # a little less than the exact least (0.95 m) admits no path
    assert not admits(steps, MotionBounds(2.5, 0.95 - 1e-3, 0.1), sides=FINE_SIDES)


def test_zero_jitter_is_a_plain_speed_bound():
    bounds = MotionBounds(2.5, 0.0, 0.1)
    # exactly at the bound lies within the tolerance (the inner polygons may call it a break)
    below = 0.25 - 1e-6
    assert run(np.array([[0.0, 0.0], [below, 0.0], [2 * below, 0.0]]), bounds) == []
    assert len(run(np.array([[0.0, 0.0], [0.2501, 0.0]]), bounds)) == 1


def test_a_break_restarts_the_walk_and_absent_pedestrians_are_forgotten():
    check = PedestrianMotionCheck(BOUNDS)
    assert check.step(0.0, {"a": (0.0, 0.0)}) == []
    assert len(check.step(0.1, {"a": (5.0, 0.0)})) == 1
    assert check.step(0.2, {"a": (5.1, 0.0)}) == []  # afresh from 5 m
    assert check.step(0.3, {}) == []
    assert check.step(0.4, {"a": (50.0, 0.0)}) == []  # came back: afresh


def test_cost_per_step_of_a_crowd():
    """21 pedestrians walking at 1.5 m/s in different directions: the check's cost per step
    (printed; well under a millisecond per pedestrian)."""
    check = PedestrianMotionCheck(BOUNDS)
    angles = [2 * math.pi * i / 21 for i in range(21)]
    start = time.perf_counter()
    steps = 200
    for k in range(steps):
        positions = {f"p{i}": (0.15 * k * math.cos(a), 0.15 * k * math.sin(a))
                     for i, a in enumerate(angles)}
        assert check.step(0.1 * k, positions) == []
    per_step = (time.perf_counter() - start) / steps
    print(f"cost per step, 21 pedestrians: {per_step * 1e3:.2f} ms")
    assert per_step < 0.05


def first_infeasible_prefix(positions: np.ndarray, speed: float, step: float,
                            jitter: float) -> int | None:
    """The first k such that positions[:k + 1] (k + 1, 2) admit no path (a convex program,
    as tests/world/test_pedestrian_motion_model.py asks), or None."""
    import cvxpy as cp

    def feasible(n: int) -> bool:
        path = cp.Variable((n, 2))
        constraints = [cp.norm(path - positions[:n], axis=1) <= jitter]
        if n > 1:
            constraints.append(cp.norm(path[1:] - path[:-1], axis=1) <= speed * step)
        problem = cp.Problem(cp.Minimize(0), constraints)
        problem.solve(solver=cp.CLARABEL)
        return problem.status == cp.OPTIMAL

    if feasible(len(positions)):
        return None
    low, high = 1, len(positions)  # feasible(low), not feasible(high)
    while high - low > 1:
        middle = (low + high) // 2
        low, high = (middle, high) if feasible(middle) else (low, middle)
    return high - 1


def test_the_check_agrees_with_a_convex_program_on_random_walks():
    """Walks whose steps are up to 0.45 m (beyond v dt = 0.25 m, within v dt + eps): the first
    break the check reports is the first prefix the convex program finds infeasible, on
    every walk not within 1e-4 (relative) of the bounds (there the two may differ)."""
    rng = np.random.default_rng(7)
    compared = 0
    for _ in range(12):
        lengths = rng.uniform(0.0, 0.45, size=40)
        angles = rng.uniform(-0.6, 0.6, size=40)  # mostly one way: drift builds up
        steps = np.column_stack([lengths * np.cos(angles), lengths * np.sin(angles)])
        positions = np.vstack([[0.0, 0.0], np.cumsum(steps, axis=0)])
        exact = first_infeasible_prefix(positions, 2.5, 0.1, 0.3)
        looser = first_infeasible_prefix(positions, 2.5 * 1.0001, 0.1, 0.3 * 1.0001)
        tighter = first_infeasible_prefix(positions, 2.5 * 0.9999, 0.1, 0.3 * 0.9999)
        if not (exact == looser == tighter):
            continue  # within the tolerance band of the bounds
        found = run(positions, needed=False)
        first = None if not found else round(found[0].time / 0.1)
        assert first == exact
        compared += 1
    assert compared >= 8

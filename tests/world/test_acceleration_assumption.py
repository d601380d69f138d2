"""The bounded-acceleration model's check (``world/acceleration_assumption.py``): one path
that keeps the jitter, speed and acceleration discs, on constructed walks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sse_cosim.world.acceleration_assumption import (
    AccelerationBounds,
    AccelerationCheck,
    keeps,
    needed_jitter,
    solve_path,
)

STEP_S = 0.1
SPEED, ACCEL = 2.5, 3.2  # the estimator's defaults: v dt = 0.25 m, a dt^2 = 0.032 m


def bounds(jitter_m: float) -> AccelerationBounds:
    return AccelerationBounds(SPEED, ACCEL, jitter_m, STEP_S)


def run(positions: np.ndarray, jitter_m: float, diagnose: bool = True) -> list:
    check = AccelerationCheck(bounds(jitter_m), diagnose=diagnose)
    found = []
    for k, xy in enumerate(positions):
        found += check.step(round(STEP_S * k, 6), {"ped": (xy[0], xy[1])})
    return found


def walk(speeds: np.ndarray, heading: float = 0.0, start: tuple[float, float] = (100.0, -7.6)
         ) -> np.ndarray:
    """Positions (k + 1, 2) of a walk whose k steps have the given speeds (m/s) along one
    heading (rad)."""
    along = np.concatenate([[0.0], np.cumsum(speeds) * STEP_S])
    return np.array(start) + along[:, None] * np.array([math.cos(heading), math.sin(heading)])


def test_an_instant_start_from_standstill_breaks_a_small_jitter():
    """SUMO's walker without the ramp: standing, then 1.5 m/s from one step to the next. The
    best path speeds up at 3.2 m/s² already while the walker stands, from eps behind it to eps
    ahead (u^2 = 2 a 2 eps), and is eps behind it again when it reaches v: (v - u)^2 / 2a =
    2 eps, so eps = v^2 / 16 a = 0.044 m. 0.02 m breaks where the walk starts, naming the
    acceleration bound."""
    positions = walk(np.r_[np.zeros(10), np.full(30, 1.5)])
    found = run(positions, 0.02)
    assert [round(b.time, 6) for b in found] == [1.1]
    first = found[0]
    assert first.broke == "the acceleration bound"
    assert first.velocity_change_mps == pytest.approx(1.5)
    assert first.distance_m > 0.02 and first.step_m == pytest.approx(0.15)
    needed = needed_jitter(positions, bounds(0.0))
    assert needed == pytest.approx(1.5 ** 2 / (16.0 * ACCEL), abs=2e-3)
    # its walk up to the break needs less: the lag is still growing there
    assert first.needed_jitter_m is not None and 0.02 < first.needed_jitter_m <= needed
    assert run(positions, needed) == []
    assert solve_path(positions - positions[0], np.empty((0, 2)), bounds(needed - 0.002)) is None


def test_a_ramp_within_the_bound_passes_with_a_tiny_jitter():
    """Standing, then speeding up by a_max dt every step to 2.5 m/s (the speed bound), then
    walking on: the walk keeps the model by itself."""
    ramp = np.minimum(np.arange(1, 40) * ACCEL * STEP_S, SPEED)
    positions = walk(np.r_[np.zeros(5), ramp, np.full(20, SPEED)], heading=0.7)
    assert run(positions, 1e-3) == []
    assert needed_jitter(positions, bounds(0.0)) == 0.001  # rounded up from rounding only


def test_a_lateral_jump_within_the_jitter_passes_and_a_larger_one_breaks():
    """A walker at 1.5 m/s re-placed 0.3 m sideways in one step (as SUMO does at a walking
    area): a path drifts across within the jitter; with a jitter it cannot bridge it breaks."""
    positions = walk(np.full(60, 1.5))
    positions[30:, 1] += 0.3
    assert run(positions, 0.2) == []
    needed = needed_jitter(positions, bounds(0.0))
    assert 0.05 < needed < 0.15
    assert run(positions, needed) == []
    found = run(positions, needed - 0.01)
    assert len(found) == 1 and 3.0 <= found[0].time <= 3.1


def test_an_acceleration_beyond_the_bound_by_a_clear_margin_is_caught():
    """Speeding up at twice a_max from standstill to 2.4 m/s and on: a small jitter breaks
    where it speeds up, naming the acceleration bound; the needed jitter passes."""
    ramp = np.minimum(np.arange(1, 40) * 2.0 * ACCEL * STEP_S, 2.4)
    positions = walk(np.r_[np.zeros(5), ramp, np.full(30, 2.4)], heading=-2.0)
    found = run(positions, 0.02)
    assert found and 0.5 <= found[0].time <= 0.9
    assert found[0].broke == "the acceleration bound"
    needed = needed_jitter(positions, bounds(0.0))
    assert needed > 0.04
    assert run(positions, needed) == []


def test_a_walk_faster_than_the_speed_bound_is_caught_as_speed():
    positions = walk(np.full(80, 2.7), heading=2.5)
    found = run(positions, 0.3)
    assert found and found[0].broke == "the speed bound"


def _smooth_walk(rng: np.random.Generator, steps: int) -> np.ndarray:
    """A path (steps + 1, 2) from a random velocity sequence within 0.95 of both bounds:
    random turns, speeding up and slowing down, stops."""
    velocity = np.zeros(2)
    path = [np.zeros(2)]
    for _ in range(steps):
        change = rng.normal(size=2)
        change *= 0.95 * ACCEL * STEP_S * min(1.0, rng.random() * 2) / np.linalg.norm(change)
        velocity = velocity + change
        speed = np.linalg.norm(velocity)
        if speed > 0.95 * SPEED:
            velocity *= 0.95 * SPEED / speed
        path.append(path[-1] + velocity * STEP_S)
    return np.array(path)


@pytest.mark.parametrize("seed", range(12))
def test_a_smooth_path_within_the_bounds_plus_jitter_within_it_always_passes(seed):
    """Random paths within the bounds and random jitter within eps (uniform over the disc,
    shrunk by 1e-6 for the check's margin): never a break, and the walk's own path keeps the
    model (the construction is right)."""
    rng = np.random.default_rng(seed)
    jitter = [0.05, 0.2, 0.6][seed % 3]
    path = _smooth_walk(rng, 300) + rng.uniform(-200.0, 200.0, size=2)
    angle = rng.uniform(0.0, 2.0 * math.pi, size=len(path))
    radius = jitter * np.sqrt(rng.random(len(path))) * (1.0 - 1e-6)
    positions = path + radius[:, None] * np.column_stack([np.cos(angle), np.sin(angle)])
    assert keeps(path, positions, bounds(jitter))
    assert run(positions, jitter) == []


def test_the_solved_path_keeps_the_model_and_continues_the_fixed_points():
    """A window solved after a jump continues the two fixed points: (V) and (A) across the
    seam hold too (keeps checks the steps that reach the new points)."""
    positions = walk(np.full(30, 1.5))
    positions[15:, 0] += 0.5  # a jump ahead
    local = positions - positions[0]
    fixed = local[:2]
    found = solve_path(local[2:], fixed, bounds(0.3))
    assert found is not None
    assert keeps(np.vstack([fixed, found]), local[2:], bounds(0.3))
    assert solve_path(local[2:], fixed, bounds(0.1)) is None


def test_a_pedestrian_that_leaves_is_forgotten_and_one_that_broke_starts_afresh():
    check = AccelerationCheck(bounds(0.02), diagnose=False)
    positions = walk(np.r_[np.zeros(3), np.full(10, 1.5)])
    found = []
    for k, xy in enumerate(positions):
        found += check.step(0.1 * k, {"ped": tuple(xy)})
    assert len(found) == 1 and found[0].needed_jitter_m is None and found[0].broke is None
    # after the break its set started at that position: walking on is no break
    assert check.step(1.4, {"ped": tuple(positions[-1] + [0.15, 0.0])}) == []
    assert check.step(1.5, {}) == []
    assert check.step(1.6, {"ped": (0.0, 0.0)}) == []  # back far away: a new walk

"""Local observers on synthetic trajectories: the truth stays inside every set, every step."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from sse_cosim.estimation.bus_fusion import fuse_at_bus
from sse_cosim.estimation.motion import POSITION_MEMO, motion_model
from sse_cosim.estimation.observer import NodeObserver
from sse_cosim.estimation.settings import EstimatorSettings
from sse_cosim.scenario.model import Estimator
from sse_cosim.sets import Strips, Zonotope

DT = 0.1


def trajectory(rng: np.random.Generator, steps: int, speed: float, jitter: float) -> np.ndarray:
    """Positions p = s + e: a path s moving at most ``speed * DT`` per step (Euclidean),
    plus a jitter of norm at most ``jitter`` (with occasional full-size jumps). Shape (steps, 2)."""
    path = np.zeros((steps, 2))
    heading = rng.uniform(0, 2 * np.pi)
    for k in range(1, steps):
        heading += rng.normal(0, 0.6)
        path[k] = path[k - 1] + rng.uniform(0, speed * DT) * np.array([np.cos(heading),
                                                                        np.sin(heading)])
    angles = rng.uniform(0, 2 * np.pi, steps)
    sizes = np.where(rng.random(steps) < 0.2, jitter, rng.uniform(0, jitter, steps))
    return path + sizes[:, None] * np.column_stack([np.cos(angles), np.sin(angles)])


def sensor_strips(rng, truth: np.ndarray, bound: float, worst_case: bool) -> Strips:
    """One detection: the rows of H are a random sensor's forward and lateral axes."""
    angle = rng.uniform(0, 2 * np.pi)
    h = np.array([[np.cos(angle), np.sin(angle)], [-np.sin(angle), np.cos(angle)]])
    noise = (rng.choice([-1.0, 1.0], 2) * bound if worst_case
             else rng.uniform(-bound, bound, 2))
    return Strips(h, h @ truth + noise, np.full(2, bound))


@pytest.mark.parametrize("state_model", ["position", "constant-velocity"])
@pytest.mark.parametrize("gain", ["frobenius", "volume", "enclose"])
@pytest.mark.parametrize("worst_case", [False, True])
def test_local_observer_contains_truth_every_step(state_model, gain, worst_case):
    config = Estimator(state_model=state_model, gain_method=gain, max_pedestrian_speed_mps=2.0,
                       position_jitter_m=0.3, max_velocity_change_mps=4.0)
    model = motion_model(config, DT)
    settings = EstimatorSettings(gain, "girard", 8)
    # a cvxpy LP per strip (``enclose`` is the ``volume`` gain outside 2-D)
    slow_lp = state_model == "constant-velocity" and gain in ("volume", "enclose")
    for seed in range(2 if slow_lp else 4):
        rng = np.random.default_rng(seed)
        truth = trajectory(rng, 90 if slow_lp else 120, speed=2.0, jitter=0.3)
        observer = NodeObserver("node", model, settings)
        for k, p in enumerate(truth):
            seen = k < 30 or (k % 7 != 0 and k < 80)  # long blind spells after 80 steps
            detections = {"ped": [sensor_strips(rng, p, 0.5, worst_case)
                                  for _ in range(rng.integers(1, 3))]} if seen else {}
            tracks = observer.step(k, detections)
            position = model.position(tracks["ped"].estimate)
            assert position.contains(p, tol=1e-7), (seed, k)


def test_set_grows_while_unseen_and_shrinks_on_detection():
    model = motion_model(Estimator(position_jitter_m=0.0), DT)
    observer = NodeObserver("n", model, EstimatorSettings("volume", "girard", 8))
    rng = np.random.default_rng(0)
    observer.step(0, {"ped": [sensor_strips(rng, np.zeros(2), 0.5, False)]})
    areas = [model.position(observer.step(k, {})["ped"].estimate).volume() for k in range(1, 6)]
    assert all(b > a for a, b in itertools.pairwise(areas))
    seen = observer.step(6, {"ped": [sensor_strips(rng, np.zeros(2), 0.5, False)]})
    assert model.position(seen["ped"].estimate).volume() < areas[-1]


def test_fused_estimate_contains_truth_and_is_never_larger_than_inputs():
    config = Estimator(position_jitter_m=0.3)
    model = motion_model(config, DT)
    settings = EstimatorSettings("volume", "girard", 8)
    for method in ("frobenius", "volume", "strips", "enclose"):
        rng = np.random.default_rng(7)
        truth = trajectory(rng, 60, speed=2.5, jitter=0.3)
        nodes = [NodeObserver(n, model, settings) for n in ("bus", "car", "rsu1")]
        for k, p in enumerate(truth):
            tracks = {o.node: o.step(k, {"ped": [sensor_strips(rng, p, 0.8, False)]})
                      for o in nodes}
            received = {"ped": {n: tracks[n]["ped"].estimate for n in ("car", "rsu1")}}
            fused = fuse_at_bus(tracks["bus"], received, method, settings, model)["ped"]
            assert model.position(fused).contains(p, tol=1e-7), (method, k)
            smallest = min(model.position(t["ped"].estimate).volume() for t in tracks.values())
            assert model.position(fused).volume() <= smallest * (1 + 1e-9)


def test_initial_set_is_the_parallelogram_of_two_strips():
    model = motion_model(Estimator(position_jitter_m=0.0), DT)
    strips = Strips(np.eye(2), np.array([3.0, -1.0]), np.array([0.5, 0.25]))
    start = model.initial_set(strips, "frobenius")
    np.testing.assert_allclose(start.center, [3.0, -1.0])
    assert start.volume() == pytest.approx(1.0 * 0.5)


@pytest.mark.parametrize("state_model", ["position", "constant-velocity"])
def test_position_sets_are_kept_per_estimate_and_equal_the_projection(state_model):
    model = motion_model(Estimator(state_model=state_model, position_jitter_m=0.3), DT)
    rng = np.random.default_rng(5)
    estimates = [Zonotope(rng.normal(size=model.dim), rng.normal(size=(model.dim, 3)))
                 for _ in range(POSITION_MEMO + 5)]
    first = model.position(estimates[0])
    assert model.position(estimates[0]) is first  # kept: computed once
    for estimate in estimates:  # the first is evicted, then computed again
        position = model.position(estimate)
        expected = model.position_matrix @ estimate + Zonotope(np.zeros(2), 0.3 * np.eye(2))
        assert np.array_equal(position.center, expected.center)
        assert np.array_equal(position.generators, expected.generators)
    again = model.position(estimates[0])
    assert again is not first and np.array_equal(again.generators, first.generators)

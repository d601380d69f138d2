"""Measurements y = H p + v (eq. senmodel) as strips (eq. strip)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from sensors_scene import SETTINGS, bus, car, paper_specs, snapshot, truck

from sse_cosim.sensors import draw_noise, measure, measurement_matrix, observe
from sse_cosim.world.snapshot import Pose

coord = st.floats(-300.0, 300.0)
poses = st.builds(Pose, coord, coord, st.floats(-math.pi, math.pi))
points = st.lists(st.tuples(coord, coord), min_size=1, max_size=6)
bounds = st.tuples(st.floats(0.01, 5.0), st.floats(0.01, 5.0))
kinds = st.sampled_from(["uniform", "worst-case"])
seeds = st.integers(0, 2**32 - 1)


@SETTINGS
@given(poses)
def test_measurement_matrix_rows_are_the_sensor_axes(pose):
    h = measurement_matrix(pose)
    assert h.shape == (2, 2)
    assert np.allclose(h[0], pose.forward) and np.allclose(h[1], pose.left)
    assert np.allclose(h @ h.T, np.eye(2)) and np.linalg.det(h) == pytest.approx(1.0)


@SETTINGS
@given(poses, points, bounds, kinds, seeds)
def test_strips_contain_the_truth(pose, pts, r, kind, seed):
    truth = np.array(pts)
    strips = measure(pose, truth, np.array(r), kind, np.random.default_rng(seed))
    assert len(strips) == len(pts)
    for p, s in zip(truth, strips, strict=True):
        assert s.normals.shape == (2, 2) and s.values.shape == (2,)
        assert np.array_equal(s.radii, np.array(r))
        assert np.allclose(s.normals, measurement_matrix(pose))
        assert s.contains(p, tol=1e-9)
        residual = np.abs(s.normals @ p - s.values)
        assert np.all(residual <= np.array(r) + 1e-9)


@SETTINGS
@given(poses, points, bounds, seeds)
def test_worst_case_noise_lies_on_the_bound(pose, pts, r, seed):
    truth = np.array(pts)
    for p, s in zip(
        truth,
        measure(pose, truth, np.array(r), "worst-case", np.random.default_rng(seed)),
        strict=True,
    ):
        assert np.abs(s.normals @ p - s.values) == pytest.approx(np.array(r), abs=1e-9)


def test_noise_draws():
    r = np.array([0.5, 2.0])
    uniform = draw_noise(r, "uniform", np.random.default_rng(3), 4000)
    assert uniform.shape == (4000, 2)
    assert np.all(np.abs(uniform) <= r)
    assert np.allclose(np.abs(uniform).max(axis=0), r, rtol=0.01)  # fills the box
    assert np.allclose(uniform.mean(axis=0), 0.0, atol=0.05)
    worst = draw_noise(r, "worst-case", np.random.default_rng(3), 4000)
    assert np.array_equal(np.abs(worst), np.broadcast_to(r, worst.shape))
    assert 0.45 < np.mean(worst[:, 0] > 0) < 0.55  # random signs
    with pytest.raises(ValueError, match="unknown noise kind"):
        draw_noise(r, "gaussian", np.random.default_rng(3), 1)
    assert measure(Pose(0, 0, 0), np.zeros((0, 2)), r, "uniform", np.random.default_rng(0)) == []


@pytest.mark.parametrize("kind", ["uniform", "worst-case"])
def test_seeded_rng_gives_identical_measurements(kind):
    persons = {"p": (190.0, -7.0), "q": (205.0, -7.5), "r": (200.0, 5.0)}
    snap = snapshot([bus(150.0), truck(), car()], persons, time=1.5)
    specs = paper_specs(kind)

    def values(seed: int) -> list[tuple[str, str, list[float]]]:
        obs = observe(snap, specs, np.random.default_rng(seed))
        return [
            (name, pid, d.strips.values.tolist())
            for name, o in obs.items()
            for pid, d in o.detections.items()
        ]

    first = values(7)
    assert len(first) >= 4
    assert first == values(7)
    assert first != values(8)
    # The sensor's frame: the car looks west, so its forward measurement is -x (+ noise).
    obs = observe(snap, specs, np.random.default_rng(7))
    car_p = obs["car_front"].detections["p"].strips
    assert car_p.values[0] == pytest.approx(-190.0, abs=1.0 + 1e-9)
    assert car_p.values[1] == pytest.approx(7.0, abs=1.0 + 1e-9)

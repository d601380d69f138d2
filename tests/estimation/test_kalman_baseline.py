"""The Kalman-filter baseline: Gaussian bookkeeping, regions, and the scenario option."""

import numpy as np
import pytest
import shapely

from sse_cosim.estimation.kalman import KalmanTracker, initial, update
from sse_cosim.estimation.motion import motion_model
from sse_cosim.regions import kind
from sse_cosim.scenario.model import Estimator
from sse_cosim.sets import Strips

K = kind("polygon")


def test_first_two_strips_give_their_exact_gaussian():
    strips = Strips(np.eye(2), [1.0, 2.0], [0.3, 0.6])
    state = initial(strips, 0)
    np.testing.assert_allclose(state.mean, [1.0, 2.0])
    np.testing.assert_allclose(state.cov, np.diag([0.01, 0.04]))
    tighter = update(state, Strips([1.0, 0.0], 1.0, 0.3))
    assert tighter.cov[0, 0] == pytest.approx(0.005)


def test_ellipse_polygon_circumscribes_the_three_sigma_ellipse():
    state = initial(Strips(np.eye(2), [0.0, 0.0], [0.9, 0.3]), 0)
    polygon = shapely.Polygon(state.ellipse())
    for angle in np.linspace(0, 2 * np.pi, 50):
        point = np.array([0.9 * np.cos(angle), 0.3 * np.sin(angle)])  # on the 3-sigma ellipse
        assert polygon.covers(shapely.Point(point))
        assert state.contains(point * 0.999) and not state.contains(point * 1.01)


def test_tracker_predicts_and_updates_and_the_option_exists():
    model = motion_model(Estimator(position_jitter_m=0.3), 0.1)
    tracker = KalmanTracker(model)
    strips = [Strips(np.eye(2), [5.0, 1.0], [0.5, 0.5])]
    tracker.step(0, {"p": strips})
    first = tracker.tracks["p"].cov.copy()
    tracker.step(3, {})
    assert np.all(np.diag(tracker.tracks["p"].cov) > np.diag(first))
    assert tracker.regions(K)["p"].shape.covers(shapely.Point(5.0, 1.0))
    assert Estimator().filter == "zonotope" and Estimator(filter="kalman").filter == "kalman"
    with pytest.raises(ValueError):
        Estimator(filter="particle")

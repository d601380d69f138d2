"""A clear region far from a pedestrian's region is skipped without changing the result."""

import numpy as np
import shapely

from sse_cosim.estimation.motion import motion_model
from sse_cosim.estimation.occupancy import ClearRegion, OccupancyTracker, _apart
from sse_cosim.regions import PolygonRegion as R
from sse_cosim.regions import kind
from sse_cosim.scenario.model import Estimator
from sse_cosim.sets import Zonotope

K = kind("polygon")


def test_far_clear_regions_change_nothing():
    model = motion_model(Estimator(position_jitter_m=0.3), 0.1)
    fused = {"p": Zonotope([0.0, 0.0], np.eye(2))}
    far = ClearRegion(R(shapely.box(50, 50, 60, 60)), 2)
    near = ClearRegion(R(shapely.box(0.5, -5, 5, 5)), 0)
    plain = OccupancyTracker(model, K).update(0, fused, {"p": [near]})["p"]
    skipped = OccupancyTracker(model, K).update(0, fused, {"p": [near, far]})["p"]
    assert plain.shape.symmetric_difference(skipped.shape).area < 1e-9
    assert _apart(R(shapely.box(0, 0, 1, 1)), R(shapely.box(3, 0, 4, 1)), 1.9)
    assert not _apart(R(shapely.box(0, 0, 1, 1)), R(shapely.box(3, 0, 4, 1)), 2.1)

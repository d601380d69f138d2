"""A clear region far from a pedestrian's region is skipped without changing the result."""

import numpy as np
import shapely

from sse_cosim.estimation.motion import motion_model
from sse_cosim.estimation.occupancy import ClearRegion, OccupancyTracker
from sse_cosim.regions import PolygonRegion as R
from sse_cosim.regions import apart, kind
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
    assert apart(R(shapely.box(0, 0, 1, 1)), R(shapely.box(3, 0, 4, 1)), 1.9)
    assert not apart(R(shapely.box(0, 0, 1, 1)), R(shapely.box(3, 0, 4, 1)), 2.1)


def test_regions_apart_share_no_point():
    """Bounding boxes apart: the intersection is empty and the difference the first region,
    as the held arrivals' split takes them without an overlay (control/picture.py)."""
    first, second = R(shapely.box(0, 0, 1, 1)), R(shapely.box(1.5, 0, 2, 1))
    assert apart(first, second) and apart(first, K.empty())
    assert first.intersection(second).is_empty
    assert first.difference(second).shape.equals(first.shape)
    assert not apart(first, R(shapely.box(1.0, 0.5, 2, 2)))  # touching boxes: not apart

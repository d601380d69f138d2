"""A clear region far from a pedestrian's region is skipped without changing the result."""

import numpy as np
import shapely

from sse_cosim.estimation.motion import motion_model
from sse_cosim.estimation.occupancy import ClearRegion, OccupancyTracker, _apart
from sse_cosim.scenario.model import Estimator
from sse_cosim.sets import Zonotope


def test_far_clear_regions_change_nothing():
    model = motion_model(Estimator(position_jitter_m=0.3), 0.1)
    fused = {"p": Zonotope([0.0, 0.0], np.eye(2))}
    far = ClearRegion(shapely.box(50, 50, 60, 60), 2)
    near = ClearRegion(shapely.box(0.5, -5, 5, 5), 0)
    plain = OccupancyTracker(model).update(0, fused, {"p": [near]})["p"]
    skipped = OccupancyTracker(model).update(0, fused, {"p": [near, far]})["p"]
    assert plain.symmetric_difference(skipped).area < 1e-9
    assert _apart(shapely.box(0, 0, 1, 1), shapely.box(3, 0, 4, 1), 1.9)
    assert not _apart(shapely.box(0, 0, 1, 1), shapely.box(3, 0, 4, 1), 2.1)

"""A static sensor's kept regions equal freshly computed ones."""

from __future__ import annotations

import math

import numpy as np

from sse_cosim.sensors import Boxes, SensorSpec, visibility_regions
from sse_cosim.world.snapshot import Footprint, Pose


def test_static_sensor_regions_are_reused_only_for_identical_occluders():
    spec = SensorSpec("cam", "rsu", static_pose=Pose(10.0, 3.0, math.radians(-120)))
    pose = spec.static_sensor_pose
    sector = spec.sector(pose)
    assert spec.sector(pose) is sector  # kept
    truck = Footprint(Pose(5.0, -5.0, 0.0), 10.0, 2.5)
    for bus_x in (-30.0, -30.0, -10.0, 0.0, -30.0):
        boxes = Boxes.from_footprints([truck, Footprint(Pose(bus_x, -1.6, 0.0), 12.0, 2.55)])
        cached = visibility_regions(pose, spec.fov_rad, spec.range_m, boxes, sector=sector,
                                    kept=spec.views)
        fresh = visibility_regions(pose, spec.fov_rad, spec.range_m, boxes)
        for a, b in zip(cached, fresh, strict=True):
            assert a.symmetric_difference(b).area < 1e-9
    again = visibility_regions(pose, spec.fov_rad, spec.range_m, boxes, sector=sector,
                               kept=spec.views)
    assert again[0] is cached[0]  # a hit returns the stored geometry
    assert np.isclose(again[0].area + again[1].area, sector.area)
    other = SensorSpec("cam2", "rsu", static_pose=spec.static_pose)
    assert visibility_regions(pose, spec.fov_rad, spec.range_m, boxes, sector=sector,
                              kept=other.views)[0] is not cached[0]  # each sensor keeps its own

"""Memoised regions of static sensors equal freshly computed ones."""

from __future__ import annotations

import math

import numpy as np

from sse_cosim.sensors import Boxes, cached_sector_polygon, visibility_regions
from sse_cosim.world.snapshot import Footprint, Pose


def test_static_sensor_regions_are_reused_only_for_identical_occluders():
    pose = Pose(10.0, 3.0, math.radians(-120))
    sector = cached_sector_polygon(pose, math.radians(90), 40.0)
    truck = Footprint(Pose(5.0, -5.0, 0.0), 10.0, 2.5)
    for bus_x in (-30.0, -30.0, -10.0, 0.0, -30.0):
        boxes = Boxes.from_footprints([truck, Footprint(Pose(bus_x, -1.6, 0.0), 12.0, 2.55)])
        cached = visibility_regions(pose, math.radians(90), 40.0, boxes, sector=sector)
        fresh = visibility_regions(pose, math.radians(90), 40.0, boxes)
        for a, b in zip(cached, fresh, strict=True):
            assert a.symmetric_difference(b).area < 1e-9
    again = visibility_regions(pose, math.radians(90), 40.0, boxes, sector=sector)
    assert again[0] is cached[0]  # a hit returns the stored geometry
    assert np.isclose(again[0].area + again[1].area, sector.area)

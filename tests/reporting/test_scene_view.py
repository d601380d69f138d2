"""The scene plots' window: around what the scene shows, on any network."""

from __future__ import annotations

import numpy as np
import shapely

from sse_cosim.reporting.plots import VIEW_MIN_M, _view_box
from sse_cosim.reporting.recorder import SceneFrame
from sse_cosim.sets import Zonotope


def frame(bus: shapely.Polygon, truths: dict[str, tuple[float, float]],
          unobserved: shapely.Geometry) -> SceneFrame:
    fused = {pid: Zonotope(np.array(p), np.eye(2)) for pid, p in truths.items()}
    return SceneFrame(0.0, {"bus": ("automated", bus)}, {}, [], [], fused, truths, unobserved)


def test_the_window_holds_the_vehicle_the_pedestrians_and_the_hidden_ground_far_from_origin():
    bus = shapely.box(-1012.0, 498.0, -1000.0, 500.5)
    hidden = shapely.box(-900.0, 520.0, -890.0, 530.0)
    x0, y0, x1, y1 = _view_box(frame(bus, {"p": (-950.0, 560.0)}, hidden))
    window = shapely.box(x0, y0, x1, y1)
    assert window.contains(bus) and window.contains(hidden)
    assert window.contains(shapely.Point(-950.0, 561.0))  # the fused set around the truth


def test_a_small_scene_gets_the_least_window_about_its_middle():
    x0, y0, x1, y1 = _view_box(frame(shapely.box(0.0, 0.0, 12.0, 2.5), {}, shapely.Polygon()))
    assert (x1 - x0, y1 - y0) == VIEW_MIN_M
    assert (x0 + x1) / 2 == 6.0 and (y0 + y1) / 2 == 1.25

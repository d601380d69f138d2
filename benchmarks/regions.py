"""The Region representations side by side on the occupancy stage's work, µs per operation,
and what the raster's coarseness costs in area.

Two workloads, each run with every representation (the polygon reference, and rasters of
cells of 0.05, 0.1 and 0.2 m):

- ``pedestrian``: a known pedestrian's region (a zonotope's polygon about 3 m x 3 m, made
  with ``convex_outer``), dilated by one step's reach (0.25 m), cut to a walkable strip of
  200 m x 8 m, less a sensor's view (a 40 m sector of 90°, ``inner``), then dilated by the
  jitter (0.1 m);
- ``unobserved``: one step of the unobserved area on a 60 m x 40 m window (two sidewalks and
  a crossing): the walkable ground less two views, the path region moved by the reach, cut to
  that ground dilated by the jitter and to the window, then the pedestrian's own region (the
  path region dilated by the jitter, on walkable ground, less the vehicle's view). The path
  region is the one after a few such steps with the vehicle driving on (no coarsening).

The walkable ground and the window are made once (they do not change between steps); every
other operation is timed as a step makes it. ``area_excess`` is each raster's final area over
the polygon's, less one (how much more ground it counts as possibly occupied).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np
import shapely

from benchmarks.common import time_calls
from sse_cosim.regions import PolygonKind, RasterKind, Region, RegionKind
from sse_cosim.sensors.geometry import sector_polygon
from sse_cosim.sets import Zonotope
from sse_cosim.world.snapshot import Pose

REACH_M = 0.25  # 2.5 m/s for 0.1 s: the default speed bound and step
JITTER_M = 0.1
CELLS_M = (0.05, 0.1, 0.2)
WARM_UP_STEPS = 5
SAMPLE_S = 0.02  # each timing sample runs about this long


def _kinds() -> dict[str, RegionKind]:
    return {"polygon": PolygonKind(), **{f"raster {c:g} m": RasterKind(c) for c in CELLS_M}}


def _view(x: float, y: float, heading: float, range_m: float, fov_deg: float
          ) -> shapely.Polygon:
    return sector_polygon(Pose(x, y, heading), math.radians(fov_deg), range_m)


def _pedestrian_steps(kind: RegionKind) -> dict[str, Callable[[], Region]]:
    """The pedestrian workload's operations, each on the previous one's result."""
    walkable = kind.outer(shapely.box(0.0, 0.0, 200.0, 8.0))
    person = Zonotope(np.array([100.3, 6.9]), np.array([[1.0, 0.35, 0.2, 0.0],
                                                          [0.1, 0.3, -0.35, 0.8]]))
    vertices = person.vertices()
    view = _view(61.0, 2.0, 0.05, 40.0, 90.0)
    made = {"region": kind.convex_outer(vertices), "view": kind.inner(view)}
    made["moved"] = made["region"].dilate(REACH_M)
    made["on foot"] = made["moved"].intersection(walkable)
    made["unseen"] = made["on foot"].difference(made["view"])
    return {
        "make region": lambda: kind.convex_outer(vertices),
        "make view": lambda: kind.inner(view),
        "dilate by reach": lambda: made["region"].dilate(REACH_M),
        "intersect walkable": lambda: made["moved"].intersection(walkable),
        "cut by view": lambda: made["on foot"].difference(made["view"]),
        "dilate by jitter": lambda: made["unseen"].dilate(JITTER_M),
        "whole step": lambda: kind.convex_outer(vertices).dilate(REACH_M).intersection(
            walkable).difference(kind.inner(view)).dilate(JITTER_M),
    }


class _Unobserved:
    """The unobserved-area workload on one representation."""

    def __init__(self, kind: RegionKind) -> None:
        self.kind = kind
        ground = shapely.union_all([shapely.box(0, 10, 60, 13), shapely.box(0, 27, 60, 30),
                                    shapely.box(28, 13, 32, 27)])
        self.window = kind.outer(shapely.box(0, 0, 60, 40))
        self.walkable = kind.outer(ground)
        self.path = self.walkable.dilate(JITTER_M)
        for step in range(WARM_UP_STEPS):
            self.path = self.advance(self.path, *self.views(step))[0]
        self.own, self.shared = self.views(WARM_UP_STEPS)

    def views(self, step: int) -> tuple[Region, Region]:
        """The vehicle's view at ``step`` (driving east at 1 m a step) and a roadside unit's."""
        own = self.kind.inner(_view(2.0 + step, 20.0, 0.0, 40.0, 90.0))
        return own, self.kind.inner(_view(58.0, 38.0, -2.4, 30.0, 120.0))

    def advance(self, path: Region, own: Region, shared: Region) -> tuple[Region, Region]:
        """One step: the path region and the pedestrian's region."""
        unseen = self.walkable.difference(self.kind.union_all([own, shared]))
        moved = path.dilate(REACH_M)
        path = moved.intersection(unseen.dilate(JITTER_M)).intersection(self.window)
        return path, path.dilate(JITTER_M).intersection(self.walkable).difference(own)

    def steps(self) -> dict[str, Callable[[], object]]:
        kind, own, shared = self.kind, self.own, self.shared
        seen = kind.union_all([own, shared])
        unseen = self.walkable.difference(seen)
        moved = self.path.dilate(REACH_M)
        near = unseen.dilate(JITTER_M)
        cut = moved.intersection(near).intersection(self.window)
        grown = cut.dilate(JITTER_M)
        return {
            "make views": lambda: self.views(WARM_UP_STEPS),
            "union of views": lambda: kind.union_all([own, shared]),
            "walkable less views": lambda: self.walkable.difference(seen),
            "dilate path by reach": lambda: self.path.dilate(REACH_M),
            "dilate unseen by jitter": lambda: unseen.dilate(JITTER_M),
            "intersect, clip to window": lambda: moved.intersection(near).intersection(
                self.window),
            "dilate by jitter": lambda: cut.dilate(JITTER_M),
            "on walkable less own view": lambda: grown.intersection(self.walkable).difference(
                own),
            "whole step": lambda: self.advance(self.path, *self.views(WARM_UP_STEPS)),
        }

    def result(self) -> Region:
        return self.advance(self.path, self.own, self.shared)[1]


def _us(call: Callable[[], object], repeats: int) -> float:
    """Median µs per call, each sample about :data:`SAMPLE_S` long (after a first call, which
    compiles or loads the kernels)."""
    start = time.perf_counter()
    call()
    once = max(time.perf_counter() - start, 1e-7)
    return 1e6 * time_calls(call, max(1, int(SAMPLE_S / once)), repeats)


def run(repeats: int = 5) -> dict:
    kinds = _kinds()
    us: dict[str, dict[str, dict[str, float]]] = {"pedestrian": {}, "unobserved": {}}
    areas: dict[str, dict[str, float]] = {"pedestrian": {}, "unobserved": {}}
    vertices = {}
    for label, kind in kinds.items():
        pedestrian = _pedestrian_steps(kind)
        unobserved = _Unobserved(kind)
        us["pedestrian"][label] = {op: _us(call, repeats) for op, call in pedestrian.items()}
        us["unobserved"][label] = {op: _us(call, repeats)
                                   for op, call in unobserved.steps().items()}
        areas["pedestrian"][label] = pedestrian["whole step"]().area
        areas["unobserved"][label] = unobserved.result().area
        if label == "polygon":
            vertices = {"pedestrian": int(shapely.get_num_coordinates(
                pedestrian["whole step"]().geometry())),
                "unobserved path region": int(shapely.get_num_coordinates(
                    unobserved.path.geometry()))}
    excess = {work: {label: a / by_kind["polygon"] - 1.0 for label, a in by_kind.items()
                     if label != "polygon"} for work, by_kind in areas.items()}
    workloads = {"pedestrian": "3 m region, dilated 0.25 m, cut to a 200 m x 8 m strip, less "
                               "a 40 m sector, dilated 0.1 m",
                 "unobserved": f"one step on a 60 m x 40 m window, after {WARM_UP_STEPS} steps"}
    return {"workloads": workloads, "us_per_operation": us,
            "area_m2": areas, "area_excess": excess, "polygon_vertices": vertices}


if __name__ == "__main__":
    import json

    print(json.dumps(run(), indent=1))

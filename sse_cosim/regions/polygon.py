"""Regions as exact shapely polygons: the reference representation.

Shapes are kept as they are (``outer`` and ``inner`` both keep the shape). A disc is drawn
with :data:`QUAD_SEGMENTS` segments per quarter circle; GEOS draws those arcs inscribed in the
true circle, so :meth:`PolygonRegion.dilate` and :meth:`PolygonRegion.erode` raise the radius
by :data:`ARC_SAFETY` until every arc's segments lie ``distance`` away: the dilation then
contains the exact one and the erosion lies inside the exact one.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np
import shapely

QUAD_SEGMENTS = 2  # polygon arcs: 2 segments per quarter circle
ARC_SAFETY = 1.0 / math.cos(math.pi / (4 * QUAD_SEGMENTS))  # makes those arcs circumscribe the disc
NO_BOUNDS = (0.0, 0.0, -1.0, -1.0)


@dataclass(frozen=True, eq=False)
class PolygonRegion:
    """A region as a shapely geometry (``shape``). Its erosions are kept on it: a step
    tests many sets against the same view at the same slack."""

    shape: shapely.Geometry
    _eroded: dict[float, PolygonRegion] = field(default_factory=dict, repr=False)

    @property
    def is_empty(self) -> bool:
        return bool(self.shape.is_empty)

    @property
    def area(self) -> float:
        return float(self.shape.area)

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        return NO_BOUNDS if self.shape.is_empty else tuple(self.shape.bounds)

    def union(self, other: PolygonRegion) -> PolygonRegion:
        return PolygonRegion(shapely.union(self.shape, other.shape))

    def intersection(self, other: PolygonRegion) -> PolygonRegion:
        return PolygonRegion(shapely.intersection(self.shape, other.shape))

    def difference(self, other: PolygonRegion) -> PolygonRegion:
        return PolygonRegion(shapely.difference(self.shape, other.shape))

    def dilate(self, distance: float) -> PolygonRegion:
        if distance <= 0 or self.shape.is_empty:
            return self
        return PolygonRegion(self.shape.buffer(ARC_SAFETY * distance, quad_segs=QUAD_SEGMENTS))

    def erode(self, distance: float) -> PolygonRegion:
        if distance <= 0 or self.shape.is_empty:
            return self
        if distance not in self._eroded:
            self._eroded[distance] = PolygonRegion(
                self.shape.buffer(-ARC_SAFETY * distance, quad_segs=QUAD_SEGMENTS))
        return self._eroded[distance]

    def covers(self, other: PolygonRegion) -> bool:
        return bool(self.prepared.covers(other.shape))

    def intersects(self, other: PolygonRegion) -> bool:
        return bool(self.prepared.intersects(other.shape))

    def contains_points(self, points: np.ndarray) -> np.ndarray:
        xy = np.asarray(points, dtype=float).reshape(-1, 2)
        return shapely.intersects_xy(self.prepared, xy[:, 0], xy[:, 1])

    def distance(self, other: PolygonRegion) -> float:
        if self.shape.is_empty or other.shape.is_empty:
            return math.inf
        return float(shapely.distance(self.shape, other.shape))

    def geometry(self) -> shapely.Geometry:
        return self.shape

    @property
    def prepared(self) -> shapely.Geometry:
        """The shape, prepared for repeated predicates (shapely prepares it in place)."""
        if not shapely.is_prepared(self.shape):
            shapely.prepare(self.shape)
        return self.shape


@dataclass(frozen=True)
class PolygonKind:
    """Makes :class:`PolygonRegion` values."""

    name: str = "polygon"

    def outer(self, shape: shapely.Geometry) -> PolygonRegion:
        return PolygonRegion(shape)

    def inner(self, shape: shapely.Geometry) -> PolygonRegion:
        return PolygonRegion(shape)

    def empty(self) -> PolygonRegion:
        return PolygonRegion(shapely.Polygon())

    def union_all(self, regions: Iterable[PolygonRegion]) -> PolygonRegion:
        shapes = [r.shape for r in regions if not r.shape.is_empty]
        return PolygonRegion(shapely.union_all(shapes)) if shapes else self.empty()

    def convex_outer(self, points: np.ndarray) -> PolygonRegion:
        xy = np.asarray(points, dtype=float).reshape(-1, 2)
        if len(xy) >= 3:
            return PolygonRegion(shapely.Polygon(xy))
        return PolygonRegion(shapely.MultiPoint(xy).convex_hull)

    def distances(self, sources: Sequence[PolygonRegion],
                  targets: Sequence[PolygonRegion]) -> np.ndarray:
        first = np.array([s.shape for s in sources], dtype=object)[:, None]
        second = np.array([t.shape for t in targets], dtype=object)[None, :]
        found = shapely.distance(first, second)  # NaN for an empty one
        return np.where(np.isnan(found), math.inf, found).reshape(len(sources), len(targets))

"""Regions as exact shapely polygons: the reference representation.

Shapes are kept as they are (``outer`` and ``inner`` both keep the shape). Dilation and
erosion offset every edge by the distance and draw no arcs: a corner is mitred, and a mitre
longer than the distance is cut square to the corner's bisector at the distance (GEOS's
mitre limit of :data:`MITRE_LIMIT`); points and line ends get square caps. Each such corner
holds the disc's arc it stands for (the cut is tangent to it, the mitre lies beyond it), so
the dilation contains the exact one, and an erosion (the dilation of the complement) lies
inside the exact one. A point of the dilation lies at most sqrt(1 + limit²) times the
distance from the shape (a cut corner's end on a needle). Arcs would not do: GEOS splits an
arc into a rounded number of chords, up to 1.5 times the nominal angle each, which dip inside
the disc.

GEOS's offset curve takes shortcuts that the corners above do not cover (its
``OffsetSegmentGenerator``): where the ends of two offset edges lie within a thousandth of
the distance of each other it keeps one of them and no corner, and it drops a curve vertex
within a millionth of the distance of the one before. Near a vertex where the boundary bends
by less than a milliradian, or along edges a few nanometres long, an offset so falls short of
the exact one: a dilation by up to 3.8e-7 of the distance on the random shapes of
tests/regions/test_polygon.py (4.7e-7 on 400 such shapes, an erosion 2.4e-7). Every offset is
therefore made :data:`OFFSET_MARGIN` of the distance farther.

GEOS's mitred offset is not always a valid geometry: a town run's cut dilated a valid
38-vertex polygon by 1.27 m into two nested shells, and the overlay that took it dropped the
part of a pedestrian's region that held the pedestrian (0.54 m off it; the safety campaign's
town runs, tests/regions/test_polygon.py). Every offset is therefore checked, and an invalid
one is replaced by the round offset by :data:`ROUND_FACTOR` times the distance, whose chords
lie on or beyond the disc's arcs (beyond the shape for a dilation, within it for an
erosion). An invalid round offset too is an error, never a region.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import shapely

from sse_cosim.sets import portable

MITRE_LIMIT = 1.0  # a corner's mitre is cut at the distance from the corner
OFFSET_MARGIN = 1e-5
"""Every offset goes this fraction of its distance farther than asked (out for a dilation, in
for an erosion): twenty times the largest shortfall of GEOS's measured (module docstring)."""
REACH_FACTOR = math.sqrt(1.0 + MITRE_LIMIT**2) * (1.0 + OFFSET_MARGIN)
"""How far a dilation reaches, per metre of its distance."""
LEAST_DILATION_M = 1e-9  # GEOS buffers by less than about 1e-16 m to nothing: dilate by this
SHORT_EDGE_M = 1e-12  # edges shorter than this are dropped before an offset GEOS cannot make
NO_BOUNDS = (0.0, 0.0, -1.0, -1.0)
COARSEN_ABOVE = 64  # vertices above which a region is coarsened
ROUND_QUAD_SEGS = 8  # chords per quarter circle of a round offset (GEOS's default)
ROUND_FACTOR = 1.0 / math.cos(0.75 * (0.5 * math.pi / ROUND_QUAD_SEGS))
"""A round offset's distance per metre of the one it stands for: GEOS's chords span up to 1.5
times the nominal angle (pi / 2 / ROUND_QUAD_SEGS), and a chord's middle lies cos(half its
angle) of the radius from the arc's centre; 1.011 for 8 chords, below :data:`REACH_FACTOR`."""


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

    @cached_property
    def bounds(self) -> tuple[float, float, float, float]:
        return NO_BOUNDS if self.shape.is_empty else tuple(self.shape.bounds)

    def union(self, other: PolygonRegion) -> PolygonRegion:
        return PolygonRegion(_overlay(shapely.union, self.shape, other.shape))

    def intersection(self, other: PolygonRegion) -> PolygonRegion:
        return PolygonRegion(_overlay(shapely.intersection, self.shape, other.shape))

    def difference(self, other: PolygonRegion) -> PolygonRegion:
        return PolygonRegion(_overlay(shapely.difference, self.shape, other.shape))

    def dilate(self, distance: float) -> PolygonRegion:
        if distance <= 0 or self.shape.is_empty:
            return self
        return PolygonRegion(_offset(self.shape, max(distance, LEAST_DILATION_M)))

    def erode(self, distance: float) -> PolygonRegion:
        if distance <= 0 or self.shape.is_empty:
            return self
        if distance not in self._eroded:
            self._eroded[distance] = PolygonRegion(_offset(self.shape, -distance))
        return self._eroded[distance]

    def coarsen(self, tolerance: float) -> PolygonRegion:
        """Repeated dilations and cuts leave regions with thousands of centimetre-long edges.
        Above :data:`COARSEN_ABOVE` vertices the shape is grown by ``tolerance`` (mitred
        corners: no arcs; GEOS's default mitre limit moves a sharp corner up to five times
        that) and simplified with the same tolerance, which moves no boundary point by more
        than that, so the result still covers the shape and lies within six times the
        tolerance of it; the cover is checked, and self returned if it fails."""
        if self.shape.is_empty or shapely.get_num_coordinates(self.shape) <= COARSEN_ABOVE:
            return self
        grown = self.shape.buffer(tolerance, quad_segs=1, join_style="mitre")
        simple = shapely.simplify(grown, tolerance, preserve_topology=True)
        return PolygonRegion(simple) if simple.covers(self.shape) else self

    def covers(self, other: PolygonRegion) -> bool:
        return other.shape.is_empty or bool(self.prepared.covers(other.shape))

    def intersects(self, other: PolygonRegion) -> bool:
        return bool(self.prepared.intersects(other.shape))

    def contains_points(self, points: np.ndarray) -> np.ndarray:
        xy = np.asarray(points, dtype=float).reshape(-1, 2)
        return shapely.intersects_xy(self.prepared, xy[:, 0], xy[:, 1])

    def distance(self, other: PolygonRegion) -> float:
        if self.shape.is_empty or other.shape.is_empty:
            return math.inf
        return float(shapely.distance(self.shape, other.shape))

    def support(self, directions: np.ndarray) -> np.ndarray:
        if self.shape.is_empty:
            return np.full(len(directions), -math.inf)
        return portable.matmul(shapely.get_coordinates(self.shape), directions.T).max(axis=0)

    def hull_points(self) -> np.ndarray:
        return shapely.get_coordinates(self.shape.convex_hull)

    def geometry(self) -> shapely.Geometry:
        return self.shape

    def parts(self) -> list[PolygonRegion]:
        return [PolygonRegion(part) for part in shapely.get_parts(self.shape)
                if not part.is_empty]

    def same(self, other: PolygonRegion) -> bool:
        return bool(shapely.equals_exact(self.shape, other.shape, tolerance=0.0))

    @property
    def prepared(self) -> shapely.Geometry:
        """The shape, prepared for repeated predicates (shapely prepares it in place)."""
        if not shapely.is_prepared(self.shape):
            shapely.prepare(self.shape)
        return self.shape


def _offset(shape: shapely.Geometry, distance: float) -> shapely.Geometry:
    """``shape`` offset by ``distance`` (m; outward if positive, inward if negative) and
    :data:`OFFSET_MARGIN` of it, mitred (module docstring), or, where GEOS's mitred offset is
    not a valid geometry, round by :data:`ROUND_FACTOR` times that; ValueError if that is not
    valid either.

    GEOS offsets an edge a few femtometres long along a normal of NaN (numpy warns: "invalid
    value encountered in buffer", at some distances "divide by zero" first; junction runs'
    views had such edges). Such a shape is
    offset without its edges shorter than :data:`SHORT_EDGE_M`: dropping a vertex within that
    of the one before moves no boundary point by more, so the offset by
    :data:`LEAST_DILATION_M` more (further out, or further in) still holds (or lies inside)
    the exact one."""
    distance *= 1.0 + OFFSET_MARGIN
    try:
        with np.errstate(invalid="raise", divide="raise"):
            mitred = _mitred(shape, distance)
    except FloatingPointError:
        shape = shapely.remove_repeated_points(shape, SHORT_EDGE_M)
        distance += math.copysign(LEAST_DILATION_M, distance)
        mitred = _mitred(shape, distance)
    if shapely.is_valid(mitred):
        return mitred
    rounded = shape.buffer(distance * ROUND_FACTOR, quad_segs=ROUND_QUAD_SEGS)
    if shapely.is_valid(rounded):
        return rounded
    raise ValueError(f"GEOS offsets a region by {distance:g} m into no valid geometry, mitred "
                     f"({shapely.is_valid_reason(mitred)}) or round "
                     f"({shapely.is_valid_reason(rounded)}): {shapely.to_wkt(shape)}")


def _mitred(shape: shapely.Geometry, distance: float) -> shapely.Geometry:
    return shapely.buffer(shape, distance, cap_style="square", join_style="mitre",
                          mitre_limit=MITRE_LIMIT)


def _overlay(operation: Callable[[shapely.Geometry, shapely.Geometry], shapely.Geometry],
             a: shapely.Geometry, b: shapely.Geometry) -> shapely.Geometry:
    """``operation`` (shapely's union, intersection or difference) of ``a`` and ``b``, exactly.

    A region can become a collection of polygons and the lines where two shapes touch (an
    intersection along a shared edge), and GEOS refuses to overlay such a collection ("Unable
    to determine overlay result geometry dimension"). Then the operation is done part by part,
    which gives the same set: A ∩ B is the union of the parts' intersections, A ∪ B the union
    of all parts, A minus B each part of A less every part of B.
    """
    try:
        return operation(a, b)
    except shapely.errors.GEOSException:
        if shapely.get_num_geometries(a) <= 1 and shapely.get_num_geometries(b) <= 1:
            raise
    first, second = shapely.get_parts(a), shapely.get_parts(b)
    if operation is shapely.union:
        return shapely.union_all(np.concatenate([first, second]))
    if operation is shapely.intersection:
        return shapely.union_all(shapely.intersection(first[:, None], second[None, :]))
    pieces = []
    for part in first:
        for cut in second:
            part = shapely.difference(part, cut)
        pieces.append(part)
    return shapely.union_all(pieces)


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

    def reach_of(self, distance: float) -> float:
        return REACH_FACTOR * max(distance, LEAST_DILATION_M)

    def union_all(self, regions: Iterable[PolygonRegion]) -> PolygonRegion:
        shapes = [r.shape for r in regions if not r.shape.is_empty]
        return PolygonRegion(shapely.union_all(shapes)) if shapes else self.empty()

    def union_apart(self, regions: Sequence[PolygonRegion]) -> PolygonRegion:
        """Their polygons as one multipolygon: apart, they make a valid one as they are."""
        parts = [p for r in regions for p in shapely.get_parts(r.shape)
                 if isinstance(p, shapely.Polygon) and not p.is_empty]
        return PolygonRegion(shapely.MultiPolygon(parts)) if parts else self.empty()

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

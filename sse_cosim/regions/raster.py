"""Regions as sets of cells of one global grid: a sound raster approximation.

The grid of a :class:`RasterKind` of cell size c is fixed: cell (i, j) (column i, row j,
integers) is the closed square [i c, (i + 1) c] x [j c, (j + 1) c], every grid line computed
as ``float(i) * c`` wherever it is used (rasterisation, predicates, :meth:`RasterRegion.geometry`),
so a region stands for exactly the union of its cells' squares, and two regions of one kind
combine cell by cell, without resampling. A :class:`RasterRegion` holds a boolean mask over a
window of the grid, cropped to its set cells, and the window's offset: a small region stays
small wherever it lies.

Soundness (:mod:`.base`), each approximation in the direction asked for:

- :meth:`RasterKind.outer` keeps every cell whose square meets the shape,
  :meth:`RasterKind.inner` only cells whose square lies inside it;
- :meth:`RasterRegion.dilate` adds every cell whose square lies within the distance of a set
  cell's square; :meth:`RasterRegion.erode` keeps a cell only when every cell within the
  distance of it is set (cells outside the mask count as unset), so every point it keeps is
  that far from any unset cell;
- union, intersection and difference are exact on the cells; covers, intersects,
  contains_points (closed: a point on a cell's edge is in the region when any cell it
  touches is set), distance (between set cells' squares) and area answer for the cells.
  The intersection keeps the cells both regions hold, so where only their cells' edges meet
  it drops those edges; no point is lost that way, since an outer raster holds *every* cell
  whose square holds a point of what it stands for (outer and dilation make it so, union,
  intersection and the difference by an inner raster keep it: no cell of an inner raster
  holds a point outside its shape).

Every decision that rounding could turn is taken :data:`SLACK_M` in the safe direction: a
cell is touched by a shape when its square grown by the slack meets the shape's boundary, and
dilation and erosion use the cells within distance + slack. So an ``inner`` raster drops the
cells along a shape's edge that lies on a grid line, and an ``outer`` one keeps the cells on
both sides of it. The slack is far above the rounding of coordinates below 1e6 m.

The cost of coarseness: an outer raster reaches up to c·√2 beyond its shape, an inner one
keeps no cell within c·√2 of the boundary, a dilation by d reaches up to d + c·√2 + slack.
Windows are limited to :data:`MAX_CELLS` cells: a raster covers a neighbourhood (a tracked
window), not a whole network at centimetres.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import shapely

from sse_cosim.regions import raster_kernels as kernels

SLACK_M = 1e-6
"""How far (m) every rounding-sensitive decision is pushed in the safe direction."""

MAX_CELLS = 1 << 26
"""The largest window (cells) a region may span."""

NO_BOUNDS = (0.0, 0.0, -1.0, -1.0)

POLYGON, LINES, POINT = 3, (1, 2), 0  # shapely type ids (LineString, LinearRing)
COLLECTIONS = (4, 5, 6, 7)  # Multi*, GeometryCollection: the type ids from 4 on

Window = tuple[int, int, int, int]
"""(col0, row0, cols, rows): a window of the grid."""


def _frozen(mask: np.ndarray) -> np.ndarray:
    mask.flags.writeable = False
    return mask


def _check_size(rows: int, cols: int, cell: float) -> None:
    if rows * cols > MAX_CELLS:
        raise ValueError(f"a raster region of {cols} x {rows} cells of {cell:g} m is over the "
                         f"limit of {MAX_CELLS} cells; use a larger cell_m or a smaller area")


@dataclass(frozen=True, eq=False)
class RasterRegion:
    """A region as the set cells of ``mask`` (rows, cols) of bool (read-only; rows along y,
    columns along x), whose cell [0, 0] is the grid's cell ``offset`` (column, row). Made by
    :class:`RasterKind` and the operations, which crop the mask to its set cells (an empty
    region has a (0, 0) mask). Its erosions are kept on it: a step tests many sets against the
    same view at the same slack."""

    cell: float
    mask: np.ndarray
    offset: tuple[int, int]
    _eroded: dict[float, RasterRegion] = field(default_factory=dict, repr=False)

    @property
    def is_empty(self) -> bool:
        return self.mask.size == 0

    @property
    def area(self) -> float:
        return float(np.count_nonzero(self.mask)) * self.cell * self.cell

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        if self.is_empty:
            return NO_BOUNDS
        col0, row0, cols, rows = self.window
        line = kernels.grid_line
        return (line(col0, self.cell), line(row0, self.cell), line(col0 + cols, self.cell),
                line(row0 + rows, self.cell))

    @property
    def window(self) -> Window:
        return self.offset[0], self.offset[1], self.mask.shape[1], self.mask.shape[0]

    def union(self, other: RasterRegion) -> RasterRegion:
        other = self._aligned(other)
        if self.is_empty or other.is_empty:
            return other if self.is_empty else self
        return self._combine(other, kernels.UNION, _hull(self.window, other.window))

    def intersection(self, other: RasterRegion) -> RasterRegion:
        other = self._aligned(other)
        window = _overlap(self.window, other.window)
        if window is None:
            return _empty(self.cell)
        return self._combine(other, kernels.INTERSECTION, window)

    def difference(self, other: RasterRegion) -> RasterRegion:
        other = self._aligned(other)
        if _overlap(self.window, other.window) is None:
            return self
        return self._combine(other, kernels.DIFFERENCE, self.window)

    def dilate(self, distance: float) -> RasterRegion:
        if distance <= 0 or self.is_empty:
            return self
        widths = reach_widths(distance, self.cell)
        reach, wide = len(widths) - 1, int(widths[0])
        _check_size(self.mask.shape[0] + 2 * reach, self.mask.shape[1] + 2 * wide, self.cell)
        grown = kernels.dilate(self.mask, widths)
        return _cropped(self.cell, grown, self.offset[0] - wide, self.offset[1] - reach)

    def erode(self, distance: float) -> RasterRegion:
        if distance <= 0 or self.is_empty:
            return self
        if distance not in self._eroded:
            kept = kernels.erode(self.mask, reach_widths(distance, self.cell))
            self._eroded[distance] = _cropped(self.cell, kept, *self.offset)
        return self._eroded[distance]

    def coarsen(self, tolerance: float) -> RasterRegion:
        """Self: a raster's cost does not grow with its history."""
        return self

    def covers(self, other: RasterRegion) -> bool:
        other = self._aligned(other)
        if other.is_empty:
            return True
        if _overlap(self.window, other.window) != other.window:
            return False  # (other's window is cropped: it has a cell outside self's)
        return kernels.covers(self.mask, *self.offset, other.mask, *other.offset)

    def intersects(self, other: RasterRegion) -> bool:
        other = self._aligned(other)
        if _overlap(_grown(self.window), other.window) is None:
            return False  # (empty, or more than a cell apart)
        return self._least_gap(other) == 0.0

    def contains_points(self, points: np.ndarray) -> np.ndarray:
        xy = np.ascontiguousarray(points, dtype=float).reshape(-1, 2)
        if self.is_empty:
            return np.zeros(len(xy), dtype=bool)
        return kernels.contains_points(self.mask, *self.offset, self.cell, xy)

    def distance(self, other: RasterRegion) -> float:
        other = self._aligned(other)
        if self.is_empty or other.is_empty:
            return math.inf
        return self.cell * self._least_gap(other)

    def support(self, directions: np.ndarray) -> np.ndarray:
        """max over the cells of n.x for each direction n (K, 2), (K,): reached at a corner of
        some row's first or last cell (:meth:`hull_points`); -inf if empty."""
        n = np.asarray(directions, dtype=float).reshape(-1, 2)
        if self.is_empty:
            return np.full(len(n), -math.inf)
        xy = self.hull_points()
        return (xy[:, :1] * n[:, 0] + xy[:, 1:] * n[:, 1]).max(axis=0)

    def hull_points(self) -> np.ndarray:
        """The outer corners of each row's first and last set cells, (4 rows, 2)."""
        if self.is_empty:
            return np.zeros((0, 2))
        rows = np.flatnonzero(self.mask.any(axis=1))
        first = np.argmax(self.mask[rows], axis=1)
        last = self.mask.shape[1] - np.argmax(self.mask[rows, ::-1], axis=1)
        col0, row0 = self.offset
        xs = _lines(col0 + np.concatenate([first, first, last, last]), self.cell)
        ys = _lines(row0 + np.concatenate([rows, rows + 1, rows, rows + 1]), self.cell)
        return np.column_stack([xs, ys])

    def geometry(self) -> shapely.Geometry:
        """The set cells as polygons (made once: the recorder's checks and the replay both ask
        for them)."""
        return self._polygons

    def parts(self) -> list[RasterRegion]:
        """The groups of set cells joined by an edge or a corner (a closed cell touches the
        ones at its corners)."""
        from scipy import ndimage

        labels, count = ndimage.label(self.mask, structure=np.ones((3, 3), dtype=bool))
        return [_cropped(self.cell, labels == k, *self.offset) for k in range(1, count + 1)]

    def same(self, other: RasterRegion) -> bool:
        return (self.cell == other.cell and self.offset == other.offset
                and np.array_equal(self.mask, other.mask))

    @cached_property
    def _polygons(self) -> shapely.Geometry:
        """The coverage union of the set cells' boxes (each row's runs, merged down the rows),
        whose rings are noded so that boxes share edges corner for corner
        (:func:`~sse_cosim.regions.raster_kernels.box_rings`)."""
        if self.is_empty:
            return shapely.Polygon()
        corners, ptr = kernels.box_rings(kernels.run_boxes(self.mask))
        col0, row0 = self.offset
        xy = np.column_stack([_lines(col0 + corners[:, 0], self.cell),
                              _lines(row0 + corners[:, 1], self.cell)])
        rings = shapely.linearrings(xy, indices=np.repeat(np.arange(len(ptr) - 1), np.diff(ptr)))
        parts = shapely.polygons(rings)
        return parts[0] if len(parts) == 1 else shapely.coverage_union_all(parts)

    def _aligned(self, other: RasterRegion) -> RasterRegion:
        if not isinstance(other, RasterRegion) or other.cell != self.cell:
            found = f"cells of {other.cell:g} m" if isinstance(other, RasterRegion) \
                else type(other).__name__
            raise ValueError(f"a raster region of cells of {self.cell:g} m combines only with "
                             f"one of the same RasterKind, not with {found}")
        return other

    def _combine(self, other: RasterRegion, operation: int, window: Window) -> RasterRegion:
        col0, row0, cols, rows = window
        mask = kernels.combine(self.mask, *self.offset, other.mask, *other.offset, operation,
                               col0, row0, rows, cols)
        return _cropped(self.cell, mask, col0, row0)

    def _least_gap(self, other: RasterRegion) -> float:
        """The least gap (cells) between set cells of self and other."""
        return kernels.least_gap(self.mask, *self.offset, other.mask, *other.offset)


@dataclass(frozen=True)
class RasterKind:
    """Makes :class:`RasterRegion` values on the grid of cells of ``cell_m`` (m) whose lines
    lie at its multiples."""

    cell_m: float = 0.1
    name: str = field(default="raster", init=False)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.cell_m) and self.cell_m > 0):
            raise ValueError(f"raster cell_m must be finite and > 0; got {self.cell_m}")

    def outer(self, shape: shapely.Geometry) -> RasterRegion:
        return self._rasterize(shape, inner=False)

    def inner(self, shape: shapely.Geometry) -> RasterRegion:
        return self._rasterize(shape, inner=True)

    def empty(self) -> RasterRegion:
        return _empty(self.cell_m)

    def reach_of(self, distance: float) -> float:
        """distance + a cell's diagonal + the slack: an added cell's square lies within
        distance + slack of a set one."""
        return 0.0 if distance <= 0 else distance + SLACK_M + math.sqrt(2.0) * self.cell_m

    def union_apart(self, regions: Sequence[RasterRegion]) -> RasterRegion:
        """:meth:`union_all`: cells combine without an overlay anyway."""
        return self.union_all(regions)

    def union_all(self, regions: Iterable[RasterRegion]) -> RasterRegion:
        empty = self.empty()
        parts = [empty._aligned(r) for r in regions]
        parts = [r for r in parts if not r.is_empty]
        if len(parts) <= 1:
            return parts[0] if parts else empty
        window = parts[0].window
        for region in parts[1:]:
            window = _hull(window, region.window)
        col0, row0, cols, rows = window
        _check_size(rows, cols, self.cell_m)
        mask = np.zeros((rows, cols), dtype=bool)
        for region in parts:
            kernels.paint(mask, col0, row0, region.mask, *region.offset)
        return RasterRegion(self.cell_m, _frozen(mask), (col0, row0))

    def convex_outer(self, points: np.ndarray) -> RasterRegion:
        xy = np.asarray(points, dtype=float).reshape(-1, 2)
        return self.outer(shapely.convex_hull(shapely.multipoints(xy))) if len(xy) \
            else self.empty()

    def distances(self, sources: Sequence[RasterRegion],
                  targets: Sequence[RasterRegion]) -> np.ndarray:
        found = np.empty((len(sources), len(targets)))
        for i, source in enumerate(sources):
            for j, target in enumerate(targets):
                found[i, j] = source.distance(target)
        return found

    def _rasterize(self, shape: shapely.Geometry, inner: bool) -> RasterRegion:
        if shape.is_empty:
            return self.empty()
        edges, part_ptr, strokes = shape_edges(shape)
        window = shape_window(shape, self.cell_m)
        col0, row0, cols, rows = window
        _check_size(rows, cols, self.cell_m)
        mask = kernels.rasterize(edges, part_ptr, strokes, col0, row0, rows, cols, self.cell_m,
                                 SLACK_M, inner)
        return _cropped(self.cell_m, mask, col0, row0)


def reach_widths(distance: float, cell: float) -> np.ndarray:
    """The cells within ``distance`` (+ :data:`SLACK_M`) of a cell, as widths (R + 1,) of int:
    at row offset |dr| <= R, the column offsets |dk| <= widths[|dr|], where whole gaps of
    max(|dr| - 1, 0) rows and max(|dk| - 1, 0) columns leave the squares within reach."""
    limit = distance + SLACK_M
    rows = np.arange(math.floor(limit / cell) + 2)
    gap_y = np.maximum(rows - 1, 0) * cell
    across = np.sqrt(np.maximum(limit * limit - gap_y * gap_y, 0.0))
    return (np.floor(across / cell) + 1).astype(np.int64)


def shape_edges(shape: shapely.Geometry) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(edges (m, 4), part_ptr (p + 1,), strokes (q, 4))`` of a shape for
    :func:`~sse_cosim.regions.raster_kernels.rasterize`: its polygons' ring edges (x0, y0, x1,
    y1), polygon by polygon, and its lines' segments and points (as segments of length 0)."""
    if shapely.get_type_id(shape) == POLYGON and shapely.get_num_interior_rings(shape) == 0:
        xy = shapely.get_coordinates(shape)  # one ring (closed): the common case, made quickly
        edges = np.hstack([xy[:-1], xy[1:]])
        return _finite(edges), np.array([0, len(edges)], dtype=np.int64), np.zeros((0, 4))
    parts = shapely.get_parts(shape)
    kinds = shapely.get_type_id(parts)
    while (kinds >= COLLECTIONS[0]).any():
        parts = shapely.get_parts(parts)
        kinds = shapely.get_type_id(parts)
    polygons = kinds == POLYGON
    rings, ring_polygon = shapely.get_rings(parts[polygons], return_index=True)
    edges, edge_ring = _segments(rings)
    part_ptr = np.searchsorted(ring_polygon[edge_ring], np.arange(np.count_nonzero(polygons) + 1))
    strokes = np.zeros((0, 4))
    if not polygons.all():
        lines, _ = _segments(parts[(kinds == LINES[0]) | (kinds == LINES[1])])
        points = shapely.get_coordinates(parts[kinds == POINT])
        strokes = np.vstack([lines, np.hstack([points, points])])
    return _finite(edges), part_ptr.astype(np.int64), _finite(strokes)


def _finite(segments: np.ndarray) -> np.ndarray:
    if not np.isfinite(segments).all():
        raise ValueError("a raster region needs finite coordinates; the shape has NaN or inf")
    return segments


def shape_window(shape: shapely.Geometry, cell: float) -> Window:
    """The window of every cell whose square grown by the slack may meet ``shape``, with a
    cell to spare on each side."""
    x0, y0, x1, y1 = shapely.bounds(shape)
    col0 = math.floor((x0 - SLACK_M) / cell) - 1
    row0 = math.floor((y0 - SLACK_M) / cell) - 1
    cols = math.floor((x1 + SLACK_M) / cell) + 2 - col0
    rows = math.floor((y1 + SLACK_M) / cell) + 2 - row0
    return col0, row0, cols, rows


def _segments(lines: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The segments (m, 4) between consecutive points of each line of ``lines`` (rings
    closed), and the line each belongs to (m,)."""
    xy, line_of = shapely.get_coordinates(lines, return_index=True)
    same = line_of[1:] == line_of[:-1]
    return np.hstack([xy[:-1][same], xy[1:][same]]).reshape(-1, 4), line_of[:-1][same]


def _lines(indices: np.ndarray, cell: float) -> np.ndarray:
    """Grid lines (m) of integer ``indices``, as :func:`raster_kernels.grid_line`."""
    return np.asarray(indices, dtype=np.int64).astype(float) * cell


def _empty(cell: float) -> RasterRegion:
    return RasterRegion(cell, _frozen(np.zeros((0, 0), dtype=bool)), (0, 0))


def _cropped(cell: float, mask: np.ndarray, col0: int, row0: int) -> RasterRegion:
    """The region of ``mask`` at (col0, row0), cropped to its set cells (a copy when smaller:
    no view keeps a larger window alive)."""
    r0, r1, k0, k1 = kernels.set_bounds(mask)
    if r0 == r1:
        return _empty(cell)
    if (r1 - r0, k1 - k0) != mask.shape:
        mask = mask[r0:r1, k0:k1].copy()
    return RasterRegion(cell, _frozen(mask), (col0 + k0, row0 + r0))


def _hull(a: Window, b: Window) -> Window:
    col0, row0 = min(a[0], b[0]), min(a[1], b[1])
    return (col0, row0, max(a[0] + a[2], b[0] + b[2]) - col0,
            max(a[1] + a[3], b[1] + b[3]) - row0)


def _overlap(a: Window, b: Window) -> Window | None:
    """The cells two windows share; None if none (or either is empty)."""
    col0, row0 = max(a[0], b[0]), max(a[1], b[1])
    cols = min(a[0] + a[2], b[0] + b[2]) - col0
    rows = min(a[1] + a[3], b[1] + b[3]) - row0
    return (col0, row0, cols, rows) if cols > 0 and rows > 0 else None


def _grown(window: Window) -> Window:
    """The window with one more cell on each side (empty stays empty)."""
    col0, row0, cols, rows = window
    return (col0 - 1, row0 - 1, cols + 2, rows + 2) if cols and rows else window


# NumPy references of the kernels (tests/regions/test_raster.py checks one against the other).


def _centres(first: int, count: int, cell: float) -> np.ndarray:
    return (np.arange(first, first + count).astype(float) + 0.5) * cell


def rasterize_reference(edges: np.ndarray, part_ptr: np.ndarray, strokes: np.ndarray,
                        window: Window, cell: float, slack: float, inner: bool) -> np.ndarray:
    """``raster_kernels.rasterize`` over every cell and segment at once: a cell is touched when
    a segment and the cell's square grown by ``slack`` are not separated along x, y or the
    segment's normal, and filled by the crossing-number test of its centre, polygon by
    polygon. Shape (rows, cols)."""
    col0, row0, cols, rows = window
    xc = _centres(col0, cols, cell)[None, :, None]
    yc = _centres(row0, rows, cell)[:, None, None]
    half = 0.5 * cell + slack
    x0, y0, x1, y1 = np.vstack([edges, strokes]).T
    nx, ny = y0 - y1, x1 - x0
    touched = ((np.maximum(x0, x1) >= xc - half) & (np.minimum(x0, x1) <= xc + half)
               & (np.maximum(y0, y1) >= yc - half) & (np.minimum(y0, y1) <= yc + half)
               & (np.abs(nx * (xc - x0) + ny * (yc - y0)) <= half * (np.abs(nx) + np.abs(ny)))
               ).any(axis=2)
    filled = np.zeros((rows, cols), dtype=bool)
    for first, stop in itertools.pairwise(part_ptr):
        x0, y0, x1, y1 = edges[first:stop].T
        crossed = (y0 > yc) != (y1 > yc)
        run = np.where(y1 == y0, 1.0, y1 - y0)
        filled |= (np.count_nonzero(crossed & (xc < x0 + (yc - y0) * (x1 - x0) / run),
                                    axis=2) % 2).astype(bool)
    return filled & ~touched if inner else filled | touched


def dilate_reference(mask: np.ndarray, widths: np.ndarray) -> np.ndarray:
    """``raster_kernels.dilate``: the mask shifted by every offset within reach, or-ed."""
    rows, cols = mask.shape
    reach, wide = len(widths) - 1, int(widths[0])
    out = np.zeros((rows + 2 * reach, cols + 2 * wide), dtype=bool)
    for dr in range(-reach, reach + 1):
        for dk in range(-widths[abs(dr)], widths[abs(dr)] + 1):
            out[reach + dr:reach + dr + rows, wide + dk:wide + dk + cols] |= mask
    return out


def erode_reference(mask: np.ndarray, widths: np.ndarray) -> np.ndarray:
    """``raster_kernels.erode``: the mask, padded with unset cells, shifted by every offset
    within reach, and-ed."""
    rows, cols = mask.shape
    reach, wide = len(widths) - 1, int(widths[0])
    padded = np.zeros((rows + 2 * reach, cols + 2 * wide), dtype=bool)
    padded[reach:reach + rows, wide:wide + cols] = mask
    out = np.ones((rows, cols), dtype=bool)
    for dr in range(-reach, reach + 1):
        for dk in range(-widths[abs(dr)], widths[abs(dr)] + 1):
            out &= padded[reach + dr:reach + dr + rows, wide + dk:wide + dk + cols]
    return out


def placed_reference(mask: np.ndarray, offset: tuple[int, int], window: Window) -> np.ndarray:
    """``mask`` at ``offset`` seen through ``window``: shape (rows, cols)."""
    col0, row0, cols, rows = window
    out = np.zeros((rows, cols), dtype=bool)
    r, k = np.nonzero(mask)
    r, k = r + offset[1] - row0, k + offset[0] - col0
    keep = (r >= 0) & (r < rows) & (k >= 0) & (k < cols)
    out[r[keep], k[keep]] = True
    return out


def combine_reference(a: np.ndarray, a_offset: tuple[int, int], b: np.ndarray,
                      b_offset: tuple[int, int], operation: int, window: Window) -> np.ndarray:
    """``raster_kernels.combine`` by NumPy's logical operators on both masks placed."""
    in_a, in_b = placed_reference(a, a_offset, window), placed_reference(b, b_offset, window)
    if operation == kernels.UNION:
        return in_a | in_b
    if operation == kernels.INTERSECTION:
        return in_a & in_b
    return in_a & ~in_b


def set_bounds_reference(mask: np.ndarray) -> tuple[int, int, int, int]:
    """``raster_kernels.set_bounds`` from the rows and columns that hold any set cell."""
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    if not rows.size:
        return 0, 0, 0, 0
    return int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1


def row_runs_reference(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``raster_kernels.row_runs`` from the steps of each row padded with unset cells."""
    steps = np.diff(np.pad(mask.astype(np.int8), ((0, 0), (1, 1))), axis=1)
    rows, starts = np.nonzero(steps == 1)
    stops = np.nonzero(steps == -1)[1]
    ptr = np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=mask.shape[0]))])
    return ptr, starts, stops


def box_rings_reference(boxes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``raster_kernels.box_rings``, box by box against every other box."""
    rings = []
    for k0, k1, j0, j1 in boxes.tolist():
        lower = sorted({c for a0, a1, _, b1 in boxes.tolist() if b1 == j0
                        for c in (a0, a1) if k0 < c < k1})
        upper = sorted({c for a0, a1, b0, _ in boxes.tolist() if b0 == j1
                        for c in (a0, a1) if k0 < c < k1}, reverse=True)
        rings.append([(k0, j0), *((c, j0) for c in lower), (k1, j0), (k1, j1),
                      *((c, j1) for c in upper), (k0, j1), (k0, j0)])
    ptr = np.concatenate([[0], np.cumsum([len(r) for r in rings])]).astype(np.int64)
    return np.array([c for r in rings for c in r], dtype=np.int64).reshape(-1, 2), ptr


def least_gap_reference(a: np.ndarray, a_offset: tuple[int, int], b: np.ndarray,
                        b_offset: tuple[int, int]) -> float:
    """``raster_kernels.least_gap`` over every pair of set cells."""
    ra, ka = np.nonzero(a)
    rb, kb = np.nonzero(b)
    if not (ra.size and rb.size):
        return math.inf
    gx = np.maximum(np.abs((ka + a_offset[0])[:, None] - (kb + b_offset[0])[None, :]) - 1, 0)
    gy = np.maximum(np.abs((ra + a_offset[1])[:, None] - (rb + b_offset[1])[None, :]) - 1, 0)
    return float(np.sqrt(float((gx * gx + gy * gy).min())))


def contains_points_reference(mask: np.ndarray, offset: tuple[int, int], cell: float,
                              points: np.ndarray) -> np.ndarray:
    """``raster_kernels.contains_points``: each point against every set cell's square."""
    r, k = np.nonzero(mask)
    x0, x1 = _lines(k + offset[0], cell), _lines(k + offset[0] + 1, cell)
    y0, y1 = _lines(r + offset[1], cell), _lines(r + offset[1] + 1, cell)
    x, y = points[:, :1], points[:, 1:]
    return ((x0 <= x) & (x <= x1) & (y0 <= y) & (y <= y1)).any(axis=1)

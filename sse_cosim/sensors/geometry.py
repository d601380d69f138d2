"""Pure planar geometry of a sensor: sectors, line of sight, shadows.

Conventions: points are network metres, angles radians CCW from east. Vehicle footprints are
oriented rectangles, handled in bulk as :class:`Boxes` (arrays, no shapely) by the cheap
vectorized tests (:func:`in_sector`, :func:`line_of_sight`); shapely is only used to build the
sector and shadow polygons when a caller asks for regions. The per-step work (sight masks, box
distances, shadow points, sector rings) runs compiled (:mod:`sse_cosim.sensors.kernels`), each
kernel checked within a stated rounding bound against its NumPy reference here (``*_reference``).

Boundary semantics (closed sets): a segment that merely touches a footprint is blocked, a
point on the sector's edge or arc is inside the sector. Polygons are inscribed approximations
of the arc (sagitta ``range * (1 - cos(pi / (4 * resolution)))``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import shapely
from shapely.geometry.base import BaseGeometry

from sse_cosim.memo import IdentityMemo
from sse_cosim.sensors import kernels
from sse_cosim.sets import portable
from sse_cosim.world.snapshot import Footprint, Pose

FULL_TURN = 2.0 * math.pi
_FULL_EPS = 1e-9
_FAR_POINTS = 5  # rays of a shadow's far cap; its spread is < pi, so steps are < pi / 4
FAR_STEPS = np.linspace(0.0, 1.0, _FAR_POINTS)  # (f,) the rays' fractions of the spread


@dataclass(frozen=True, eq=False)
class Boxes:
    """``m`` oriented rectangles as arrays.

    ``centers`` (m, 2); ``axes`` (m, 2, 2) with rows the unit forward and left axes;
    ``half`` (m, 2) the half length (along forward) and half width (along left).
    """

    centers: np.ndarray
    axes: np.ndarray
    half: np.ndarray

    @classmethod
    def from_footprints(cls, footprints: Sequence[Footprint]) -> Boxes:
        """Boxes of vehicle footprints (front-bumper reference), in the given order."""
        m = len(footprints)
        if m == 0:
            return cls.empty()
        rows = []
        for f in footprints:  # scalar maths: m is small, numpy call overhead dominates
            c, s = math.cos(f.front.heading), math.sin(f.front.heading)
            hl = 0.5 * f.length
            rows.append((f.front.x - hl * c, f.front.y - hl * s, c, s, -s, c, hl, 0.5 * f.width))
        data = np.array(rows, dtype=float)  # (m, 8)
        return cls(data[:, 0:2], data[:, 2:6].reshape(m, 2, 2), data[:, 6:8])

    @classmethod
    def empty(cls) -> Boxes:
        """No boxes."""
        return cls(np.zeros((0, 2)), np.zeros((0, 2, 2)), np.zeros((0, 2)))

    def __len__(self) -> int:
        return int(self.centers.shape[0])

    def subset(self, keep: np.ndarray) -> Boxes:
        """The boxes selected by a boolean mask or index array ``keep`` (m,)."""
        return Boxes(self.centers[keep], self.axes[keep], self.half[keep])

    def corners(self) -> np.ndarray:
        """Corners counter-clockwise from the rear right, shape (m, 4, 2)."""
        signs = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])  # (4, 2)
        local = signs[None, :, :] * self.half[:, None, :]  # (m, 4, 2)
        return self.centers[:, None, :] + portable.matmul(local, self.axes)

    def distances(self, point: np.ndarray) -> np.ndarray:
        """Euclidean distance from ``point`` (2,) to each (closed) box, shape (m,)."""
        return box_distances(np.asarray(point, dtype=float).reshape(1, 2), self)[0]


def sector_mask(
    origins: np.ndarray,
    headings: np.ndarray,
    fovs_rad: np.ndarray,
    ranges_m: np.ndarray,
    targets: np.ndarray,
) -> np.ndarray:
    """Whether each target lies in each of ``s`` closed sectors, shape (s, k) bool.

    ``origins`` (s, 2) apexes, ``headings``/``fovs_rad``/``ranges_m`` (s,) their boresights,
    opening angles (>= 2 pi: a disc) and ranges; ``targets`` (k, 2).
    """
    o = np.asarray(origins, dtype=float).reshape(-1, 2)
    t = np.asarray(targets, dtype=float).reshape(-1, 2)
    heading = np.asarray(headings, dtype=float).reshape(-1, 1)
    dx = t[None, :, 0] - o[:, 0:1]  # (s, k)
    dy = t[None, :, 1] - o[:, 1:2]
    dist2 = dx * dx + dy * dy
    reach = np.asarray(ranges_m, dtype=float).reshape(-1, 1)
    half = 0.5 * np.asarray(fovs_rad, dtype=float).reshape(-1, 1)
    along = dx * portable.cos(heading) + dy * portable.sin(heading)
    full = half >= 0.5 * FULL_TURN - _FULL_EPS
    return (dist2 <= reach * reach) & (full | (along >= np.sqrt(dist2) * portable.cos(half)))


def in_sector(pose: Pose, fov_rad: float, range_m: float, targets: np.ndarray) -> np.ndarray:
    """Whether each target (k, 2) lies in the closed circular sector, shape (k,) bool.

    The sector has its apex at the pose, is centred on its heading, opens ``fov_rad``
    (>= 2 pi: a disc) and reaches ``range_m``.
    """
    return sector_mask(
        pose.position[None, :],
        np.array([pose.heading]),
        np.array([fov_rad]),
        np.array([range_m]),
        targets,
    )[0]


def clear_mask(
    origins: np.ndarray,
    targets: np.ndarray,
    boxes: Boxes,
    active: np.ndarray | None = None,
) -> np.ndarray:
    """Whether each segment origin→target misses every active box, shape (s, k) bool.

    ``origins`` (s, 2), ``targets`` (k, 2); ``active`` (s, m) bool selects the boxes that
    count for each origin (default: all). Separating-axis test of every segment against
    every closed rectangle at once, in the rectangle's frame: its two axes and the segment's
    normal (|cross(seg, centre - origin)| > |seg_l| h_f + |seg_f| h_l separates).
    """
    o = np.asarray(origins, dtype=float).reshape(-1, 2)
    t = np.asarray(targets, dtype=float).reshape(-1, 2)
    if len(boxes) == 0 or t.shape[0] == 0 or o.shape[0] == 0:
        return np.ones((o.shape[0], t.shape[0]), dtype=bool)
    f, l_ = _local(np.vstack([o, t]), boxes)
    n = o.shape[0]
    return _clear(f[:n], l_[:n], f[n:], l_[n:], boxes.half, active)


def _clear(
    of: np.ndarray,
    ol: np.ndarray,
    tf: np.ndarray,
    tl: np.ndarray,
    half: np.ndarray,
    active: np.ndarray | None,
) -> np.ndarray:
    """:func:`clear_mask` from box-frame coordinates: origins ``of``/``ol`` (s, m), targets
    ``tf``/``tl`` (k, m), ``half`` (m, 2), ``active`` (s, m) or None; shape (s, k)."""
    of, ol = of[:, None, :], ol[:, None, :]  # (s, 1, m)
    tf, tl = tf[None, :, :], tl[None, :, :]  # (1, k, m)
    hf, hl = half[:, 0], half[:, 1]  # (m,)
    sep = (np.minimum(of, tf) > hf) | (np.maximum(of, tf) < -hf)  # (s, k, m)
    sep |= (np.minimum(ol, tl) > hl) | (np.maximum(ol, tl) < -hl)
    sep |= np.abs(of * tl - tf * ol) > np.abs(tl - ol) * hf + np.abs(tf - of) * hl
    if active is not None:
        sep |= ~np.asarray(active, dtype=bool)[:, None, :]
    return np.all(sep, axis=2)


def sight_masks(
    origins: np.ndarray,
    headings: np.ndarray,
    fovs_rad: np.ndarray,
    ranges_m: np.ndarray,
    carriers: np.ndarray,
    targets: np.ndarray,
    boxes: Boxes,
) -> tuple[np.ndarray, np.ndarray]:
    """``(seen (s, k), occluders (s, m))`` for ``s`` sensors, ``k`` targets, ``m`` boxes.

    Sensor j (``origins`` (s, 2), ``headings``/``fovs_rad``/``ranges_m`` (s,)) sees target i
    iff it is in the sector and its segment misses every occluder of j: the boxes within
    ``ranges_m[j]`` of the sensor except its carrier ``carriers[j]`` (box index, -1: none).
    Compiled (:func:`sse_cosim.sensors.kernels.sight_masks`); what :func:`in_sector` and
    :func:`line_of_sight` compute per sensor, and :func:`sight_masks_reference` in NumPy.
    """
    return kernels.sight_masks(
        _floats(origins, (-1, 2)), _floats(headings, (-1,)), _floats(fovs_rad, (-1,)),
        _floats(ranges_m, (-1,)), np.ascontiguousarray(carriers, dtype=np.int64).reshape(-1),
        _floats(targets, (-1, 2)), boxes.centers, boxes.axes, boxes.half,
        0.5 * FULL_TURN - _FULL_EPS)


def _floats(values: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """``values`` as a contiguous float64 array of ``shape`` (for the compiled kernels)."""
    return np.ascontiguousarray(values, dtype=float).reshape(shape)


def sight_masks_reference(
    origins: np.ndarray,
    headings: np.ndarray,
    fovs_rad: np.ndarray,
    ranges_m: np.ndarray,
    carriers: np.ndarray,
    targets: np.ndarray,
    boxes: Boxes,
) -> tuple[np.ndarray, np.ndarray]:
    """The NumPy reference of :func:`sight_masks` (the same arguments and result): one
    vectorized pass."""
    o = np.asarray(origins, dtype=float).reshape(-1, 2)
    t = np.asarray(targets, dtype=float).reshape(-1, 2)
    s, m = o.shape[0], len(boxes)
    seen = sector_mask(o, headings, fovs_rad, ranges_m, t)
    if m == 0:
        return seen, np.zeros((s, 0), dtype=bool)
    f, l_ = _local(np.vstack([o, t]), boxes)  # (s + k, m)
    ef = np.maximum(np.abs(f[:s]) - boxes.half[:, 0], 0.0)
    el = np.maximum(np.abs(l_[:s]) - boxes.half[:, 1], 0.0)
    reach = np.asarray(ranges_m, dtype=float).reshape(-1, 1)
    occluders = ef * ef + el * el <= reach * reach  # (s, m)
    own = np.asarray(carriers, dtype=int).reshape(-1)
    rows = np.flatnonzero(own >= 0)
    occluders[rows, own[rows]] = False
    if seen.any():
        seen &= _clear(f[:s], l_[:s], f[s:], l_[s:], boxes.half, occluders)
    return seen, occluders


def _local(points: np.ndarray, boxes: Boxes) -> tuple[np.ndarray, np.ndarray]:
    """Forward and left coordinates of ``points`` (p, 2) in every box's frame, (p, m) each."""
    dx = points[:, 0:1] - boxes.centers[None, :, 0]  # (p, m)
    dy = points[:, 1:2] - boxes.centers[None, :, 1]
    ax = boxes.axes
    return dx * ax[:, 0, 0] + dy * ax[:, 0, 1], dx * ax[:, 1, 0] + dy * ax[:, 1, 1]


def box_distances(origins: np.ndarray, boxes: Boxes) -> np.ndarray:
    """Euclidean distance from each origin (s, 2) to each closed box, shape (s, m) (compiled:
    :func:`sse_cosim.sensors.kernels.box_distances`)."""
    return kernels.box_distances(_floats(origins, (-1, 2)), boxes.centers, boxes.axes,
                                 boxes.half)


def box_distances_reference(origins: np.ndarray, boxes: Boxes) -> np.ndarray:
    """The NumPy reference of :func:`box_distances`."""
    f, l_ = _local(np.asarray(origins, dtype=float).reshape(-1, 2), boxes)
    ef = np.maximum(np.abs(f) - boxes.half[:, 0], 0.0)
    el = np.maximum(np.abs(l_) - boxes.half[:, 1], 0.0)
    return np.hypot(ef, el)


def line_of_sight(
    origin: np.ndarray, targets: np.ndarray, boxes: Boxes | Sequence[Footprint]
) -> np.ndarray:
    """Whether the segment origin→target misses every box, shape (k,) bool.

    ``origin`` (2,), ``targets`` (k, 2), ``boxes`` m rectangles (or footprints); touching a
    box blocks. See :func:`clear_mask`.
    """
    if not isinstance(boxes, Boxes):
        boxes = Boxes.from_footprints(boxes)
    return clear_mask(np.asarray(origin, dtype=float).reshape(1, 2), targets, boxes)[0]


def sector_polygon(
    pose: Pose, fov_rad: float, range_m: float, resolution: int = 16
) -> shapely.Polygon:
    """The sector as a polygon inscribed in its arc; ``resolution`` chords per quarter turn.

    A sector of ``fov_rad`` >= 2 pi is the disc around the pose.
    """
    full = fov_rad >= FULL_TURN - _FULL_EPS
    ring = kernels.sector_points(pose.x, pose.y, pose.heading, range_m,
                                 _arc_offsets(FULL_TURN if full else fov_rad, resolution), full)
    return shapely.polygons(ring)


def sector_polygon_reference(
    pose: Pose, fov_rad: float, range_m: float, resolution: int = 16
) -> shapely.Polygon:
    """The NumPy reference of :func:`sector_polygon` (its ring compiled in
    :func:`sse_cosim.sensors.kernels.sector_points`)."""
    full = fov_rad >= FULL_TURN - _FULL_EPS
    angles = pose.heading + _arc_offsets(FULL_TURN if full else fov_rad, resolution)
    arc = pose.position + range_m * np.stack([np.cos(angles), np.sin(angles)], axis=1)
    if full:
        return shapely.Polygon(arc[:-1])
    return shapely.Polygon(np.vstack([pose.position, arc]))


@lru_cache(maxsize=64)
def _arc_offsets(span: float, resolution: int) -> np.ndarray:
    """The arc's angles about the boresight, (n + 1,) evenly over ``span``: ``resolution``
    chords per quarter turn (computed once per opening; read-only)."""
    n = max(1, math.ceil(span / (0.5 * math.pi) * resolution))
    offsets = np.linspace(-0.5 * span, 0.5 * span, n + 1)
    offsets.setflags(write=False)
    return offsets


def shadow_points_reference(origin: np.ndarray, boxes: Boxes, range_m: float
                            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(points (m, 4 + f, 2), reach (m,), inside (m,))``: the points whose convex hull is
    each box together with its shadow from ``origin`` (the box's corners, then far points at
    ``reach`` from the origin, beyond ``range_m``, on the rays between its silhouette
    bearings, the extreme bearings seen from the origin), and whether the box holds the
    origin. The NumPy reference of :func:`sse_cosim.sensors.kernels.shadow_points`."""
    o = np.asarray(origin, dtype=float).reshape(2)
    corners = boxes.corners()  # (m, 4, 2)
    rel = corners - o  # (m, 4, 2)
    to_center = boxes.centers - o  # (m, 2)
    cross = to_center[:, None, 0] * rel[:, :, 1] - to_center[:, None, 1] * rel[:, :, 0]
    dot = np.einsum("mj,mkj->mk", to_center, rel)
    bearing = np.arctan2(cross, dot)  # (m, 4), relative to the centre's bearing
    base = np.arctan2(to_center[:, 1], to_center[:, 0])  # (m,)
    lo, hi = bearing.min(axis=1), bearing.max(axis=1)
    rays = base[:, None] + lo[:, None] + (hi - lo)[:, None] * FAR_STEPS[None, :]  # (m, f)
    reach = 2.0 * (range_m + np.sqrt(np.einsum("mkj,mkj->mk", rel, rel)).max(axis=1))  # (m,)
    far = o + reach[:, None, None] * np.stack([np.cos(rays), np.sin(rays)], axis=2)
    inside = box_distances_reference(o.reshape(1, 2), boxes)[0] <= 0.0
    return np.concatenate([corners, far], axis=1), reach, inside


def shadow_polygons(origin: np.ndarray, boxes: Boxes, range_m: float) -> np.ndarray:
    """Each box together with the shadow it casts from ``origin``, shape (m,) of polygons.

    The box's two silhouette corners are extended radially beyond ``range_m``; box ∪ shadow
    is convex, so it is the convex hull of its shadow points (compiled:
    :func:`sse_cosim.sensors.kernels.shadow_points`). A box containing the origin hides
    everything: its shadow is a disc beyond the range.
    """
    o = np.asarray(origin, dtype=float).reshape(2)
    if len(boxes) == 0:
        return np.empty(0, dtype=object)
    points, reach, inside = kernels.shadow_points(o, boxes.centers, boxes.axes, boxes.half,
                                                  float(range_m), FAR_STEPS)
    # one line string per box: the same coordinates as a multipoint (so the same hull),
    # built without a shapely Point per coordinate
    hulls = shapely.convex_hull(shapely.linestrings(points))
    if np.any(inside):
        disc = shapely.Point(o).buffer(2.0 * float(reach.max()), quad_segs=8)
        hulls[inside] = disc
    return hulls


def visibility_regions(
    pose: Pose,
    fov_rad: float,
    range_m: float,
    boxes: Boxes,
    *,
    resolution: int = 16,
    sector: shapely.Polygon | None = None,
    kept: IdentityMemo[tuple[BaseGeometry, BaseGeometry]] | None = None,
) -> tuple[BaseGeometry, BaseGeometry]:
    """``(visible, occluded)``: the sector minus / intersected with the boxes' shadows.

    ``boxes`` are the occluders (the carrier already left out); only those reaching the
    sector's bounding circle are used. ``sector`` overrides the computed sector polygon
    (e.g. the one a static sensor keeps). The two regions partition the sector.

    A static sensor (same pose, same ``sector`` object) whose near occluders stand still
    (a parked truck) gets the same regions step after step: with the sensor's memo ``kept``
    they are kept by the pose, the sector and the occluders' exact coordinates, so a hit
    returns the identical result.
    """
    if sector is None:
        sector = sector_polygon(pose, fov_rad, range_m, resolution)
    near = boxes.subset(boxes.distances(pose.position) <= range_m) if len(boxes) else boxes
    if len(near) == 0:
        return sector, shapely.Polygon()

    def regions() -> tuple[BaseGeometry, BaseGeometry]:
        shadow = shapely.union_all(shadow_polygons(pose.position, near, range_m))
        return shapely.difference(sector, shadow), shapely.intersection(sector, shadow)

    if kept is None:
        return regions()
    key = (pose.x, pose.y, pose.heading, fov_rad, range_m, id(sector),
           near.centers.tobytes(), near.axes.tobytes(), near.half.tobytes())
    return kept.get(key, (sector,), regions)

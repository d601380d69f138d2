"""Compiled kernel (numba, cached on disk) of the shadows a sensor's occluders cast.

:func:`shadow_points` is :func:`~sse_cosim.sensors.geometry.shadow_points_reference` (the NumPy
reference, whose docstring carries the construction) on plain float64 arrays, with its
arithmetic: the same products and sums in the same order (the reference's two-term
``einsum`` sums start from zero), the same ``arctan2``/``cos``/``sin`` where NumPy's are
libm's, so the points agree to within the rounding of the angles, the bound
``tests/sensors/test_sensors_geometry.py`` checks (NumPy's SIMD trigonometry may differ from
libm's in the last bit).

numba caches the machine code in ``__pycache__`` next to this file (ignored by git).
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

SIGNS = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
"""The corners of a box, counter-clockwise from the rear right: signs of (forward, left)."""


@njit(cache=True)
def _corners(center: FloatArray, axes: FloatArray, half: FloatArray) -> FloatArray:
    """``Boxes.corners`` of one box: ``center`` (2,), ``axes`` (2, 2), ``half`` (2,) -> (4, 2)."""
    corners = np.empty((4, 2))
    for k in range(4):
        l0, l1 = SIGNS[k, 0] * half[0], SIGNS[k, 1] * half[1]
        for j in range(2):
            total = 0.0
            total += l0 * axes[0, j]
            total += l1 * axes[1, j]
            corners[k, j] = center[j] + total
    return corners


@njit(cache=True)
def shadow_points(origin: FloatArray, centers: FloatArray, axes: FloatArray, half: FloatArray,
                  range_m: float, steps: FloatArray
                  ) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
    """``(points (m, 4 + f, 2), reach (m,), inside (m,))`` of the boxes ``centers`` (m, 2),
    ``axes`` (m, 2, 2), ``half`` (m, 2) seen from ``origin`` (2,): each box's corners then its
    far points at the ray fractions ``steps`` (f,), how far those lie from the origin, and
    whether the (closed) box holds the origin."""
    m, f = centers.shape[0], steps.shape[0]
    points = np.empty((m, 4 + f, 2))
    reach = np.empty(m)
    inside = np.empty(m, dtype=np.bool_)
    for b in range(m):
        corners = _corners(centers[b], axes[b], half[b])
        t0, t1 = centers[b, 0] - origin[0], centers[b, 1] - origin[1]
        lo, hi, far = np.inf, -np.inf, 0.0
        for k in range(4):
            r0, r1 = corners[k, 0] - origin[0], corners[k, 1] - origin[1]
            dot = 0.0
            dot += t0 * r0
            dot += t1 * r1
            bearing = np.arctan2(t0 * r1 - t1 * r0, dot)
            lo, hi = min(lo, bearing), max(hi, bearing)
            square = 0.0
            square += r0 * r0
            square += r1 * r1
            far = max(far, np.sqrt(square))
            points[b, k] = corners[k]
        reach[b] = 2.0 * (range_m + far)
        base = np.arctan2(t1, t0)
        for s in range(f):
            ray = base + lo + (hi - lo) * steps[s]
            points[b, 4 + s, 0] = origin[0] + reach[b] * np.cos(ray)
            points[b, 4 + s, 1] = origin[1] + reach[b] * np.sin(ray)
        dx, dy = origin[0] - centers[b, 0], origin[1] - centers[b, 1]
        along = dx * axes[b, 0, 0] + dy * axes[b, 0, 1]
        across = dx * axes[b, 1, 0] + dy * axes[b, 1, 1]
        inside[b] = abs(along) - half[b, 0] <= 0.0 and abs(across) - half[b, 1] <= 0.0
    return points, reach, inside


@njit(cache=True)
def sector_points(x: float, y: float, heading: float, range_m: float, offsets: FloatArray,
                  full: bool) -> FloatArray:
    """The ring of a sector polygon, shape (k, 2): the apex (x, y), then the arc's points at
    the angles ``heading + offsets`` (n + 1,) and ``range_m`` from it; a full turn (a disc) is
    the arc alone, its last point (the first again) left out."""
    n = offsets.shape[0]
    first = 0 if full else 1
    ring = np.empty((n - 1 if full else n + 1, 2))
    if not full:
        ring[0, 0], ring[0, 1] = x, y
    for i in range(n - 1 if full else n):
        angle = heading + offsets[i]
        ring[first + i, 0] = x + range_m * np.cos(angle)
        ring[first + i, 1] = y + range_m * np.sin(angle)
    return ring


@njit(cache=True)
def _box_frame(x: float, y: float, centers: FloatArray, axes: FloatArray, b: int
               ) -> tuple[float, float]:
    """``geometry._local``: the forward and left coordinates of (x, y) in box ``b``'s frame."""
    dx, dy = x - centers[b, 0], y - centers[b, 1]
    return dx * axes[b, 0, 0] + dy * axes[b, 0, 1], dx * axes[b, 1, 0] + dy * axes[b, 1, 1]


@njit(cache=True)
def sight_masks(origins: FloatArray, headings: FloatArray, fovs_rad: FloatArray,
                ranges_m: FloatArray, carriers: NDArray[np.int64], targets: FloatArray,
                centers: FloatArray, axes: FloatArray, half: FloatArray, full_half: float
                ) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    """``geometry.sight_masks_reference`` on arrays: ``(seen (s, k), occluders (s, m))`` for
    sensors ``origins`` (s, 2), ``headings``/``fovs_rad``/``ranges_m`` (s,), ``carriers`` (s,)
    (box index, -1: none), targets (k, 2) and boxes ``centers`` (m, 2), ``axes`` (m, 2, 2),
    ``half`` (m, 2); a half-opening >= ``full_half`` is a disc. The reference's elementwise
    arithmetic, test by test (a segment is clear when every active box is separated from it
    along the box's axes or the segment's normal)."""
    s, k, m = origins.shape[0], targets.shape[0], centers.shape[0]
    seen = np.zeros((s, k), dtype=np.bool_)
    occluders = np.zeros((s, m), dtype=np.bool_)
    target_f = np.empty((k, m))
    target_l = np.empty((k, m))
    for i in range(k):
        for b in range(m):
            target_f[i, b], target_l[i, b] = _box_frame(targets[i, 0], targets[i, 1],
                                                        centers, axes, b)
    origin_f = np.empty(m)
    origin_l = np.empty(m)
    for j in range(s):
        ox, oy = origins[j, 0], origins[j, 1]
        reach = ranges_m[j]
        for b in range(m):
            origin_f[b], origin_l[b] = _box_frame(ox, oy, centers, axes, b)
            ef = max(abs(origin_f[b]) - half[b, 0], 0.0)
            el = max(abs(origin_l[b]) - half[b, 1], 0.0)
            occluders[j, b] = ef * ef + el * el <= reach * reach and b != carriers[j]
        cos_h, sin_h = np.cos(headings[j]), np.sin(headings[j])
        half_fov = 0.5 * fovs_rad[j]
        full = half_fov >= full_half
        cos_half = np.cos(half_fov)
        for i in range(k):
            dx, dy = targets[i, 0] - ox, targets[i, 1] - oy
            dist2 = dx * dx + dy * dy
            along = dx * cos_h + dy * sin_h
            if not (dist2 <= reach * reach and (full or along >= np.sqrt(dist2) * cos_half)):
                continue
            seen[j, i] = _clear(origin_f, origin_l, target_f[i], target_l[i], half,
                                occluders[j])
    return seen, occluders


@njit(cache=True)
def _clear(of: FloatArray, ol: FloatArray, tf: FloatArray, tl: FloatArray, half: FloatArray,
           active: NDArray[np.bool_]) -> bool:
    """``geometry._clear`` for one segment: whether it misses every active box, from both
    ends' box-frame coordinates (m,) each."""
    for b in range(half.shape[0]):
        if not active[b]:
            continue
        hf, hl = half[b, 0], half[b, 1]
        if min(of[b], tf[b]) > hf or max(of[b], tf[b]) < -hf:
            continue
        if min(ol[b], tl[b]) > hl or max(ol[b], tl[b]) < -hl:
            continue
        if abs(of[b] * tl[b] - tf[b] * ol[b]) > abs(tl[b] - ol[b]) * hf + abs(tf[b] - of[b]) * hl:
            continue
        return False
    return True


@njit(cache=True)
def box_distances(origins: FloatArray, centers: FloatArray, axes: FloatArray,
                  half: FloatArray) -> FloatArray:
    """``geometry.box_distances_reference``: the distance from each origin (s, 2) to each
    closed box (``centers`` (m, 2), ``axes`` (m, 2, 2), ``half`` (m, 2)), shape (s, m)."""
    s, m = origins.shape[0], centers.shape[0]
    distances = np.empty((s, m))
    for j in range(s):
        for b in range(m):
            along, across = _box_frame(origins[j, 0], origins[j, 1], centers, axes, b)
            distances[j, b] = np.hypot(max(abs(along) - half[b, 0], 0.0),
                                       max(abs(across) - half[b, 1], 0.0))
    return distances

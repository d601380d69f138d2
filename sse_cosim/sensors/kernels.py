"""Compiled kernel (numba, cached on disk) of the shadows a sensor's occluders cast.

:func:`shadow_points` is :func:`~sse_cosim.sensors.geometry.shadow_points_reference` (the NumPy
reference, whose docstring carries the construction) on plain float64 arrays, with its
arithmetic: the same products and sums in the same order (the reference's two-term
``einsum`` sums start from zero), the same ``arctan2``/``cos``/``sin``, so the points are equal
bit for bit (``tests/sensors/test_sensors_geometry.py``).

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

"""Compiled kernels (numba, cached on disk) of the recorder's position sets and containment
check, on plain float64 arrays:

- :func:`position_2d` for :func:`~sse_cosim.reporting.recorder.position_arrays` (a state set's
  position rows beside its jitter box, each entry plus 0.0, as NumPy's ufuncs add it);
- :func:`halfspaces_2d` for the half-spaces of a 2-D zonotope (reference
  :func:`~sse_cosim.reporting.recorder.zonotope_2d_halfspaces_reference`) and
  :func:`contains_2d` for :func:`~sse_cosim.reporting.recorder.zonotope_2d_contains`;
- :func:`encoded_cm` for the replay's polygons in integer centimetres (reference
  :func:`~sse_cosim.reporting.replay.encode_reference`; ``rint`` rounds half to even, as
  NumPy's).

Each does its reference's IEEE 754 operations (elementwise +, -, *, /, sqrt, abs and
comparisons, each correctly rounded) in the same order, every sum from the left, and no fused
multiply-add (numba asks LLVM for none without ``fastmath``): the reference's bits and
verdicts on every CPU, which ``tests/reporting/test_recorder_kernels.py`` checks exactly (the
``kernels`` marker).

numba caches the machine code in ``__pycache__`` next to this file (ignored by git).
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

FLAT_SINE = 0.5
"""A set whose generators are all within 30° of each other counts as flat."""


@njit(cache=True)
def position_2d(center: FloatArray, generators: FloatArray,
                jitter: float) -> tuple[FloatArray, FloatArray]:
    """⟨c[:2], [G[:2], jitter I]⟩ of c (n,), G (n, e), shapes (2,), (2, e + 2), or
    ⟨c[:2], G[:2]⟩, (2,), (2, e), for ``jitter`` 0, every entry plus 0.0 (a zero of either
    sign becomes 0.0): ``recorder.position_arrays``, whose docstring says why."""
    e = generators.shape[1]
    box = 0 if jitter == 0.0 else 2
    position_center = np.empty(2)
    position_generators = np.empty((2, e + box))
    for i in range(2):
        position_center[i] = center[i] + 0.0
        for j in range(e):
            position_generators[i, j] = generators[i, j] + 0.0
        for j in range(box):
            position_generators[i, e + j] = (1.0 if i == j else 0.0) * jitter + 0.0
    return position_center, position_generators


@njit(cache=True)
def _nonzero_columns(generators: FloatArray) -> FloatArray:
    """The nonzero columns of G (2, e), in order, as a (2, k) array."""
    e = generators.shape[1]
    columns = np.empty((2, e))
    k = 0
    for j in range(e):
        if generators[0, j] != 0.0 or generators[1, j] != 0.0:
            columns[0, k] = generators[0, j]
            columns[1, k] = generators[1, j]
            k += 1
    return columns[:, :k]


@njit(cache=True)
def _units(columns: FloatArray) -> FloatArray:
    """Each column (2, k) of ``columns`` (nonzero) scaled to length 1, by its largest entry
    first (no square underflows)."""
    k = columns.shape[1]
    units = np.empty((2, k))
    for j in range(k):
        a, b = columns[0, j], columns[1, j]
        scale = abs(b) if abs(b) > abs(a) else abs(a)  # Python's max(|a|, |b|)
        a, b = a / scale, b / scale
        length = np.sqrt(a * a + b * b)
        units[0, j], units[1, j] = a / length, b / length
    return units


@njit(cache=True)
def _is_flat(units: FloatArray) -> bool:
    """Whether the sine between every two unit directions (2, k) is below :data:`FLAT_SINE`."""
    k = units.shape[1]
    for i in range(k):
        for j in range(i + 1, k):
            if abs(units[0, i] * units[1, j] - units[1, i] * units[0, j]) >= FLAT_SINE:
                return False
    return True


@njit(cache=True)
def halfspaces_2d(generators: FloatArray, tol: float) -> FloatArray:
    """The rows (d_x, d_y, b), shape (m, 3), of the half-spaces |d·(x − c)| <= b whose
    intersection is the 2-D zonotope ⟨c, G⟩, G (2, e), widened by ``tol``: the normal
    (−u_y, u_x) of every nonzero generator's unit direction u, then, for a flat set, the
    directions u themselves; a point's two axes. b = Σ_i |d·g_i| + tol, summed from the
    left."""
    columns = _nonzero_columns(generators)
    k = columns.shape[1]
    if k == 0:
        rows = np.zeros((2, 3))
        rows[0, 0], rows[0, 2] = 1.0, tol
        rows[1, 1], rows[1, 2] = 1.0, tol
        return rows
    units = _units(columns)
    flat = _is_flat(units)
    rows = np.empty((2 * k if flat else k, 3))
    for j in range(k):
        rows[j, 0], rows[j, 1] = -units[1, j], units[0, j]
        if flat:
            rows[k + j, 0], rows[k + j, 1] = units[0, j], units[1, j]
    for r in range(rows.shape[0]):
        dx, dy = rows[r, 0], rows[r, 1]
        total = 0.0
        for j in range(k):
            total += abs(dx * columns[0, j] + dy * columns[1, j])
        rows[r, 2] = total + tol
    return rows


@njit(cache=True)
def contains_2d(center: FloatArray, generators: FloatArray, point: FloatArray,
                tol: float) -> bool:
    """Whether ``point`` (2,) lies in the 2-D zonotope ⟨c, G⟩, ``center`` (2,), ``generators``
    (2, e), up to ``tol``: |d·(x − c)| <= b for every row (d, b) of :func:`halfspaces_2d`."""
    halfspaces = halfspaces_2d(generators, tol)
    x, y = point[0] - center[0], point[1] - center[1]
    for r in range(halfspaces.shape[0]):
        if not abs(halfspaces[r, 0] * x + halfspaces[r, 1] * y) <= halfspaces[r, 2]:
            return False
    return True


@njit(cache=True)
def encoded_cm(points: FloatArray, per_m: float) -> NDArray[np.int32]:
    """The replay's encoding of ``points`` (k >= 1, 2) in m (``replay._encode``): each point
    times ``per_m``, rounded half to even to an int32, then the first point and the steps
    between neighbours that are not zero, flattened (2 + 2s,)."""
    k = points.shape[0]
    out = np.empty(2 * k, dtype=np.int32)
    last_x = np.int32(np.rint(points[0, 0] * per_m))
    last_y = np.int32(np.rint(points[0, 1] * per_m))
    out[0], out[1] = last_x, last_y
    count = 2
    for i in range(1, k):
        x = np.int32(np.rint(points[i, 0] * per_m))
        y = np.int32(np.rint(points[i, 1] * per_m))
        if x != last_x or y != last_y:
            out[count], out[count + 1] = x - last_x, y - last_y
            count += 2
        last_x, last_y = x, y
    return out[:count].copy()

"""Arithmetic that gives the same bits on every x86-64 CPU: matrix products and angles.

Two parts of NumPy pick their machine code for the CPU they run on, so their last bits (and
every decision taken on them: which vertex a polygon keeps, which set a fusion chooses) may
move from one machine to another:

- ``@``, ``np.dot`` and ``np.linalg`` hand float64 work to OpenBLAS, whose kernels differ by
  CPU (with or without FMA, AVX2 or AVX-512) in how they round and in what order they sum;
- ``np.sin``, ``np.cos``, ``np.tan``, ``np.arctan2`` and other transcendental ufuncs
  dispatch to SIMD versions on CPUs with AVX-512, which may differ in the last bit from the C
  library's.

The estimator, the sensors and the controller use these functions instead:

- :func:`matmul` multiplies elementwise and sums in a fixed order, each operation rounded as
  IEEE 754 prescribes, the same on every CPU;
- :func:`sin`, :func:`cos`, :func:`tan`, :func:`arctan2` and :func:`hypot` are compiled
  ufuncs that call the C library's functions element by element, as the compiled kernels
  (numba) do.

``tests/sets/test_sets_portable.py`` checks them against NumPy within a stated bound, and
``tests/test_portable_results.py`` runs a scenario under other OpenBLAS kernels, NumPy's
baseline SIMD and numba's generic CPU, and asks for the same files, byte for byte.
"""

from __future__ import annotations

import math

import numpy as np
from numba import vectorize
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


def matmul(a: ArrayLike, b: ArrayLike) -> FloatArray:
    """``a @ b`` without BLAS, for a (..., m, n) or (n,) and b (..., n, k) or (n,): elementwise
    products summed over n (index order below eight terms, numpy's pairwise order above)."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if b.ndim == 1:
        return (a * b).sum(axis=-1)
    if a.ndim == 1:
        return (a[:, np.newaxis] * b).sum(axis=0)
    return (a[..., :, :, np.newaxis] * b[..., np.newaxis, :, :]).sum(axis=-2)


def inverse_2x2(m: ArrayLike) -> FloatArray:
    """The inverse of a regular (2, 2) matrix by its adjugate (LAPACK's LU rounds by CPU)."""
    m = np.asarray(m, dtype=np.float64)
    det = m[0, 0] * m[1, 1] - m[0, 1] * m[1, 0]
    if not det != 0.0:
        raise np.linalg.LinAlgError("singular 2x2 matrix")
    return np.array([[m[1, 1], -m[0, 1]], [-m[1, 0], m[0, 0]]]) / det


@vectorize(["float64(float64)"], cache=True)
def sin(x: float) -> float:
    """The C library's sin, elementwise."""
    return math.sin(x)


@vectorize(["float64(float64)"], cache=True)
def cos(x: float) -> float:
    """The C library's cos, elementwise."""
    return math.cos(x)


@vectorize(["float64(float64)"], cache=True)
def tan(x: float) -> float:
    """The C library's tan, elementwise."""
    return math.tan(x)


@vectorize(["float64(float64, float64)"], cache=True)
def hypot(x: float, y: float) -> float:
    """The C library's hypot, elementwise (the length of (x, y))."""
    return math.hypot(x, y)


@vectorize(["float64(float64, float64)"], cache=True)
def arctan2(y: float, x: float) -> float:
    """The C library's atan2, elementwise (the angle of (x, y))."""
    return math.atan2(y, x)

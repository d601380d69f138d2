"""Order reduction of zonotope generator matrices; every method is sound (result ⊇ input).

Both methods keep the ``max_generators - n`` generators largest by ‖g‖₁ − ‖g‖∞ (Girard's
criterion) and enclose the zonotope spanned by the others with a box of n generators: axis
aligned for ``girard``, aligned with the principal axes (SVD) of those generators for ``pca``.
The center never changes, so methods act on the generator matrix alone.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from sse_cosim.sets import kernels, portable

FloatArray = NDArray[np.float64]
Reducer = Callable[[FloatArray, int], FloatArray]


def box_in_frame(generators: FloatArray, frame: FloatArray) -> FloatArray:
    """Generators (n, n) of the box aligned with the orthonormal ``frame`` (n, n) that encloses
    ⟨0, generators⟩: column i is frame_i · Σ_j |frame_iᵀ g_j|."""
    return frame * np.abs(portable.matmul(frame.T, generators)).sum(axis=1)


def _girard_frame(rest: FloatArray) -> FloatArray:
    return np.eye(rest.shape[0])


def _pca_frame(rest: FloatArray) -> FloatArray:
    return np.linalg.svd(rest, full_matrices=True)[0]


def _reducer(frame: Callable[[FloatArray], FloatArray]) -> Reducer:
    def reduce(generators: FloatArray, max_generators: int) -> FloatArray:
        n = generators.shape[0]
        if max_generators < n:
            raise ValueError(f"max_generators must be >= the dimension {n}, got {max_generators}")
        g = generators[:, np.any(generators != 0, axis=0)]
        if g.shape[1] <= max_generators:
            return g
        score = np.abs(g).sum(axis=0) - np.abs(g).max(axis=0)
        order = np.argsort(-score, kind="stable")
        kept, rest = g[:, order[: max_generators - n]], g[:, order[max_generators - n :]]
        box = box_in_frame(rest, frame(rest))
        return np.hstack([kept, box[:, np.any(box != 0, axis=0)]])

    return reduce


girard_reduce_reference = _reducer(_girard_frame)
"""The ``girard`` reduction in NumPy: the reference of the compiled kernel."""


def girard_reduce(generators: FloatArray, max_generators: int) -> FloatArray:
    """The ``girard`` reduction by the compiled :func:`~sse_cosim.sets.kernels.girard_reduce`
    (the same bits as :data:`girard_reduce_reference`)."""
    n = generators.shape[0]
    if max_generators < n:
        raise ValueError(f"max_generators must be >= the dimension {n}, got {max_generators}")
    return kernels.girard_reduce(generators, max_generators)


REDUCTION_METHODS: dict[str, Reducer] = {
    "girard": girard_reduce,
    "pca": _reducer(_pca_frame),
}

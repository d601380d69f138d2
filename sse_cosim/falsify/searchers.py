"""How the falsifier chooses where to look next: one searcher per method, in a registry.

A searcher proposes a generation of points in the unit cube (``ask``) and learns their
margins (``tell``). It is built from a seed alone and holds no other state, so a search
replayed from its recorded margins proposes the same points again: that is how a killed
search resumes (:mod:`sse_cosim.falsify.search`).

- ``cma``: CMA-ES (Hansen's covariance matrix adaptation) from the ``cmaes`` package, the
  implementation Optuna's CMA-ES sampler uses, with the box as its bounds. Its random state
  belongs to the object (no global NumPy state). It proposes the same points on every
  machine (:class:`PortableCMA`).
- ``random``: uniform random search with the same generation size, the baseline the report
  sets beside every search.

A new method is one class added to :data:`SEARCHERS`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Protocol

import numpy as np
from cmaes import CMA

from sse_cosim.sets import portable

CMA_SIGMA = 0.3
"""CMA-ES's initial step size in the unit cube: about a third of each interval."""
POINT_DECIMALS = 6
"""CMA-ES's points are rounded to this many decimals of the unit cube (10 us of a 10 s
interval): its linear algebra differs from one CPU to another in the last digits, which the
rounding removes (:class:`PortableCMA`)."""


class Searcher(Protocol):
    def ask(self) -> np.ndarray:
        """The next generation, shape (n, d), each coordinate in [0, 1]."""

    def tell(self, points: np.ndarray, margins: Sequence[float]) -> None:
        """The margins of the points of the last generation, in the same order."""


def generation_size(dims: int) -> int:
    """CMA-ES's default population for ``dims`` dimensions (4 + 3 ln d), used by every
    method so that both spend the budget in the same steps."""
    return 4 + math.floor(3 * math.log(dims))


class PortableCMA(CMA):
    """``cmaes``'s CMA-ES, sampling N(0, C) as C^(1/2) z with the symmetric square root
    B D B^T instead of B D z.

    The eigenvectors B of C come from LAPACK, whose kernels differ by CPU (OpenBLAS picks
    them at run time). Where C has a repeated eigenvalue (C starts as the identity, and each
    generation's update adds a rank of at most the number of parents, so in 41 dimensions
    most of it stays repeated for many generations), the eigenvectors of that eigenspace are
    any basis of it, each CPU returns another, and B D z differs entirely: the searches of
    two machines part at the first such generation. B D B^T is the same matrix whatever the
    basis, so the samples differ only as much as the last digits of its eigenpairs (the
    products are :func:`~sse_cosim.sets.portable.matmul`'s), and rounding them to
    :data:`POINT_DECIMALS` gives the same points (tests/falsify/test_portable_search.py, on
    OpenBLAS's and NumPy's kernels for another CPU). The distribution is the same, N(m,
    sigma^2 C)."""

    def _sample_solution(self) -> np.ndarray:
        b, d = self._eigen_decomposition()
        z = self._rng.randn(self._n_dim)  # ~ N(0, I)
        return self._mean + self._sigma * portable.matmul(b, d * portable.matmul(b.T, z))


class CmaSearcher:
    """CMA-ES over the unit cube, started at its centre, its points rounded to
    :data:`POINT_DECIMALS` (the points it is told are those)."""

    def __init__(self, dims: int, seed: int, size: int) -> None:
        self._cma = PortableCMA(mean=np.full(dims, 0.5), sigma=CMA_SIGMA,
                        bounds=np.tile([0.0, 1.0], (dims, 1)), seed=seed,
                        population_size=size)

    def ask(self) -> np.ndarray:
        points = [self._cma.ask() for _ in range(self._cma.population_size)]
        return np.round(np.array(points), POINT_DECIMALS)

    def tell(self, points: np.ndarray, margins: Sequence[float]) -> None:
        self._cma.tell([(p, float(m)) for p, m in zip(points, margins, strict=True)])


class RandomSearcher:
    """Uniform random points of the unit cube."""

    def __init__(self, dims: int, seed: int, size: int) -> None:
        self._rng = np.random.default_rng(seed)
        self._shape = (size, dims)

    def ask(self) -> np.ndarray:
        return self._rng.random(self._shape)

    def tell(self, points: np.ndarray, margins: Sequence[float]) -> None:
        """Random search learns nothing."""


SEARCHERS: dict[str, Callable[[int, int, int], Searcher]] = {
    "cma": CmaSearcher,
    "random": RandomSearcher,
}
"""Method name -> constructor(dims, seed, generation size)."""

"""How the falsifier chooses where to look next: one searcher per method, in a registry.

A searcher proposes a generation of points in the unit cube (``ask``) and learns their
margins (``tell``). It is built from a seed alone and holds no other state, so a search
replayed from its recorded margins proposes the same points again: that is how a killed
search resumes (:mod:`sse_cosim.falsify.search`).

- ``cma``: CMA-ES (Hansen's covariance matrix adaptation) from the ``cmaes`` package, the
  implementation Optuna's CMA-ES sampler uses, with the box as its bounds. Its random state
  belongs to the object (no global NumPy state).
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

CMA_SIGMA = 0.3
"""CMA-ES's initial step size in the unit cube: about a third of each interval."""


class Searcher(Protocol):
    def ask(self) -> np.ndarray:
        """The next generation, shape (n, d), each coordinate in [0, 1]."""

    def tell(self, points: np.ndarray, margins: Sequence[float]) -> None:
        """The margins of the points of the last generation, in the same order."""


def generation_size(dims: int) -> int:
    """CMA-ES's default population for ``dims`` dimensions (4 + 3 ln d), used by every
    method so that both spend the budget in the same steps."""
    return 4 + math.floor(3 * math.log(dims))


class CmaSearcher:
    """CMA-ES over the unit cube, started at its centre."""

    def __init__(self, dims: int, seed: int, size: int) -> None:
        self._cma = CMA(mean=np.full(dims, 0.5), sigma=CMA_SIGMA,
                        bounds=np.tile([0.0, 1.0], (dims, 1)), seed=seed,
                        population_size=size)

    def ask(self) -> np.ndarray:
        return np.array([self._cma.ask() for _ in range(self._cma.population_size)])

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

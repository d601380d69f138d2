"""Zonotopes ⟨c, G⟩ = {c + Gβ : β ∈ [-1, 1]^e} (paper eq. zonoDef), n-dimensional.

Exact operations: Minkowski sum (eq. minkowski), linear map (eq. linmap), support function,
interval hull, volume, 2-D vertices and point containment.

Performance: the public constructor validates and copies its arrays; operations of this
library build their results with :meth:`Zonotope.unchecked`, which skips that for arrays the
library computed itself from validated inputs (finite by construction). 2-D sets, the only
ones the co-simulation uses, get closed-form paths (cross products instead of SVDs and
determinant stacks); ``tests/sets`` checks them against the general code.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from functools import cache
from itertools import combinations
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sse_cosim.sets import portable
from sse_cosim.sets._registry import lookup
from sse_cosim.sets.kernels import PARALLEL_RTOL, area_2d, contains_2d, full_rank_2d, vertices_2d
from sse_cosim.sets.lp import linprog
from sse_cosim.sets.portable import matmul
from sse_cosim.sets.reduction import REDUCTION_METHODS
from sse_cosim.sets.volume_gain_kernels import full_rank_nd, generator_volume_nd

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]



def _read_only(values: ArrayLike) -> FloatArray:
    array = np.array(values, dtype=np.float64)
    array.setflags(write=False)
    return array


@cache
def subset_indices(e: int, k: int) -> NDArray[np.intp]:
    """All k-subsets of range(e) in lexicographic order, shape (C(e, k), k), read-only."""
    rows = list(combinations(range(e), k))
    indices = np.array(rows, dtype=np.intp).reshape(len(rows), k)
    indices.setflags(write=False)
    return indices


def generator_volume(generators: FloatArray) -> float:
    """Volume of ⟨c, G⟩, G (n, e): 2ⁿ Σ over n-subsets S of |det G_S| (2-D: 2 Σ_ij |g_i × g_j|).

    2-D by the compiled :func:`~sse_cosim.sets.kernels.area_2d` (the same bits as the
    reference), n >= 3 by the compiled
    :func:`~sse_cosim.sets.volume_gain_kernels.generator_volume_nd` (the reference's value
    up to rounding), 1-D by :func:`generator_volume_reference`.
    """
    n = generators.shape[0]
    if n == 2:
        return area_2d(generators)
    if n >= 3:
        return generator_volume_nd(np.ascontiguousarray(generators, dtype=np.float64))
    return generator_volume_reference(generators)


def generator_volume_reference(generators: FloatArray) -> float:
    """:func:`generator_volume` in NumPy, any n (the reference of the compiled kernels).

    Zero columns are skipped first, so adding or dropping them never changes the rounding.
    """
    if generators.shape[0] == 2:
        g = generators[:, (generators[0] != 0) | (generators[1] != 0)]
        cross = g[0][:, None] * g[1] - g[1][:, None] * g[0]
        return float(2.0 * np.abs(cross).sum())
    generators = generators[:, np.any(generators != 0, axis=0)]
    n, e = generators.shape
    blocks = generators[:, subset_indices(e, n)].transpose(1, 0, 2)
    return float(2.0**n * abs_determinants(blocks).sum())


def abs_determinants(blocks: FloatArray) -> FloatArray:
    """|det| of each square block (k, n, n), as the product of |diag R| of its QR factors.

    ``np.linalg.det`` goes through LU and logarithms, and warns (divide by zero) on the
    singular or subnormal blocks of a degenerate set, such as the constant-velocity model's
    4-D sets whose velocity generators have shrunk to nothing; Q is orthogonal, so QR gives
    the same |det| with neither a division by a pivot nor a logarithm.
    """
    r = np.linalg.qr(blocks, mode="r")
    return np.abs(np.diagonal(r, axis1=-2, axis2=-1)).prod(axis=-1)


def cofactor_vectors(generators: FloatArray) -> FloatArray:
    """Cofactor vector d_S of every (n-1)-subset S of G's columns, so that det[G_S, x] = d_Sᵀx.

    G (n, e) -> (C(e, n-1), n); in 2-D row i is (-g_i[1], g_i[0]).
    """
    n, e = generators.shape
    if n == 2:
        return np.stack([-generators[1], generators[0]], axis=1)
    blocks = generators[:, subset_indices(e, n - 1)].transpose(1, 0, 2)
    rows = np.arange(n)
    minors = np.stack([np.linalg.det(blocks[:, rows != i, :]) for i in range(n)], axis=1)
    return minors * (-1.0) ** (rows + n - 1)


def _unit_rows(vectors: FloatArray) -> FloatArray:
    """The nonzero rows of ``vectors`` (k, n), normalized."""
    norms = np.sqrt((vectors * vectors).sum(axis=1))
    keep = norms > 0
    return vectors[keep] / norms[keep, None]


def facet_normals(generators: FloatArray) -> FloatArray:
    """Unit normals (k, n) of all candidate facets of ⟨c, G⟩: the nonzero cofactor vectors,
    normalized, with parallel ones merged (sign fixed so the first nonzero entry is positive)."""
    units = _unit_rows(cofactor_vectors(generators))
    rounded = np.round(units, 12) + 0.0
    first = np.argmax(rounded != 0, axis=1)
    sign = np.sign(rounded[np.arange(len(units)), first])
    keyed = rounded * sign[:, None] + 0.0
    if keyed.shape[1] == 2:  # same first occurrences as the row-wise unique, much cheaper
        _, keep = np.unique(keyed[:, 0] + 1j * keyed[:, 1], return_index=True)
    else:
        _, keep = np.unique(keyed, axis=0, return_index=True)
    keep = np.sort(keep)
    return units[keep] * sign[keep, None]


def full_rank(generators: FloatArray) -> bool:
    """Whether G (n, e) has rank n, with numpy's ``matrix_rank`` tolerance
    (s_min > e·eps·s_max); 2-D in closed form (s_max² and s_min·s_max from 2×2 minors),
    otherwise by the compiled :func:`~sse_cosim.sets.volume_gain_kernels.full_rank_nd`
    (one-sided Jacobi instead of LAPACK's SVD: the same decision on every CPU)."""
    n, e = generators.shape
    if e < n:
        return False
    if n != 2:
        return bool(full_rank_nd(np.ascontiguousarray(generators, dtype=np.float64)))
    a, b = generators[0], generators[1]
    p, q, r = matmul(a, a), matmul(b, b), matmul(a, b)
    if p + q == 0.0:
        return False
    s_max2 = 0.5 * (p + q) + np.sqrt(0.25 * (p - q) ** 2 + r * r)  # largest eigenvalue of GGᵀ
    cross = a[:, None] * b - b[:, None] * a
    s_prod = np.sqrt(0.5 * (cross * cross).sum())  # s_min·s_max = sqrt(det GGᵀ) (Cauchy-Binet)
    return bool(s_prod > e * np.finfo(np.float64).eps * s_max2)


def contains_2d_reference(center: FloatArray, generators: FloatArray, points: FloatArray,
                          tol: float) -> BoolArray:
    """The NumPy reference of :func:`~sse_cosim.sets.kernels.contains_2d`: whether each point
    (k, 2) lies in the full-rank 2-D ⟨c, G⟩, shape (k,), by the unit facet normals."""
    normals = _unit_rows(cofactor_vectors(generators))  # parallel repeats only repeat a test
    offsets = np.abs(matmul(points - center, normals.T))
    return (offsets <= np.abs(matmul(normals, generators)).sum(axis=1) + tol).all(axis=1)


def _merge_parallel(sorted_generators: FloatArray) -> FloatArray:
    """Sum runs of consecutive parallel columns of angle-sorted, same-half-plane generators,
    each run column by column from the left (the compiled kernel's order; ``np.add.reduceat``
    groups the terms otherwise)."""
    a, b = sorted_generators[:, :-1], sorted_generators[:, 1:]
    cross = a[0] * b[1] - a[1] * b[0]
    scale = np.sqrt((a * a).sum(axis=0)) * np.sqrt((b * b).sum(axis=0))
    starts = np.flatnonzero(np.concatenate([[True], np.abs(cross) > PARALLEL_RTOL * scale]))
    ends = np.append(starts[1:], sorted_generators.shape[1])
    return np.stack([np.cumsum(sorted_generators[:, start:end], axis=1)[:, -1]
                     for start, end in zip(starts, ends, strict=True)], axis=1)


def vertices_2d_reference(center: FloatArray, generators: FloatArray) -> FloatArray:
    """The NumPy reference of :func:`~sse_cosim.sets.kernels.vertices_2d`: the vertices (k, 2)
    of the 2-D ⟨c, G⟩ (``Zonotope.vertices``)."""
    g = generators[:, np.any(generators != 0, axis=0)]
    flip = (g[1] < 0) | ((g[1] == 0) & (g[0] < 0))
    g = np.where(flip, -g, g)
    g = g[:, np.argsort(portable.arctan2(g[1], g[0]), kind="stable")]
    if g.shape[1] == 0:
        return center[None, :].copy()
    g = _merge_parallel(g)
    start = center - g.sum(axis=1)
    path = start + np.cumsum(2.0 * np.hstack([g, -g]).T, axis=0)
    return np.vstack([start, path[:-1]])


@dataclass(frozen=True, eq=False)
class Zonotope:
    """⟨c, G⟩ (eq. zonoDef): ``center`` (n,), ``generators`` (n, e), e >= 0; read-only float64."""

    center: FloatArray
    generators: FloatArray

    # Makes numpy defer ``M @ Z`` and ``v + Z`` to __rmatmul__ / __radd__.
    __array_ufunc__ = None

    @classmethod
    def unchecked(cls, center: FloatArray, generators: FloatArray) -> Zonotope:
        """⟨c, G⟩ from float64 arrays of shapes (n,), (n, e) that this library computed from
        validated inputs: no copy, no checks (they are made read-only in place)."""
        zonotope = object.__new__(cls)
        center.setflags(write=False)
        generators.setflags(write=False)
        object.__setattr__(zonotope, "center", center)
        object.__setattr__(zonotope, "generators", generators)
        return zonotope

    def __post_init__(self) -> None:
        center = np.array(self.center, dtype=np.float64)
        if center.ndim != 1 or center.size == 0:
            raise ValueError(f"zonotope center must have shape (n,), n >= 1; got {center.shape}")
        generators = np.array(self.generators, dtype=np.float64)
        if generators.ndim == 1 and generators.size == 0:
            generators = generators.reshape(center.size, 0)
        if generators.ndim != 2 or generators.shape[0] != center.size:
            raise ValueError(
                f"zonotope generators must have shape ({center.size}, e); got {generators.shape}"
            )
        if not (np.isfinite(center).all() and np.isfinite(generators).all()):
            raise ValueError("zonotope center and generators must be finite")
        object.__setattr__(self, "center", _read_only(center))
        object.__setattr__(self, "generators", _read_only(generators))

    @property
    def dim(self) -> int:
        """State dimension n."""
        return self.center.size

    @property
    def n_generators(self) -> int:
        """Number of generators e."""
        return self.generators.shape[1]

    def __add__(self, other: Zonotope | ArrayLike) -> Zonotope:
        """Minkowski sum with a zonotope (eq. minkowski) or translation by a vector (n,)."""
        if isinstance(other, Zonotope):
            if other.dim != self.dim:
                raise ValueError(f"Minkowski sum of a {self.dim}-D and a {other.dim}-D zonotope")
            generators = np.concatenate([self.generators, other.generators], axis=1)
            return Zonotope.unchecked(self.center + other.center, generators)
        return self.translate(other)

    __radd__ = __add__

    def __rmatmul__(self, matrix: ArrayLike) -> Zonotope:
        """``M @ Z`` = ⟨Mc, MG⟩ for M (m, n) (eq. linmap)."""
        m = np.asarray(matrix, dtype=np.float64)
        if m.ndim != 2 or m.shape[1] != self.dim or m.shape[0] == 0:
            raise ValueError(f"linear map must have shape (m, {self.dim}); got {m.shape}")
        if not np.isfinite(m).all():
            raise ValueError("zonotope center and generators must be finite")
        return Zonotope.unchecked(matmul(m, self.center), matmul(m, self.generators))

    def translate(self, vector: ArrayLike) -> Zonotope:
        """⟨c + v, G⟩ for v (n,)."""
        v = np.asarray(vector, dtype=np.float64)
        if v.shape != (self.dim,):
            raise ValueError(f"translation must have shape ({self.dim},); got {v.shape}")
        if not np.isfinite(v).all():
            raise ValueError("zonotope center and generators must be finite")
        return Zonotope.unchecked(self.center + v, self.generators)

    def scale(self, factor: float) -> Zonotope:
        """L·Z = ⟨Lc, LG⟩ for a scalar L (eq. linmap)."""
        return Zonotope(factor * self.center, factor * self.generators)

    def interval_hull(self) -> tuple[FloatArray, FloatArray]:
        """Tightest axis-aligned box (lo, hi), each (n,): c ∓ Σ_i |g_i|."""
        radius = np.abs(self.generators).sum(axis=1)
        return self.center - radius, self.center + radius

    def support(self, direction: ArrayLike) -> float | FloatArray:
        """h_Z(d) = dᵀc + Σ_i |dᵀg_i|; d (n,) -> float, d (k, n) -> (k,)."""
        d = np.asarray(direction, dtype=np.float64)
        values = matmul(d, self.center) + np.abs(matmul(d, self.generators)).sum(axis=-1)
        return float(values) if d.ndim == 1 else values

    def volume(self) -> float:
        """Exact n-D volume: 2ⁿ Σ over n-subsets S of generators of |det G_S| (computed once:
        the arrays are read-only)."""
        cached = self.__dict__.get("_volume")
        if cached is None:
            cached = generator_volume(self.generators)
            self.__dict__["_volume"] = cached
        return cached

    def vertices(self) -> FloatArray:
        """Vertices of a 2-D zonotope, counter-clockwise from the lowest one, shape (k, 2).

        Generators are folded into the upper half-plane, sorted by angle and parallel ones
        merged; then the boundary is the cumulative sum of 2g_i followed by -2g_i. A point gives
        one row, a segment two. Compiled (:func:`~sse_cosim.sets.kernels.vertices_2d`; its
        NumPy reference is :func:`vertices_2d_reference`).
        """
        if self.dim != 2:
            raise ValueError(f"vertices() needs a 2-D zonotope; this one is {self.dim}-D")
        return vertices_2d(self.center, self.generators)

    def contains(self, point: ArrayLike, tol: float = 1e-9) -> bool | BoolArray:
        """Whether x (n,) lies in Z, or per row of x (k, n), with absolute slack ``tol``.

        Full-rank 2-D: exact half-space test |nᵀ(x - c)| <= Σ_i |nᵀg_i| + tol over the unit facet
        normals n. Otherwise an LP (HiGHS): ∃ β ∈ [-1, 1]^e, |δ|∞ <= tol with Gβ = x - c + δ.
        """
        x = np.asarray(point, dtype=np.float64)
        points = np.atleast_2d(x)
        if points.shape[1] != self.dim:
            raise ValueError(f"points must have {self.dim} coordinates; got shape {x.shape}")
        g = self.generators
        if self.dim == 2 and full_rank_2d(g):  # compiled (reference: contains_2d_reference)
            inside = contains_2d(self.center, g, np.ascontiguousarray(points), tol)
        else:
            inside = np.array([self._contains_lp(p, tol) for p in points], dtype=bool)
        return bool(inside[0]) if x.ndim == 1 else inside

    def _contains_lp(self, point: FloatArray, tol: float) -> bool:
        n, e = self.generators.shape
        offset = point - self.center
        scale = max(np.abs(self.generators).max(initial=0.0), np.abs(offset).max(), tol) or 1.0
        result = linprog(
            np.zeros(e + n),
            A_eq=np.hstack([self.generators, -np.eye(n)]) / scale,
            b_eq=offset / scale,
            bounds=[(-1.0, 1.0)] * e + [(-tol / scale, tol / scale)] * n,
            method="highs",
            options={"primal_feasibility_tolerance": 1e-10},
        )
        if result.status not in (0, 2):
            raise RuntimeError(f"containment LP failed: {result.message}")
        return result.status == 0

    def remove_zero_generators(self) -> Zonotope:
        """The same set without all-zero generator columns (itself if it has none)."""
        keep = np.any(self.generators != 0, axis=0)
        if keep.all():
            return self
        return Zonotope.unchecked(self.center, self.generators[:, keep])

    def reduce(self, max_generators: int, method: str = "girard") -> Zonotope:
        """Sound reduction to at most ``max_generators`` (>= n) generators (see reduction.py)."""
        reducer = lookup(REDUCTION_METHODS, method, "reduction method")
        generators = reducer(self.generators, max_generators)
        if generators is self.generators:
            return self
        return Zonotope.unchecked(self.center, generators)

    def to_json(self) -> dict[str, list[Any]]:
        """``{"center": [n floats], "generators": n rows of e floats}`` (``G.tolist()``)."""
        return {"center": self.center.tolist(), "generators": self.generators.tolist()}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Zonotope:
        """Inverse of :meth:`to_json`."""
        missing = {"center", "generators"} - set(data)
        if missing:
            raise ValueError(f"zonotope JSON lacks {sorted(missing)}")
        return cls(np.asarray(data["center"]), np.asarray(data["generators"]))

    @classmethod
    def from_interval(cls, lo: ArrayLike, hi: ArrayLike) -> Zonotope:
        """The box [lo, hi] (each (n,)) as ⟨(lo + hi)/2, diag((hi - lo)/2)⟩, zero widths dropped."""
        low, high = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
        if low.shape != high.shape or np.any(low > high):
            raise ValueError("interval needs lo and hi of the same shape with lo <= hi")
        return cls((low + high) / 2, np.diag((high - low) / 2)).remove_zero_generators()

"""Measurement strips S = {x : |Hx - y| <= r} row-wise (paper eq. strip)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from sse_cosim.sets import portable
from sse_cosim.sets.kernels import unit_strips
from sse_cosim.sets.zonotope import BoolArray, FloatArray, Zonotope, facet_normals, full_rank


def _read_only(values: FloatArray) -> FloatArray:
    values.setflags(write=False)
    return values


@dataclass(frozen=True, eq=False)
class Strips:
    """m strips {x : |h_jᵀx - y_j| <= r_j}: ``normals`` H (m, n), ``values`` y, ``radii`` r (m,).

    Radii must be > 0 and normals nonzero; m may be 0 (no constraint). A single strip may be
    given as a normal of shape (n,) with scalar value and radius.
    """

    normals: FloatArray
    values: FloatArray
    radii: FloatArray

    @classmethod
    def unchecked(cls, normals: FloatArray, values: FloatArray, radii: FloatArray) -> Strips:
        """Strips from float64 arrays (m, n), (m,), (m,) that this library derived from
        validated strips or sets (finite, radii > 0, nonzero normals): no copy, no checks."""
        strips = object.__new__(cls)
        for name, array in (("normals", normals), ("values", values), ("radii", radii)):
            array.setflags(write=False)
            object.__setattr__(strips, name, array)
        return strips

    @classmethod
    def rows(cls, normals: ArrayLike, values: ArrayLike, radii: ArrayLike) -> list[Strips]:
        """k strip sets sharing H (m, n) and r (m,), one per row of ``values`` (k, m): what k
        calls of the constructor give, with H and r validated once."""
        shared = cls(normals, np.zeros(np.atleast_2d(normals).shape[0]), radii)
        rows = np.array(values, dtype=np.float64)
        if rows.ndim != 2 or rows.shape[1] != len(shared):
            raise ValueError(f"strip values need shape (k, {len(shared)}); got {rows.shape}")
        if not np.isfinite(rows).all():
            raise ValueError("strip normals, values and radii must be finite")
        return [cls.unchecked(shared.normals, row, shared.radii) for row in rows]

    def __post_init__(self) -> None:
        normals = np.atleast_2d(np.array(self.normals, dtype=np.float64))
        values = np.atleast_1d(np.array(self.values, dtype=np.float64))
        radii = np.atleast_1d(np.array(self.radii, dtype=np.float64))
        m = normals.shape[0]
        if normals.ndim != 2 or values.shape != (m,) or radii.shape != (m,):
            raise ValueError(
                f"strips need normals (m, n), values (m,) and radii (m,); got "
                f"{normals.shape}, {values.shape}, {radii.shape}"
            )
        if not (np.isfinite(normals).all() and np.isfinite(values).all()
                and np.isfinite(radii).all()):
            raise ValueError("strip normals, values and radii must be finite")
        if (radii <= 0).any():
            raise ValueError(f"strip radii must be > 0 (bounded noise r > 0); got {radii.tolist()}")
        if not normals.any(axis=1).all():
            raise ValueError("strip normals must be nonzero")
        object.__setattr__(self, "normals", _read_only(normals))
        object.__setattr__(self, "values", _read_only(values))
        object.__setattr__(self, "radii", _read_only(radii))

    @property
    def dim(self) -> int:
        """Dimension n of the space the strips live in."""
        return self.normals.shape[1]

    def __len__(self) -> int:
        return self.normals.shape[0]

    def contains(self, point: ArrayLike, tol: float = 1e-9) -> bool | BoolArray:
        """Whether x (n,) satisfies every strip, |Hx - y| <= r + tol, or per row of x (k, n)."""
        x = np.asarray(point, dtype=np.float64)
        residual = np.abs(portable.matmul(np.atleast_2d(x), self.normals.T) - self.values)
        inside = (residual <= self.radii + tol).all(axis=1)
        return bool(inside[0]) if x.ndim == 1 else inside

    def pullback(self, output_map: ArrayLike) -> Strips:
        """Strips in state space from strips in output space z = Cx: normals H @ C, C (p, n)."""
        c = np.asarray(output_map, dtype=np.float64)
        if c.ndim != 2 or c.shape[0] != self.dim:
            raise ValueError(f"output map must have shape ({self.dim}, n); got {c.shape}")
        normals = portable.matmul(self.normals, c)
        if not np.isfinite(normals).all() or not np.any(normals != 0, axis=1).all():
            raise ValueError("strip normals must be finite and nonzero")
        return Strips.unchecked(normals, self.values, self.radii)

    def select(self, mask: ArrayLike) -> Strips:
        """The strips picked by a boolean mask (m,) or an index array."""
        index = np.asarray(mask)
        normals = self.normals[index].reshape(-1, self.dim)
        return Strips.unchecked(
            normals, self.values[index].reshape(-1), self.radii[index].reshape(-1)
        )

    def normalized(self) -> Strips:
        """The same sets with unit normals (rows divided by ‖h_j‖), by the compiled
        :func:`~sse_cosim.sets.kernels.unit_strips` (NumPy reference
        :meth:`normalized_reference`)."""
        already, normals, values, radii = unit_strips(self.normals, self.values, self.radii)
        return self if already else Strips.unchecked(normals, values, radii)

    def normalized_reference(self) -> Strips:
        """:meth:`normalized` in NumPy."""
        norms = np.sqrt((self.normals * self.normals).sum(axis=1))
        if (norms == 1.0).all():
            return self
        return Strips.unchecked(
            self.normals / norms[:, None], self.values / norms, self.radii / norms
        )

    @staticmethod
    def stack(strips: Sequence[Strips]) -> Strips:
        """All strips of a non-empty list, in order."""
        if not strips:
            raise ValueError("cannot stack an empty list of strips")
        if len(strips) == 1:
            return strips[0]
        return Strips.unchecked(
            np.vstack([s.normals for s in strips]),
            np.concatenate([s.values for s in strips]),
            np.concatenate([s.radii for s in strips]),
        )


def zonotope_facet_strips(zonotope: Zonotope) -> Strips:
    """Z as the intersection of strips, one per facet-normal direction (unit normals).

    Normals are the cofactor vectors of the (n-1)-subsets of generators (2-D: g_i rotated by
    90°), zero ones skipped, parallel ones merged; value nᵀc, radius Σ_j |nᵀg_j|. Exact (equal to
    Z) when G has full rank; a rank-deficient Z has no full-dimensional facet and gives no strip.
    """
    g = zonotope.generators
    if not full_rank(g):
        return Strips.unchecked(np.zeros((0, zonotope.dim)), np.zeros(0), np.zeros(0))
    normals = facet_normals(g)
    return Strips.unchecked(normals, portable.matmul(normals, zonotope.center),
                            np.abs(portable.matmul(normals, g)).sum(axis=1))


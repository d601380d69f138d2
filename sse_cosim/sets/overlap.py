"""Whether sets meet: zonotope-strip and zonotope-zonotope tests, and a common point of many
zonotopes (an LP).

Exact tests, the basis of sensor-failure detection: sets that each hold the pedestrian always
meet, so disjoint sets prove a fault (paper Section III, "Robust Decision Making", Fig. 4;
:mod:`sse_cosim.estimation.vote`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from sse_cosim.sets import portable
from sse_cosim.sets.kernels import meet_2d
from sse_cosim.sets.lp import linprog
from sse_cosim.sets.strips import Strips
from sse_cosim.sets.zonotope import BoolArray, FloatArray, Zonotope


def projection_interval(zonotope: Zonotope, strips: Strips) -> tuple[FloatArray, FloatArray]:
    """[min, max] of h_jᵀx over Z for every strip normal: h_jᵀc ∓ Σ_i |h_jᵀg_i|, each (m,)."""
    center = portable.matmul(strips.normals, zonotope.center)
    radius = np.abs(portable.matmul(strips.normals, zonotope.generators)).sum(axis=1)
    return center - radius, center + radius


def strip_disjoint(zonotope: Zonotope, strips: Strips, tol: float = 1e-9) -> BoolArray:
    """Per strip (m,): whether Z ∩ S_j = ∅, i.e. the projection interval of Z misses
    [y_j - r_j, y_j + r_j] by more than ``tol`` (in the units of y)."""
    lo, hi = projection_interval(zonotope, strips)
    return (hi < strips.values - strips.radii - tol) | (lo > strips.values + strips.radii + tol)


def strip_covers(zonotope: Zonotope, strips: Strips) -> BoolArray:
    """Per strip (m,): whether Z ⊆ S_j (the strip carries no information about Z)."""
    lo, hi = projection_interval(zonotope, strips)
    return (lo >= strips.values - strips.radii) & (hi <= strips.values + strips.radii)


def zonotopes_disjoint(first: Zonotope, second: Zonotope, tol: float = 1e-9) -> bool:
    """Whether Z1 ∩ Z2 = ∅, exactly: they meet iff c1 - c2 ∈ ⟨0, [G1, -G2]⟩ (``tol`` a distance).

    2-D in one compiled call (:func:`~sse_cosim.sets.kernels.meet_2d`) unless [G1, -G2] is
    rank-deficient; otherwise, and as its reference, :func:`zonotopes_disjoint_reference`.
    """
    if first.dim == 2 and second.dim == 2:
        meets = meet_2d(first.center, first.generators, second.center, second.generators, tol)
        if meets >= 0:
            return meets == 0
    return zonotopes_disjoint_reference(first, second, tol)


def zonotopes_disjoint_reference(first: Zonotope, second: Zonotope, tol: float = 1e-9) -> bool:
    """:func:`zonotopes_disjoint` in NumPy, any dimension: ``Zonotope.contains`` on the
    difference ⟨0, [G1, -G2]⟩ (an LP when it is not full-rank 2-D)."""
    difference = Zonotope.unchecked(  # (from two valid zonotopes: nothing to check)
        np.zeros(first.dim), np.hstack([first.generators, -second.generators])
    )
    return not difference.contains(first.center - second.center, tol)


def have_common_point(sets: Sequence[Zonotope], tol: float = 1e-9) -> bool:
    """Whether the zonotopes (same dimension) share a point, up to ``tol`` (a distance).

    Two sets: the exact test of :func:`zonotopes_disjoint`. More: the LP
    min t s.t. |c_i + G_i b_i - x|_inf <= t, |b_i|_inf <= 1, and t <= tol.
    """
    if len(sets) <= 1:
        return True
    if len(sets) == 2:
        return not zonotopes_disjoint(sets[0], sets[1], tol)
    if _has_witness(sets, tol):
        return True
    dim = sets[0].dim
    origin = np.mean([z.center for z in sets], axis=0)  # conditioning: work near zero
    sizes = [z.n_generators for z in sets]
    n_vars = dim + sum(sizes) + 1  # x, every b_i, t
    rows, rhs = [], []
    offset = dim
    for z, size in zip(sets, sizes, strict=True):
        block = np.zeros((dim, n_vars))
        block[:, :dim] = -np.eye(dim)
        block[:, offset:offset + size] = z.generators
        offset += size
        for sign in (1.0, -1.0):  # ±(c + G b - x) <= t
            part = sign * block
            part[:, -1] = -1.0
            rows.append(part)
            rhs.append(-sign * (z.center - origin))
    cost = np.zeros(n_vars)
    cost[-1] = 1.0
    bounds = [(None, None)] * dim + [(-1.0, 1.0)] * sum(sizes) + [(0.0, None)]
    result = linprog(cost, A_ub=np.vstack(rows), b_ub=np.concatenate(rhs), bounds=bounds,
                     method="highs")
    if result.status != 0:
        raise RuntimeError(f"common-point LP failed: {result.message}")
    return bool(result.fun <= tol)


def _has_witness(sets: Sequence[Zonotope], tol: float) -> bool:
    """Whether a cheap candidate (a centre, or the mean of the centres) lies in every set:
    a common point found without the LP."""
    centers = [z.center for z in sets]
    for candidate in [*centers, np.mean(centers, axis=0)]:
        if all(z.contains(candidate, tol) for z in sets):
            return True
    return False

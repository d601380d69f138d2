"""Exact consistency tests between zonotopes and strips (sensor-failure detection)."""

from __future__ import annotations

import numpy as np

from sse_cosim.sets.strips import Strips
from sse_cosim.sets.zonotope import BoolArray, FloatArray, Zonotope


def projection_interval(zonotope: Zonotope, strips: Strips) -> tuple[FloatArray, FloatArray]:
    """[min, max] of h_jᵀx over Z for every strip normal: h_jᵀc ∓ Σ_i |h_jᵀg_i|, each (m,)."""
    center = strips.normals @ zonotope.center
    radius = np.abs(strips.normals @ zonotope.generators).sum(axis=1)
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
    """Whether Z1 ∩ Z2 = ∅, exactly: they meet iff c1 - c2 ∈ ⟨0, [G1, -G2]⟩ (``tol`` a distance)."""
    difference = Zonotope(
        np.zeros(first.dim), np.hstack([first.generators, -second.generators])
    )
    return not difference.contains(first.center - second.center, tol)

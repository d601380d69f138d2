"""Proposition 2: fusion (intersection) of several zonotope estimates (eqs. cdiff, gdiff).

:func:`fuse_with_weights` implements the equations for given weights; the ``frobenius`` and
``volume`` methods only choose the weights. The ``strips`` method instead cuts the smallest
input with the facet strips of the others through Prop. 1. The ``enclose`` method (2-D)
intersects the inputs exactly as a convex polygon and encloses it in a zonotope along the
inputs' generator directions (:mod:`sse_cosim.sets.enclosure`). These two are the only
methods that can return a set smaller than every input (see :func:`volume_weights`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import ArrayLike

from sse_cosim.sets import enclosure_kernels
from sse_cosim.sets._registry import lookup
from sse_cosim.sets.enclosure import enclose_intersection_reference
from sse_cosim.sets.gains import intersect_strips
from sse_cosim.sets.kernels import full_rank_2d
from sse_cosim.sets.overlap import projection_interval, strip_covers
from sse_cosim.sets.strips import Strips, zonotope_facet_strips
from sse_cosim.sets.zonotope import FloatArray, Zonotope, full_rank

FusionMethod = Callable[[Sequence[Zonotope]], Zonotope]
WeightChooser = Callable[[Sequence[Zonotope]], FloatArray]


EXACT_SIZE_GENERATORS = 16
"""An n-D input (n >= 3) with more generators than this is sized by the volume of its Girard
reduction to this many, an enclosure (so an upper bound of its volume): the exact volume sums
C(e, n) determinants (in 4-D, e = 68: 814,385 of them, 80 ms), and a shared estimate that has
aged k steps is predicted with two generators more a step. Which input is chosen never
affects soundness: each contains the truth."""


def _size(zonotope: Zonotope) -> float:
    """The input's volume (2-D, or at most :data:`EXACT_SIZE_GENERATORS` generators), else the
    volume of its reduction to that many generators."""
    if zonotope.dim == 2 or zonotope.n_generators <= EXACT_SIZE_GENERATORS:
        return zonotope.volume()
    return zonotope.reduce(EXACT_SIZE_GENERATORS).volume()


def _smallest(zonotopes: Sequence[Zonotope]) -> int:
    """Index of the input with the least :func:`_size` (first on ties)."""
    return int(np.argmin([_size(z) for z in zonotopes]))


def fuse_with_weights(zonotopes: Sequence[Zonotope], weights: ArrayLike) -> Zonotope:
    """⟨ĉ, Ĝ⟩ ⊇ ∩_j Z_j with ĉ = Σ w_j c_j / Σ w (eq. cdiff), Ĝ = [w_1 G_1, ...] / Σ w (eq. gdiff).

    Sound for any weights with Σ w ≠ 0: x ∈ ∩ Z_j means x = c_j + G_j β_j for every j, so
    (Σ w) x = Σ w_j c_j + Σ w_j G_j β_j, i.e. x = ĉ + Ĝ [β_1; ...; β_m] with |β|∞ <= 1.
    Zero-weight inputs contribute no generators.
    """
    w = np.asarray(weights, dtype=np.float64)
    if w.shape != (len(zonotopes),):
        raise ValueError(f"need one weight per zonotope ({len(zonotopes)}); got shape {w.shape}")
    total = w.sum()
    if total == 0:
        raise ValueError("fusion weights must not sum to zero (Prop. 2)")
    center = sum(wj * z.center for wj, z in zip(w, zonotopes, strict=True)) / total
    generators = np.hstack([wj * z.generators for wj, z in zip(w, zonotopes, strict=True)]) / total
    if not (np.isfinite(center).all() and np.isfinite(generators).all()):
        raise ValueError("zonotope center and generators must be finite")
    return Zonotope.unchecked(center, generators).remove_zero_generators()


def frobenius_weights(zonotopes: Sequence[Zonotope]) -> FloatArray:
    """w_j ∝ 1/‖G_j‖_F², the minimizer of ‖Ĝ‖_F² on the simplex; a point input gets all weight."""
    norms = np.array([np.sum(z.generators**2) for z in zonotopes])
    if np.any(norms == 0):
        return np.eye(len(zonotopes))[int(np.argmin(norms))]
    return (1.0 / norms) / np.sum(1.0 / norms)


def volume_weights(zonotopes: Sequence[Zonotope]) -> FloatArray:
    """One-hot on the smallest-volume input: the exact minimizer of the fused volume over ALL
    weights with Σ w ≠ 0 (so never larger than the smallest input, unlike the paper's example;
    an n-D input of more than :data:`EXACT_SIZE_GENERATORS` generators is sized by an upper
    bound, :func:`_size`).

    With Σ w = 1 the fused set is ĉ + Σ_j |w_j| ⟨0, G_j⟩, so Brunn-Minkowski gives
    vol^(1/n) >= Σ_j |w_j| vol(Z_j)^(1/n) >= min_j vol(Z_j)^(1/n), as Σ_j |w_j| >= 1.
    """
    return np.eye(len(zonotopes))[_smallest(zonotopes)]


def _weighted(choose: WeightChooser) -> FusionMethod:
    def fuse_weighted(zonotopes: Sequence[Zonotope]) -> Zonotope:
        return fuse_with_weights(zonotopes, choose(zonotopes))

    return fuse_weighted


def strips_fusion(zonotopes: Sequence[Zonotope]) -> Zonotope:
    """The smallest-volume input cut by the facet strips of every other input (Prop. 1,
    ``volume`` gain); strips that already cover it are skipped. Sound because each Z_j lies in
    its facet strips; never larger than the smallest input."""
    index = _smallest(zonotopes)
    base = zonotopes[index]
    facets = [zonotope_facet_strips(z) for j, z in enumerate(zonotopes) if j != index]
    cutting = Strips.stack([s.select(~strip_covers(base, s)) for s in facets]).normalized()
    if len(cutting) == 0:
        return base
    lo, hi = projection_interval(base, cutting)
    tightest_first = np.argsort(cutting.radii / (hi - lo), kind="stable")
    return intersect_strips(base, cutting.select(tightest_first), method="volume")


def enclose_fusion(zonotopes: Sequence[Zonotope]) -> Zonotope:
    """2-D: ∩_j Z_j exactly as a convex polygon P (the smallest input clipped by the facet
    strips of the others), enclosed in a zonotope along the generator directions of all inputs
    (the directions of P's edges); the smaller in area of that and the smallest input.

    Sound: P is the exact intersection and the enclosure contains it (checked with a margin,
    :func:`enclosure.enclose_polygon`); the smallest input contains it too. Falls back to the
    smallest input (``volume`` fusion) when n != 2, when an input is not full-dimensional (it
    is then the smallest: volume 0), when the inputs share no point (inconsistent sources,
    which :mod:`sse_cosim.sets.overlap` detects; any set is sound), or when no
    enclosure is accepted. The clipping and the enclosure run compiled
    (:func:`~sse_cosim.sets.enclosure_kernels.enclose_fusion`).
    """
    index = _smallest(zonotopes)
    base = zonotopes[index]
    if base.dim != 2 or not all(full_rank_2d(z.generators) for z in zonotopes):
        return base
    starts = np.cumsum([0] + [z.n_generators for z in zonotopes])
    found, center, generators = enclosure_kernels.enclose_fusion(
        np.stack([z.center for z in zonotopes]), np.hstack([z.generators for z in zonotopes]),
        starts, index)
    if not found:
        return base
    enclosed = Zonotope.unchecked(center, generators)
    return enclosed if enclosed.volume() < base.volume() else base


def enclose_fusion_reference(zonotopes: Sequence[Zonotope]) -> Zonotope:
    """The NumPy reference of :func:`enclose_fusion`."""
    index = _smallest(zonotopes)
    base = zonotopes[index]
    if base.dim != 2 or not all(full_rank(z.generators) for z in zonotopes):
        return base
    others = Strips.stack([zonotope_facet_strips(z) for j, z in enumerate(zonotopes) if j != index])
    found = enclose_intersection_reference(base, others,
                                           np.hstack([z.generators for z in zonotopes]))
    if found is None:
        return base
    enclosed = found[0]
    return enclosed if enclosed.volume() < base.volume() else base


FUSION_METHODS: dict[str, FusionMethod] = {
    "frobenius": _weighted(frobenius_weights),
    "volume": _weighted(volume_weights),
    "strips": strips_fusion,
    "enclose": enclose_fusion,
}


def available_fusion_methods() -> tuple[str, ...]:
    """Names accepted by :func:`fuse`."""
    return tuple(FUSION_METHODS)


def fuse(zonotopes: Sequence[Zonotope], method: str = "frobenius") -> Zonotope:
    """Zonotope ⊇ ∩_j Z_j by ``method`` (see :data:`FUSION_METHODS`); one input comes back as is."""
    fusion = lookup(FUSION_METHODS, method, "fusion method")
    if not zonotopes:
        raise ValueError("fuse needs at least one zonotope")
    dims = sorted({z.dim for z in zonotopes})
    if len(dims) != 1:
        raise ValueError(f"cannot fuse zonotopes of dimensions {dims}")
    if len(zonotopes) == 1:
        return zonotopes[0]
    return fusion(list(zonotopes))

"""Proposition 1: zonotope ∩ strips over-approximated by a zonotope (eqs. C_lambda, G_lambda).

:func:`apply_gain` is the update for a given gain Λ = [λ_1, ..., λ_m] (n, m):

    c' = c + Λ(y - Hc)                      (eq. C_lambda)
    G' = [(I - ΛH)G, Λ diag(r)]             (eq. G_lambda)

It is sound for ANY Λ: if x = c + Gβ ∈ Z and y - Hx = diag(r)δ with |δ|∞ <= 1, then
x = c' + (I - ΛH)Gβ - Λ diag(r)δ ∈ ⟨c', G'⟩. Every method in :data:`GAIN_METHODS` therefore
only chooses Λ.

:data:`CORRECTION_METHODS` holds every method :func:`intersect_strips` accepts: each gain of
:data:`GAIN_METHODS` applied by :func:`apply_gain`, and ``enclose`` (:func:`enclose_correction`),
which is not a gain: in 2-D it intersects exactly (a convex polygon) and encloses the polygon
in a zonotope (:mod:`sse_cosim.sets.enclosure`), keeping the ``volume`` result where that is
smaller.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from sse_cosim.sets import enclosure_kernels, kernels, volume_gain_kernels
from sse_cosim.sets._registry import lookup
from sse_cosim.sets.enclosure import enclose_intersection_reference, smaller_enclosure
from sse_cosim.sets.overlap import strip_covers
from sse_cosim.sets.strips import Strips
from sse_cosim.sets.zonotope import (
    FloatArray,
    Zonotope,
    cofactor_vectors,
    full_rank,
    generator_volume,
)

if TYPE_CHECKING:  # cvxpy loads on first use: runs with closed-form gains skip its ~1 s import
    import cvxpy as cp

GainMethod = Callable[[Zonotope, Strips], FloatArray]
"""Chooses Λ (n, m) for Z and m strips with unit normals."""

CorrectionMethod = Callable[[Zonotope, Strips], Zonotope]
"""Encloses Z ∩ S_1 ∩ ... ∩ S_m (Z with generators) in a zonotope; each method rescales the
strips to unit normals first (:meth:`Strips.normalized`, or the same inside a kernel)."""

StripGain = Callable[[FloatArray, FloatArray, float], FloatArray]
"""Chooses λ (n,) for generators G (n, e) of a full-rank zonotope and one strip (h, r)."""


@dataclass(frozen=True)
class CompiledProblem:
    """A parametrized DPP problem, its decision variable of interest and its parameters."""

    problem: cp.Problem
    variable: cp.Variable
    parameters: dict[str, cp.Parameter]


PROBLEM_CACHE: dict[tuple[str | int, ...], CompiledProblem] = {}
"""DPP problems built once per (kind, shape...) and re-solved with new parameter values."""


def updated_generators(generators: FloatArray, strips: Strips, gain: FloatArray) -> FloatArray:
    """G' = [(I - ΛH)G, Λ diag(r)] (eq. G_lambda); G (n, e), Λ (n, m) -> (n, e + m)."""
    return np.hstack([generators - gain @ (strips.normals @ generators), gain * strips.radii])


def apply_gain(zonotope: Zonotope, strips: Strips, gain: ArrayLike) -> Zonotope:
    """Prop. 1 update for a given gain Λ (n, m) (eqs. C_lambda, G_lambda), zero columns dropped."""
    lam = np.asarray(gain, dtype=np.float64)
    if lam.shape != (zonotope.dim, len(strips)):
        raise ValueError(f"gain must have shape {(zonotope.dim, len(strips))}; got {lam.shape}")
    if not np.isfinite(lam).all():
        raise ValueError("gain must be finite")
    center = zonotope.center + lam @ (strips.values - strips.normals @ zonotope.center)
    generators = updated_generators(zonotope.generators, strips, lam)
    if not (np.isfinite(center).all() and np.isfinite(generators).all()):
        raise ValueError("zonotope center and generators must be finite")
    return Zonotope.unchecked(center, generators).remove_zero_generators()


def frobenius_gain(zonotope: Zonotope, strips: Strips) -> FloatArray:
    """Λ = P Hᵀ (H P Hᵀ + diag(r²))⁻¹ with P = GGᵀ, the minimizer of ‖G'‖_F², shape (n, m),
    by the compiled :func:`~sse_cosim.sets.kernels.frobenius_gain` (Householder QR of the
    least-squares problem of :func:`frobenius_gain_reference`)."""
    return kernels.frobenius_gain(zonotope.generators, strips.normals, strips.radii)


def frobenius_intersection(zonotope: Zonotope, strips: Strips) -> Zonotope:
    """Prop. 1 with the Frobenius gain in one compiled call
    (:func:`~sse_cosim.sets.kernels.intersect_frobenius`); equals :func:`apply_gain` with
    :func:`frobenius_gain` up to rounding."""
    return _kernel_result(kernels.intersect_frobenius, zonotope, strips)


def _kernel_result(kernel: Callable[..., tuple[FloatArray, FloatArray]], zonotope: Zonotope,
                 strips: Strips) -> Zonotope:
    """The zonotope (c', G') that the compiled ``kernel`` makes from Z's c and G and the
    strips' H, y and r."""
    return Zonotope.unchecked(*kernel(zonotope.center, zonotope.generators, strips.normals,
                                      strips.values, strips.radii))


def frobenius_gain_reference(zonotope: Zonotope, strips: Strips) -> FloatArray:
    """:func:`frobenius_gain` in NumPy, the reference of the compiled kernel.

    Solved as the equivalent least-squares problem Λ [HG, diag(r)] ≈ [G, 0] (no inverse and
    no squared condition number).
    """
    g, h, r = zonotope.generators, strips.normals, strips.radii
    lhs = np.hstack([h @ g, np.diag(r)])
    rhs = np.hstack([g, np.zeros((g.shape[0], len(r)))])
    return np.linalg.lstsq(lhs.T, rhs.T, rcond=None)[0].T


def _compiled(key: tuple[str | int, ...], build: Callable[..., CompiledProblem]) -> CompiledProblem:
    if key not in PROBLEM_CACHE:
        PROBLEM_CACHE[key] = build(*key[1:])
    return PROBLEM_CACHE[key]


def _solve(compiled: CompiledProblem, solver: str, **values: object) -> FloatArray | None:
    """Set the parameters, re-solve (no warm start: results never depend on call history) and
    return the variable's value, or None unless the solver reports an optimum."""
    for name, value in values.items():
        compiled.parameters[name].value = value
    import cvxpy as cp

    try:
        compiled.problem.solve(solver=solver, warm_start=False)
    except cp.error.SolverError:
        return None
    if compiled.problem.status != cp.OPTIMAL:
        return None
    return np.asarray(compiled.variable.value, dtype=np.float64)


def _build_frobenius(n: int, m: int, e: int) -> CompiledProblem:
    import cvxpy as cp

    gain = cp.Variable((n, m))
    g, hg, r = cp.Parameter((n, e)), cp.Parameter((m, e)), cp.Parameter((m, m))
    objective = cp.sum_squares(g - gain @ hg) + cp.sum_squares(gain @ r)
    return CompiledProblem(cp.Problem(cp.Minimize(objective)), gain, {"g": g, "hg": hg, "r": r})


def cvxpy_frobenius_gain(zonotope: Zonotope, strips: Strips) -> FloatArray:
    """The ``frobenius`` gain from cvxpy: min ‖G - Λ(HG)‖_F² + ‖Λ diag(r)‖_F² (cached DPP)."""
    g = zonotope.generators
    scale = max(np.abs(g).max(), strips.radii.max())
    n, e = g.shape
    compiled = _compiled(("frobenius", n, len(strips), e), _build_frobenius)
    gain = _solve(
        compiled,
        "CLARABEL",
        g=g / scale,
        hg=strips.normals @ g / scale,
        r=np.diag(strips.radii / scale),
    )
    if gain is None:
        raise RuntimeError(f"cvxpy-frobenius: solver status {compiled.problem.status}")
    return gain


def _piecewise_volume(base: float, cofactors: FloatArray, normal: FloatArray, radius: float,
                      lams: FloatArray) -> FloatArray:
    return base * np.abs(1.0 - lams @ normal) + radius * np.abs(lams @ cofactors.T).sum(axis=1)


def strip_gain_volume(generators: FloatArray, normal: FloatArray, radius: float,
                      gains: ArrayLike) -> FloatArray:
    """vol(⟨·, [(I - λhᵀ)G, rλ]⟩)/2ⁿ for each row λ of ``gains`` (k, n), shape (k,).

    Equals |1 - hᵀλ|·V + r·Σ_S |d_Sᵀλ| with V = vol(⟨·, G⟩)/2ⁿ and d_S the cofactor vector of
    each (n-1)-subset S of G's columns: convex and piecewise linear in λ.
    """
    lams = np.atleast_2d(np.asarray(gains, dtype=np.float64))
    base = generator_volume(generators) / 2.0 ** generators.shape[0]
    return _piecewise_volume(base, cofactor_vectors(generators), normal, radius, lams)


def volume_gain_vertices(generators: FloatArray, normal: FloatArray, radius: float) -> FloatArray:
    """Exact 2-D minimizer of :func:`strip_gain_volume`: the best vertex of the arrangement of
    the lines hᵀλ = 1 and d_iᵀλ = 0, i.e. λ = 0 or λ = g_i / (hᵀg_i).

    All candidates are scored at once in closed form: d_iᵀλ = g_i × λ (2-D cross product) and
    V = Σ_{i<j} |g_i × g_j|; the same values as :func:`strip_gain_volume`. Compiled
    (:func:`~sse_cosim.sets.kernels.volume_gain_2d`; NumPy reference
    :func:`volume_gain_vertices_reference`).
    """
    return kernels.volume_gain_2d(np.ascontiguousarray(generators, dtype=np.float64),
                                  np.ascontiguousarray(normal, dtype=np.float64), float(radius))


def volume_gain_vertices_reference(generators: FloatArray, normal: FloatArray,
                                   radius: float) -> FloatArray:
    """The NumPy reference of :func:`volume_gain_vertices`."""
    g0, g1 = generators[0], generators[1]
    hg = normal[0] * g0 + normal[1] * g1
    usable = np.abs(hg) > 1e-12 * np.sqrt(g0 * g0 + g1 * g1)
    cand0 = np.concatenate([[0.0], g0[usable] / hg[usable]])
    cand1 = np.concatenate([[0.0], g1[usable] / hg[usable]])
    nonzero = (g0 != 0) | (g1 != 0)
    a, b = g0[nonzero], g1[nonzero]
    base = 0.5 * np.abs(a[:, None] * b - b[:, None] * a).sum()  # vol / 2², as generator_volume
    cuts = np.abs(cand1[:, None] * g0 - cand0[:, None] * g1).sum(axis=1)  # Σ_i |g_i × λ|
    values = base * np.abs(1.0 - (cand0 * normal[0] + cand1 * normal[1])) + radius * cuts
    best = int(np.argmin(values))
    return np.array([cand0[best], cand1[best]])


def _build_volume_lp(n: int, k: int) -> CompiledProblem:
    import cvxpy as cp

    lam, t, s = cp.Variable(n), cp.Variable(), cp.Variable(k)
    h, d = cp.Parameter(n), cp.Parameter((k, n))
    base, radius = cp.Parameter(nonneg=True), cp.Parameter(nonneg=True)
    residual, cuts = 1 - h @ lam, d @ lam
    constraints = [residual <= t, -t <= residual, cuts <= s, -s <= cuts]
    problem = cp.Problem(cp.Minimize(base * t + radius * cp.sum(s)), constraints)
    return CompiledProblem(problem, lam, {"h": h, "d": d, "base": base, "radius": radius})


def volume_gain_lp(generators: FloatArray, normal: FloatArray, radius: float) -> FloatArray:
    """Minimizer of :func:`strip_gain_volume` by an LP (cvxpy, HiGHS), any dimension.

    min V·t + r·Σs s.t. |1 - hᵀλ| <= t, |Dλ| <= s. D is zero-padded to a power-of-two row
    count so few problem shapes are compiled. Falls back to λ = 0 if the solver fails or its
    λ is (by tolerance) worse than λ = 0.
    """
    n = generators.shape[0]
    scale = np.abs(generators).max()
    d = cofactor_vectors(generators / scale)
    base = generator_volume(generators / scale) / 2.0**n
    rows = max(8, 1 << (len(d) - 1).bit_length())
    compiled = _compiled(("volume", n, rows), _build_volume_lp)
    padded = np.vstack([d, np.zeros((rows - len(d), n))])
    lam = _solve(compiled, "HIGHS", h=normal, d=padded, base=base, radius=radius / scale)
    zero = np.zeros(n)
    if lam is None:
        return zero
    values = _piecewise_volume(base, d, normal, radius / scale, np.vstack([lam, zero]))
    return lam if values[0] <= values[1] else zero


def volume_gain_simplex(generators: FloatArray, normal: FloatArray, radius: float) -> FloatArray:
    """Exact minimizer of :func:`strip_gain_volume` for G (n, e), n >= 3, h (n,) and r, shape
    (n,), compiled (:func:`~sse_cosim.sets.volume_gain_kernels.volume_gain_nd`; reference
    :func:`volume_gain_lp`, the same minimum up to rounding).

    min f = min(V, r·m), m the least Σ_S |d_Sᵀμ| on the plane hᵀμ = 1, so λ is 0 or that μ,
    which a simplex method for weighted L1 problems finds at a vertex of the arrangement of
    the planes d_Sᵀμ = 0 with an optimality certificate. Where it certifies nothing (G of
    rank < n, where λ = 0 is optimal, or rounding trouble) its last vertex is kept if it beats
    λ = 0, else λ = 0 (always sound).
    """
    return volume_gain_kernels.volume_gain_nd(
        np.ascontiguousarray(generators, dtype=np.float64),
        np.ascontiguousarray(normal, dtype=np.float64), float(radius))


def _volume_gain_fast(generators: FloatArray, normal: FloatArray, radius: float) -> FloatArray:
    if generators.shape[0] == 2:
        return volume_gain_vertices(generators, normal, radius)
    return volume_gain_simplex(generators, normal, radius)


def _sequential(choose: StripGain) -> GainMethod:
    """Apply the strips one after another, λ_j by ``choose`` on the current set, and return the
    equivalent joint gain: after step j, Λ <- [(I - λ_j h_jᵀ)Λ, λ_j].

    A strip that covers the current set gets λ = 0 (optimal: nothing to cut); a rank-deficient
    current set (volume 0 for every λ) gets the one-strip ``frobenius`` gain.
    """

    def gain(zonotope: Zonotope, strips: Strips) -> FloatArray:
        # Plain arrays throughout: the same arithmetic as strip_covers, frobenius_gain and
        # apply_gain on one strip, without building a Strips and a Zonotope per strip.
        n = zonotope.dim
        total = np.zeros((n, len(strips)))
        center, g = zonotope.center, zonotope.generators
        for j in range(len(strips)):
            normal, value, radius = strips.normals[j], strips.values[j], float(strips.radii[j])
            hg = normal @ g
            mid, half = normal @ center, np.abs(hg).sum()
            if mid - half >= value - radius and mid + half <= value + radius:
                continue  # the strip covers the current set: λ = 0, nothing changes
            if not full_rank(g):
                # one-strip frobenius gain: λ = G (hG)ᵀ / (|hG|² + r²)
                lam = g @ hg / (hg @ hg + radius * radius)
            else:
                lam = choose(g, normal, radius)
            if not lam.any():
                continue
            total[:, :j] -= np.outer(lam, normal @ total[:, :j])
            total[:, j] = lam
            center = center + lam * (value - mid)
            g = np.hstack([g - np.outer(lam, hg), (lam * radius)[:, None]])
            g = g[:, np.any(g != 0, axis=0)]
        return total

    return gain


def _smallest_volume(*methods: GainMethod) -> GainMethod:
    """The candidate gain (of ``methods`` and Λ = 0) whose result has the least exact volume."""

    def gain(zonotope: Zonotope, strips: Strips) -> FloatArray:
        candidates = [method(zonotope, strips) for method in methods]
        volumes = [
            generator_volume(updated_generators(zonotope.generators, strips, lam))
            for lam in candidates
        ]
        volumes.append(zonotope.volume())  # Λ = 0: the update only adds zero columns
        candidates.append(np.zeros((zonotope.dim, len(strips))))
        return candidates[int(np.argmin(volumes))]

    return gain


GAIN_METHODS: dict[str, GainMethod] = {
    "frobenius": frobenius_gain,
    "cvxpy-frobenius": cvxpy_frobenius_gain,
    "volume": _smallest_volume(_sequential(_volume_gain_fast), frobenius_gain),
    "cvxpy-volume": _smallest_volume(_sequential(volume_gain_lp), frobenius_gain),
}


def _by_gain(choose: GainMethod) -> CorrectionMethod:
    def correct(zonotope: Zonotope, strips: Strips) -> Zonotope:
        return apply_gain(zonotope, strips, choose(zonotope, strips))

    return _normalized_first(correct)


def _normalized_first(correct: CorrectionMethod) -> CorrectionMethod:
    """``correct`` (for strips with unit normals) on the strips rescaled to unit normals."""

    def on_unit_strips(zonotope: Zonotope, strips: Strips) -> Zonotope:
        return correct(zonotope, strips.normalized())

    return on_unit_strips


def enclose_correction(zonotope: Zonotope, strips: Strips) -> Zonotope:
    """2-D: Z ∩ S exactly as a convex polygon P, enclosed in a zonotope along the directions of
    Z's generators and of the strips' edges (⊥ their normals), the directions of P's edges
    (:mod:`sse_cosim.sets.enclosure`); the smaller in area of that and the ``volume`` gain's
    result (both contain Z ∩ S). The ``volume`` gain is skipped when the enclosure's area is
    within :data:`~sse_cosim.sets.enclosure.EXACT_RTOL` of P's: nothing that holds P is smaller
    (so the result may exceed ``volume``'s, or Z's when the strips barely cut it, by that
    relative amount; strips that all cover Z return Z).

    Falls back to the ``volume`` result when n != 2, when Z is not full-dimensional, when
    Z ∩ S is empty (an inconsistent measurement: any set is sound, and
    :mod:`sse_cosim.sets.overlap` is where that is detected, as for the gains), or when
    no enclosure is found. ``strips`` may have normals of any length: in 2-D one compiled
    call rescales them and corrects (:func:`~sse_cosim.sets.enclosure_kernels.enclose_or_volume`).
    """
    if zonotope.dim != 2:
        return volume_correction(zonotope, strips.normalized())
    return _kernel_result(enclosure_kernels.enclose_or_volume, zonotope, strips)


def enclose_correction_reference(zonotope: Zonotope, strips: Strips) -> Zonotope:
    """The NumPy reference of :func:`enclose_correction`, for strips with unit normals
    (compiled in :func:`~sse_cosim.sets.enclosure_kernels.enclose_or_volume`)."""
    if zonotope.dim != 2 or not full_rank(zonotope.generators) \
            or strip_covers(zonotope, strips).all():
        return volume_correction_reference(zonotope, strips)
    edges = np.stack([-strips.normals[:, 1], strips.normals[:, 0]])
    found = enclose_intersection_reference(zonotope, strips,
                                           np.hstack([zonotope.generators, edges]))
    if found is None:
        return volume_correction_reference(zonotope, strips)
    return smaller_enclosure(*found, lambda: volume_correction_reference(zonotope, strips))


def volume_correction(zonotope: Zonotope, strips: Strips) -> Zonotope:
    """Z ∩ S (strips with unit normals) by Proposition 1 with the ``volume`` gain (also the
    ``enclose`` correction's fallback) in one compiled call: in 2-D
    :func:`~sse_cosim.sets.kernels.volume_correction_2d`, for n >= 3
    :func:`~sse_cosim.sets.volume_gain_kernels.volume_correction_nd`; 1-D by
    :func:`volume_correction_reference`."""
    if zonotope.dim == 2:
        return _kernel_result(kernels.volume_correction_2d, zonotope, strips)
    if zonotope.dim >= 3:
        return _kernel_result(volume_gain_kernels.volume_correction_nd, zonotope, strips)
    return volume_correction_reference(zonotope, strips)


def volume_correction_reference(zonotope: Zonotope, strips: Strips) -> Zonotope:
    """:func:`volume_correction` in NumPy: the ``volume`` gain applied by :func:`apply_gain`."""
    return apply_gain(zonotope, strips, GAIN_METHODS["volume"](zonotope, strips))


CORRECTION_METHODS: dict[str, CorrectionMethod] = {
    **{name: _by_gain(choose) for name, choose in GAIN_METHODS.items()},
    "frobenius": _normalized_first(frobenius_intersection),
    "volume": _normalized_first(volume_correction),
    "enclose": enclose_correction,  # rescales the strips inside its kernel
}


def available_gain_methods() -> tuple[str, ...]:
    """Names accepted by :func:`intersect_strips` (the scenario's ``estimator.gain_method``):
    the gains of :data:`GAIN_METHODS` and ``enclose``."""
    return tuple(CORRECTION_METHODS)


def intersect_strips(zonotope: Zonotope, strips: Strips, method: str = "frobenius") -> Zonotope:
    """Zonotope ⊇ Z ∩ S_1 ∩ ... ∩ S_m by Prop. 1 with the gain of ``method``, or by the exact
    2-D enclosure (``enclose``, :func:`enclose_correction`).

    Every method first rescales the strips to unit normals (same sets, same result up to
    rounding). A point Z (no generators) or no strips returns Z.
    """
    correct = lookup(CORRECTION_METHODS, method, "gain method")
    if strips.dim != zonotope.dim:
        raise ValueError(f"{strips.dim}-D strips cannot cut a {zonotope.dim}-D zonotope")
    if len(strips) == 0 or zonotope.n_generators == 0:
        return zonotope
    return correct(zonotope, strips)


def intersect_block_strips(zonotope: Zonotope, strips: Strips, first: int) -> Zonotope:
    """Zonotope ⊇ Z ∩ S for strips that bound the 2-D block of coordinates ``first``,
    ``first + 1`` alone (normals zero elsewhere), by Prop. 1 with a gain that is zero outside
    the block: the block's ``volume`` gain, in one compiled call
    (:func:`~sse_cosim.sets.kernels.block_volume_correction`). Z's set in every other
    coordinate is kept exactly. A gain on the whole state would buy a smaller volume by moving
    width out of the block into the others (a cut of the velocity that widens the position);
    Prop. 1 is sound for any gain, this one included. A point Z or no strips returns Z."""
    if strips.dim != zonotope.dim:
        raise ValueError(f"{strips.dim}-D strips cannot cut a {zonotope.dim}-D zonotope")
    if not 0 <= first <= zonotope.dim - 2:
        raise ValueError(f"no 2-D block starts at coordinate {first} of a {zonotope.dim}-D set")
    outside = np.delete(strips.normals, [first, first + 1], axis=1)
    if outside.any():
        raise ValueError("the strips' normals must be zero outside the block")
    if len(strips) == 0 or zonotope.n_generators == 0:
        return zonotope
    unit = strips.normalized()
    return Zonotope.unchecked(*kernels.block_volume_correction(
        zonotope.center, zonotope.generators, unit.normals, unit.values, unit.radii, first))

"""Compiled exact minimizer of the one-strip volume (``gains.strip_gain_volume``) in n >= 3
dimensions, on plain float64 arrays (numba, cached on disk like :mod:`~sse_cosim.sets.kernels`).

The function is f(λ) = V·|1 - hᵀλ| + r·Σ_S |d_Sᵀλ| (λ ∈ Rⁿ, V = vol(G)/2ⁿ, d_S the cofactor
vectors of the (n-1)-subsets of G's columns). With c = hᵀλ ≠ 0, f(λ) = V|1 - c| + r|c|·φ(λ/c)
with φ(μ) = Σ_S |d_Sᵀμ| and hᵀ(λ/c) = 1, so f(λ) >= V|1 - c| + r|c|·m, m = min {φ(μ) : hᵀμ = 1};
with c = 0, f(λ) = V + rφ(λ) >= V. The right-hand side is convex and piecewise linear in c with
its kinks at c = 0 and c = 1, so

    min f = min(V, r·m),  attained at λ = 0 or at a minimizer μ* of φ on the plane hᵀμ = 1.

:func:`plane_l1_minimizer` finds μ* by the simplex method for this weighted L1 problem (the
form of Barrodale and Roberts, 1973). A vertex of the arrangement of the hyperplanes
d_Sᵀμ = 0 within the plane is fixed by a basis B of n rows, hᵀ and n - 1 unit rows
d̂_S = d_S/w_S (w_S = ‖d_S‖), and the multipliers u of the basis rows solve
Bᵀu = -Σ_{S ∉ B} w_S s_S d̂_S, s_S the sign of d̂_Sᵀμ (kept from before for a row through the
vertex: any sign is a subgradient there). If |u_S| <= w_S for every basis row but hᵀ, then
0 ∈ ∂φ(μ) + span(h): μ is optimal, a certificate. Otherwise the basis row with the largest
|u_S| - w_S leaves along the edge where φ descends at rate w_S - |u_S| < 0, as far as it keeps
descending (the weighted median: each row crossed, its sign flipped, adds 2 w |d̂ᵀδ| to the
slope), and the row where it stops enters.

Many rows pass through one point (every d_S with S ∋ i vanishes at g_i/(hᵀg_i)), and at such
a vertex pivots may not move. So the method first solves a perturbed problem, the rows
shifted to d̂_Sᵀμ = ε ξ_S with distinct ξ_S (:func:`_offsets`), whose vertices are simple,
then goes on from its last basis on the problem itself, where that basis is optimal unless
the perturbation moved the optimum, and a few pivots finish. Pivots that do not move still
happen (rounding, rows parallel within ε); after n in a row the method follows Bland's rule
(the smallest row index leaves, and of the rows that block at once the smallest enters) until
one moves. In exact arithmetic that ends every run of such pivots (Bland 1977), and every
other pivot lowers the objective, so the method ends; a pivot budget bounds it under rounding.
It starts at μ = h/(hᵀh) with n - 1 coordinate placeholders in the basis (weight 0: they leave
first and never return).

:func:`volume_gain_nd` is the λ of ``gains.volume_gain_simplex``; its reference is the LP
``gains.volume_gain_lp`` (cvxpy, HiGHS), which ``tests/sets`` compares it with, and a brute
force over every vertex of the arrangement on small cases. :func:`cofactor_rows` is
``zonotope.cofactor_vectors`` (reference) for n >= 3 and :func:`generator_volume_nd` is
``zonotope.generator_volume`` for n >= 3 (reference ``generator_volume_reference``), each up
to rounding (cofactor expansion and elimination instead of LAPACK's LU and QR; no BLAS or
LAPACK, so the same bits on every CPU).

:func:`volume_correction_nd` is Proposition 1 with the ``volume`` gain in n >= 3 dimensions
in one call (``gains.volume_correction``; reference ``gains.volume_correction_reference``):
the 2-D kernel's steps (``kernels.sequential_volume_gain``,
``kernels.smallest_volume_correction``) with :func:`volume_gain_nd`,
:func:`generator_volume_nd` and the rank test :func:`full_rank_nd` (``zonotope.full_rank``
for n != 2: numpy's ``matrix_rank`` tolerance on singular values from one-sided Jacobi,
:func:`singular_values`, instead of LAPACK's SVD).
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from sse_cosim.sets.kernels import (
    nonzero_columns,
    sequential_volume_gain,
    smallest_volume_correction,
)

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

RESIDUAL_RTOL = 1e-11
"""A row with |d̂ᵀμ| <= this · ‖μ‖∞ passes through the vertex (the vertex's rounding, with the
basis's condition number up to about 1e4, stays below it)."""

RATE_RTOL = 1e-12
"""A row with |d̂ᵀδ| <= this · ‖δ‖∞ is parallel to the edge δ and never blocks it."""

MULTIPLIER_RTOL = 1e-11
"""The vertex is optimal when every |u_S| <= w_S + this · Σ w (the multipliers' rounding)."""

PERTURBATION = 1e-7
"""ε of the perturbed problem's right-hand sides (:func:`_offsets`), far above the vertices'
rounding (:data:`RESIDUAL_RTOL`) for vertices of norm up to about 1e3."""

MAX_JACOBI_SWEEPS = 60
"""Sweeps of :func:`singular_values` before it stops unconverged (it converges quadratically:
a handful for the small matrices here)."""

MAX_PIVOTS_PER_ROW = 10
"""Pivot budget per row of D and dimension. In exact arithmetic the method ends by itself (a
pivot that moves lowers φ, and Bland's rule ends every run of pivots that do not); rounding
(rows of D parallel to within their own rounding) may make it cycle, and the budget then
stops it uncertified."""


@njit(cache=True)
def _eliminated_determinant(a: FloatArray) -> float:
    """det of a square (k, k) matrix from its :func:`_lu` (partial pivoting): the product of
    the pivots, negated for an odd row order; 0 when a pivot column is all zero."""
    lu, order, regular = _lu(a)
    if not regular:
        return 0.0
    k = a.shape[0]
    det = 1.0
    for col in range(k):
        det *= lu[col, col]
    seen = np.zeros(k, dtype=np.bool_)
    for start in range(k):  # each cycle of length c flips the sign c - 1 times
        length = 0
        i = start
        while not seen[i]:
            seen[i] = True
            i = order[i]
            length += 1
        if length > 0 and length % 2 == 0:
            det = -det
    return det


@njit(cache=True)
def _minor(generators: FloatArray, skipped: int, columns: IntArray, work: FloatArray) -> float:
    """det of G's rows without ``skipped`` and its ``columns`` (k = n - 1 of them): in closed
    form for k = 2 and k = 3 (expanded along the first row), else by elimination in ``work``
    (k, k)."""
    k = columns.shape[0]
    r0 = 1 if skipped == 0 else 0
    r1 = r0 + 1 + (1 if skipped == r0 + 1 else 0)
    if k == 2:
        return generators[r0, columns[0]] * generators[r1, columns[1]] \
            - generators[r0, columns[1]] * generators[r1, columns[0]]
    if k == 3:
        r2 = r1 + 1 + (1 if skipped == r1 + 1 else 0)
        a, b, c = columns[0], columns[1], columns[2]
        return generators[r0, a] * (generators[r1, b] * generators[r2, c]
                                    - generators[r1, c] * generators[r2, b]) \
            - generators[r0, b] * (generators[r1, a] * generators[r2, c]
                                   - generators[r1, c] * generators[r2, a]) \
            + generators[r0, c] * (generators[r1, a] * generators[r2, b]
                                   - generators[r1, b] * generators[r2, a])
    for row in range(k):
        source = row if row < skipped else row + 1
        for col in range(k):
            work[row, col] = generators[source, columns[col]]
    return _eliminated_determinant(work)


@njit(cache=True)
def _subset_count(e: int, k: int) -> int:
    """C(e, k) (0 when k > e)."""
    if k > e:
        return 0
    count = 1
    for i in range(k):
        count = count * (e - i) // (i + 1)
    return count


@njit(cache=True)
def _next_subset(indices: IntArray, e: int) -> bool:
    """Advance the sorted k-subset ``indices`` of range(e) to the next in lexicographic order in
    place; False after the last one."""
    k = indices.shape[0]
    p = k - 1
    while p >= 0 and indices[p] == e - k + p:
        p -= 1
    if p < 0:
        return False
    indices[p] += 1
    for q in range(p + 1, k):
        indices[q] = indices[q - 1] + 1
    return True


@njit(cache=True)
def cofactor_rows(generators: FloatArray) -> FloatArray:
    """``zonotope.cofactor_vectors`` for G (n, e), n >= 3: the cofactor vector d_S of every
    (n-1)-subset S of the columns (lexicographic order), det[G_S, x] = d_Sᵀx, shape
    (C(e, n-1), n); entry i is (-1)^(i+n-1) times the minor without row i (:func:`_minor`)."""
    n, e = generators.shape
    k = n - 1
    rows = np.zeros((_subset_count(e, k), n))
    if rows.shape[0] == 0:
        return rows
    indices = np.arange(k)
    work = np.empty((k, k))
    count = 0
    while True:
        for i in range(n):
            sign = 1.0 if (i + n - 1) % 2 == 0 else -1.0
            rows[count, i] = sign * _minor(generators, i, indices, work)
        count += 1
        if not _next_subset(indices, e):
            return rows


@njit(cache=True)
def volume_from_cofactors(generators: FloatArray, cofactors: FloatArray) -> float:
    """vol(⟨·, G⟩)/2ⁿ = Σ over n-subsets T of |det G_T| for G (n, e), n >= 3, from
    :func:`cofactor_rows` (C(e, n-1), n): each T once, as its first n - 1 columns S (row of
    ``cofactors`` in lexicographic order) and its last column g_k, det G_T = d_Sᵀg_k."""
    n, e = generators.shape
    indices = np.arange(n - 1)
    total = 0.0
    for row in range(cofactors.shape[0]):
        for col in range(indices[n - 2] + 1, e):
            det = 0.0
            for i in range(n):
                det += cofactors[row, i] * generators[i, col]
            total += abs(det)
        _next_subset(indices, e)
    return total


@njit(cache=True)
def generator_volume_nd(generators: FloatArray) -> float:
    """``zonotope.generator_volume`` for G (n, e), n >= 3: 2ⁿ Σ over n-subsets T of
    |det G_T| by :func:`volume_from_cofactors`, zero columns dropped first (as the reference
    ``generator_volume_reference``, which takes |det| from QR instead)."""
    g = nonzero_columns(generators)
    return 2.0 ** g.shape[0] * volume_from_cofactors(g, cofactor_rows(g))


@njit(cache=True)
def _lu(matrix: FloatArray) -> tuple[FloatArray, IntArray, bool]:
    """PA = LU of a square (n, n) matrix with partial pivoting: the packed factors (unit lower
    L below the diagonal), the row order P (n,), and whether every pivot is nonzero."""
    a = matrix.copy()
    n = a.shape[0]
    order = np.arange(n)
    for col in range(n):
        pivot = col
        for row in range(col + 1, n):
            if abs(a[row, col]) > abs(a[pivot, col]):
                pivot = row
        if a[pivot, col] == 0.0:
            return a, order, False
        if pivot != col:
            for j in range(n):
                a[col, j], a[pivot, j] = a[pivot, j], a[col, j]
            order[col], order[pivot] = order[pivot], order[col]
        for row in range(col + 1, n):
            a[row, col] /= a[col, col]
            for j in range(col + 1, n):
                a[row, j] -= a[row, col] * a[col, j]
    return a, order, True


@njit(cache=True)
def _lu_solve(lu: FloatArray, order: IntArray, rhs: FloatArray) -> FloatArray:
    """x with A x = rhs (n,) from :func:`_lu` of A."""
    n = lu.shape[0]
    x = np.empty(n)
    for i in range(n):
        total = rhs[order[i]]
        for j in range(i):
            total -= lu[i, j] * x[j]
        x[i] = total
    for i in range(n - 1, -1, -1):
        total = x[i]
        for j in range(i + 1, n):
            total -= lu[i, j] * x[j]
        x[i] = total / lu[i, i]
    return x


@njit(cache=True)
def _lu_solve_transposed(lu: FloatArray, order: IntArray, rhs: FloatArray) -> FloatArray:
    """x with Aᵀ x = rhs (n,) from :func:`_lu` of A (Aᵀ = UᵀLᵀP)."""
    n = lu.shape[0]
    y = np.empty(n)
    for i in range(n):
        total = rhs[i]
        for j in range(i):
            total -= lu[j, i] * y[j]
        y[i] = total / lu[i, i]
    for i in range(n - 1, -1, -1):
        total = y[i]
        for j in range(i + 1, n):
            total -= lu[j, i] * y[j]
        y[i] = total
    x = np.empty(n)
    for i in range(n):
        x[order[i]] = y[i]
    return x


@njit(cache=True)
def _largest_abs(values: FloatArray) -> float:
    largest = 0.0
    for value in values:
        largest = max(largest, abs(value))
    return largest


@njit(cache=True)
def _dot(a: FloatArray, b: FloatArray) -> float:
    total = 0.0
    for i in range(a.shape[0]):
        total += a[i] * b[i]
    return total


@njit(cache=True)
def _start(normal: FloatArray) -> tuple[FloatArray, FloatArray, IntArray]:
    """The first basis for :func:`plane_l1_minimizer`: rows hᵀ and the unit vectors of every
    coordinate but h's largest, right-hand sides 1 and μ_0 = h/(hᵀh) there (so the vertex is
    μ_0), and the slots' rows of D (-1: none, a placeholder); shapes (n, n), (n,), (n,)."""
    n = normal.shape[0]
    start = normal / _dot(normal, normal)
    largest = 0
    for i in range(n):
        if abs(normal[i]) > abs(normal[largest]):
            largest = i
    basis = np.zeros((n, n))
    rhs = np.empty(n)
    slots = np.full(n, -1)
    basis[0] = normal
    rhs[0] = 1.0
    slot = 1
    for i in range(n):
        if i != largest:
            basis[slot, i] = 1.0
            rhs[slot] = start[i]
            slot += 1
    return basis, rhs, slots


@njit(cache=True)
def _leaving_slot(multipliers: FloatArray, slots: IntArray, weights: FloatArray,
                  tolerance: float, bland: bool) -> int:
    """The basis slot to leave among those with |u| > w + tolerance, a placeholder first;
    else, under Bland's rule, the one whose row of D has the smallest index, otherwise the one
    with the largest |u| - w (the steepest edge per unit of that row's residual). -1 if none
    (the vertex is optimal). Slot 0 (hᵀμ = 1) never leaves."""
    chosen, largest = -1, 0.0
    for k in range(1, slots.shape[0]):
        row = slots[k]
        if row < 0:
            return k
        excess = abs(multipliers[k]) - weights[row]
        if excess <= tolerance:
            continue
        if chosen < 0 or (row < slots[chosen] if bland else excess > largest):
            chosen, largest = k, excess
    return chosen


@njit(cache=True)
def _entering_row(residuals: FloatArray, rates: FloatArray, signs: FloatArray,
                  weights: FloatArray, in_basis: NDArray[np.bool_], slope: float,
                  zero: float, parallel: float, bland: bool) -> int:
    """The row of D that enters along the edge (slope f' < 0, or 0 for a placeholder), or -1
    if no row blocks it. Rows whose residual r moves toward 0 (s·rate < 0, s the sign of r,
    kept for a row through the vertex) block it, at step |r|/|rate| (0 through the vertex).
    The rows are crossed in order of their step (their signs flipped) while the slope, raised
    by 2 w |rate| at each, stays negative, and the row where it turns enters (the weighted
    median: the edge's exact line search). Under Bland's rule a row through the vertex that
    blocks stops the edge at once: the smallest such index enters."""
    k = residuals.shape[0]
    steps = np.full(k, np.inf)
    for j in range(k):
        if in_basis[j] or not signs[j] * rates[j] < -parallel:
            continue
        if abs(residuals[j]) > zero:
            steps[j] = abs(residuals[j]) / abs(rates[j])
        elif bland:
            return j
        else:
            steps[j] = 0.0
    for j in np.argsort(steps, kind="mergesort"):
        if steps[j] == np.inf:
            return -1
        slope += 2.0 * weights[j] * abs(rates[j])
        if slope >= 0.0:
            return j
        signs[j] = -signs[j]
    return -1


@njit(cache=True)
def _offsets(k: int) -> FloatArray:
    """The right-hand sides ε·ξ_j (k,) of the perturbed problem: ε = PERTURBATION, ξ_j in
    [0.5, 1.5) by the golden-ratio sequence (all distinct: no two shifted rows through one
    vertex stay together unless they are parallel)."""
    offsets = np.empty(k)
    for j in range(k):
        offsets[j] = PERTURBATION * (0.5 + ((j + 1) * 0.6180339887498949) % 1.0)
    return offsets


@njit(cache=True)
def _pivot(rows: FloatArray, weights: FloatArray, offsets: FloatArray, basis: FloatArray,
           rhs: FloatArray, slots: IntArray, in_basis: NDArray[np.bool_], signs: FloatArray
           ) -> tuple[FloatArray, bool]:
    """Simplex pivots for min Σ_j w_j |d̂_jᵀμ - b_j| subject to hᵀμ = 1 (b = ``offsets``) from
    the basis (rows ``basis`` (n, n), right-hand sides ``rhs`` (n,), ``slots`` (n,) their rows
    of D or -1, ``in_basis`` and ``signs`` (k,) of the rows), updated in place: the last
    vertex μ (n,) and whether it is certified optimal (module docstring)."""
    k, n = rows.shape
    mu = np.full(n, np.nan)
    residuals = np.zeros(k)
    rates = np.zeros(k)
    tolerance = MULTIPLIER_RTOL * weights.sum()
    stalled = 0  # degenerate pivots in a row
    for _ in range(MAX_PIVOTS_PER_ROW * (k + n)):
        lu, order, regular = _lu(basis)
        if not regular:
            break
        mu = _lu_solve(lu, order, rhs)
        zero = RESIDUAL_RTOL * _largest_abs(mu)
        gradient = np.zeros(n)
        for j in range(k):
            if in_basis[j]:
                continue
            residuals[j] = _dot(rows[j], mu) - offsets[j]
            if abs(residuals[j]) > zero:
                signs[j] = 1.0 if residuals[j] > 0.0 else -1.0
            for i in range(n):
                gradient[i] -= weights[j] * signs[j] * rows[j, i]
        multipliers = _lu_solve_transposed(lu, order, gradient)
        bland = stalled >= n
        slot = _leaving_slot(multipliers, slots, weights, tolerance, bland)
        if slot < 0:
            return mu, True
        leaving = slots[slot]
        step = 1.0 if multipliers[slot] >= 0.0 else -1.0
        unit = np.zeros(n)
        unit[slot] = step
        direction = _lu_solve(lu, order, unit)
        for j in range(k):
            rates[j] = _dot(rows[j], direction)
        slope = (weights[leaving] if leaving >= 0 else 0.0) - abs(multipliers[slot])
        entering = _entering_row(residuals, rates, signs, weights, in_basis, slope, zero,
                                 RATE_RTOL * _largest_abs(direction), bland)
        if entering < 0:
            break
        stalled = stalled + 1 if abs(residuals[entering]) <= zero else 0
        if leaving >= 0:
            in_basis[leaving] = False
            signs[leaving] = step
        in_basis[entering] = True
        slots[slot] = entering
        basis[slot] = rows[entering]
        rhs[slot] = offsets[entering]
    return mu, False


@njit(cache=True)
def plane_l1_minimizer(rows: FloatArray, weights: FloatArray,
                       normal: FloatArray) -> tuple[FloatArray, bool]:
    """μ (n,) minimizing Σ_j w_j |d̂_jᵀμ| subject to hᵀμ = 1, for unit rows d̂ (k, n), weights
    w (k,) > 0 and h (n,) ≠ 0, and whether the optimum is certified.

    First on the perturbed problem (right-hand sides :func:`_offsets` instead of 0), whose
    vertices are simple (no pivot stalls there), then from its last basis on the problem
    itself, where that basis is optimal unless the perturbation moved the optimum (rows within
    about ε of it), and a few more pivots finish. Without a certificate (the rows do not span
    Rⁿ, or rounding makes the basis singular, an edge unbounded or the pivots run past their
    budget) μ is the last vertex reached (NaN if there is none, as for h = 0).
    """
    k, n = rows.shape
    basis, rhs, slots = _start(normal)
    in_basis = np.zeros(k, dtype=np.bool_)
    signs = np.ones(k)
    _pivot(rows, weights, _offsets(k), basis, rhs, slots, in_basis, signs)
    for slot in range(1, n):
        if slots[slot] >= 0:
            rhs[slot] = 0.0
    return _pivot(rows, weights, np.zeros(k), basis, rhs, slots, in_basis, signs)


@njit(cache=True)
def unit_rows(vectors: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The nonzero rows of ``vectors`` (k, n) divided by their norms, and the norms: shapes
    (k', n) and (k',). Each norm is taken of the row scaled by its largest entry first, so
    rows of subnormal entries keep their direction."""
    k, n = vectors.shape
    norms = np.empty(k)
    for j in range(k):
        largest = _largest_abs(vectors[j])
        scaled = vectors[j] / largest if largest > 0.0 else vectors[j]
        norms[j] = largest * np.sqrt(_dot(scaled, scaled))
    rows = np.empty((int((norms > 0.0).sum()), n))
    weights = np.empty(rows.shape[0])
    kept = 0
    for j in range(k):
        if norms[j] > 0.0:
            rows[kept] = vectors[j] / norms[j]
            weights[kept] = norms[j]
            kept += 1
    return rows, weights


@njit(cache=True)
def volume_gain_nd(generators: FloatArray, normal: FloatArray, radius: float) -> FloatArray:
    """λ (n,) minimizing V·|1 - hᵀλ| + r·Σ_S |d_Sᵀλ| for G (n, e), n >= 3, h (n,) and r >= 0
    (``gains.strip_gain_volume``): μ* of :func:`plane_l1_minimizer` if its value is below λ = 0's
    (V), else λ = 0 (also when G or h is zero). Where the solver certifies nothing (rounding
    trouble, or D of rank < n: then V = 0 and λ = 0 is optimal) its last vertex stands in for
    μ*, with the same comparison, so λ = 0 (always sound) is the worst that can come back.
    G is scaled by max |g_ij| first (the minimizer does not change)."""
    n = generators.shape[0]
    zero = np.zeros(n)
    scale = _largest_abs(generators.ravel())
    if not (scale > 0.0 and np.isfinite(scale)):
        return zero
    g = generators / scale
    cofactors = cofactor_rows(g)
    base = volume_from_cofactors(g, cofactors)
    rows, weights = unit_rows(cofactors)
    mu = plane_l1_minimizer(rows, weights, normal)[0]
    cuts = 0.0
    for j in range(rows.shape[0]):
        cuts += weights[j] * abs(_dot(rows[j], mu))
    value = base * abs(1.0 - _dot(normal, mu)) + radius / scale * cuts
    return mu if value < base else zero  # False for NaN (h = 0)


@njit(cache=True)
def singular_values(generators: FloatArray) -> FloatArray:
    """The singular values (n,) of G (n, e), e >= n, unsorted, by one-sided Jacobi (Hestenes)
    on Gᵀ: plane rotations of pairs of G's rows until every pair is orthogonal to within eps
    of their norms; the singular values are then the rows' norms. Plain arithmetic in a fixed
    order (no LAPACK), so the same bits on every CPU; each value within a few eps·s_max of
    LAPACK's, as its SVD's (both backward stable). G is scaled by max |g_ij| first (no
    overflow in the squares; a square that underflows belongs to a row below 1e-154 of the
    largest entry)."""
    n, e = generators.shape
    scale = _largest_abs(generators.ravel())
    if not scale > 0.0:
        return np.zeros(n)
    a = generators / scale
    eps = np.finfo(np.float64).eps
    for _ in range(MAX_JACOBI_SWEEPS):
        rotated = False
        for p in range(n - 1):
            for q in range(p + 1, n):
                alpha = _dot(a[p], a[p])
                beta = _dot(a[q], a[q])
                gamma = _dot(a[p], a[q])
                if abs(gamma) <= eps * np.sqrt(alpha) * np.sqrt(beta):
                    continue
                zeta = (beta - alpha) / (2.0 * gamma)
                t = 1.0 / (abs(zeta) + np.sqrt(1.0 + zeta * zeta)) if abs(zeta) < 1e150 \
                    else 0.5 / abs(zeta)
                if zeta < 0.0:
                    t = -t
                cos = 1.0 / np.sqrt(1.0 + t * t)
                sin = cos * t
                for j in range(e):
                    x, y = a[p, j], a[q, j]
                    a[p, j] = cos * x - sin * y
                    a[q, j] = sin * x + cos * y
                rotated = True
        if not rotated:
            break
    values = np.empty(n)
    for i in range(n):
        values[i] = scale * np.sqrt(_dot(a[i], a[i]))
    return values


@njit(cache=True)
def full_rank_nd(generators: FloatArray) -> bool:
    """``zonotope.full_rank`` for G (n, e), n != 2: e >= n and s_min > e·eps·s_max (numpy's
    ``matrix_rank`` tolerance) from :func:`singular_values` instead of LAPACK's SVD. The two
    may disagree only where s_min is within a few eps·s_max of the threshold, i.e. where
    both are rounding; the decision there only picks between two sound gains of
    Proposition 1 (the one-strip Frobenius gain or :func:`volume_gain_nd`)."""
    n, e = generators.shape
    if e < n:
        return False
    values = singular_values(generators)
    return values.min() > e * np.finfo(np.float64).eps * values.max()


@njit(cache=True)
def volume_correction_nd(center: FloatArray, generators: FloatArray, normals: FloatArray,
                         values: FloatArray, radii: FloatArray
                         ) -> tuple[FloatArray, FloatArray]:
    """Prop. 1 with the ``volume`` gain for ⟨c, G⟩, n >= 3, and unit-normal strips (H (m, n),
    y and r (m,)): ``kernels.smallest_volume_correction`` with the sequential gain of
    :func:`full_rank_nd` and :func:`volume_gain_nd`, sizes by :func:`generator_volume_nd`;
    -> c' (n,), G' (n, <= e + m). Reference: ``gains.volume_correction_reference``, equal up
    to rounding (and to the rank decisions within rounding of the threshold)."""
    sequential = sequential_volume_gain(full_rank_nd, volume_gain_nd, generators, normals,
                                        values, radii, center)
    return smallest_volume_correction(generator_volume_nd, sequential, center, generators,
                                      normals, values, radii)

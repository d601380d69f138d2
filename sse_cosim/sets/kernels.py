"""Compiled kernels (numba, cached on disk) of the hot set operations, on plain float64 arrays.

Each kernel has a NumPy reference beside its public function, and ``tests/sets`` checks one
against the other on random and degenerate inputs, within a stated rounding bound (the
same operations in the same order agree bit for bit, but NumPy's BLAS and SIMD code may
round otherwise on another CPU, so no test asks for more):

- :func:`area_2d` for :func:`~sse_cosim.sets.zonotope.generator_volume` in 2-D
  (reference ``generator_volume_reference``): it sums in numpy's order;
- :func:`girard_reduce` for the ``girard`` order reduction (reference
  ``girard_reduce_reference`` in :mod:`~sse_cosim.sets.reduction`): the same scores;
- :func:`full_rank_2d` for :func:`~sse_cosim.sets.zonotope.full_rank` in 2-D and
  :func:`contains_2d` for :meth:`~sse_cosim.sets.zonotope.Zonotope.contains` of a full-rank
  2-D zonotope (reference ``contains_2d_reference``): the same sums in numpy's order, the
  two-term dot products may round differently from numpy's BLAS calls (a point within a
  rounding of a facet, beyond the tolerance, is the only place they can disagree);
- :func:`meet_2d` for ``overlap.zonotopes_disjoint`` in 2-D (reference
  ``zonotopes_disjoint_reference``): the same kernels on the same arrays, so the same answer;
- :func:`volume_gain_2d` for ``gains.volume_gain_vertices`` (reference
  ``volume_gain_vertices_reference``): the same candidates and choice, up to ties;
- :func:`vertices_2d` for :meth:`~sse_cosim.sets.zonotope.Zonotope.vertices` (reference
  ``vertices_2d_reference``): the same sort, merges and sums;
- :func:`frobenius_gain` and :func:`intersect_frobenius` for the Frobenius gain of
  Proposition 1 (reference ``frobenius_gain_reference`` in :mod:`~sse_cosim.sets.gains`): the
  same least-squares minimizer by Householder QR instead of LAPACK's SVD solver, so equal up
  to rounding;
- :func:`volume_correction_2d` for Proposition 1 with the ``volume`` gain in 2-D (reference
  ``volume_correction_reference`` in :mod:`~sse_cosim.sets.gains`): the same candidates and
  choice, the Frobenius one by QR, so equal up to rounding. Its two steps,
  :func:`sequential_volume_gain` and :func:`smallest_volume_correction`, take the
  dimension's rank test, one-strip gain and volume as arguments, so
  ``volume_gain_kernels.volume_correction_nd`` runs them in n-D.

numba caches the machine code in ``__pycache__`` next to this file (ignored by git).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numba import njit
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

RankTest = Callable[[FloatArray], bool]
"""A compiled test whether G (n, e) has rank n."""

StripGain = Callable[[FloatArray, FloatArray, float], FloatArray]
"""A compiled one-strip gain λ (n,) for G (n, e), a unit normal h (n,) and a radius r."""

Volume = Callable[[FloatArray], float]
"""A compiled volume of ⟨·, G⟩ for G (n, e)."""

_BLOCK = 128  # numpy's PW_BLOCKSIZE

PARALLEL_RTOL = 1e-12
"""Consecutive sorted generators whose cross product is below this (relative) are parallel."""


@njit(cache=True)
def _block_sum(values: FloatArray, first: int, count: int) -> float:
    """numpy's pairwise_sum for count <= 128: eight running sums, combined as a tree (kept in
    scalars: no allocation)."""
    if count < 8:
        total = 0.0
        for i in range(first, first + count):
            total += values[i]
        return total
    r0, r1, r2, r3 = values[first], values[first + 1], values[first + 2], values[first + 3]
    r4, r5, r6, r7 = values[first + 4], values[first + 5], values[first + 6], values[first + 7]
    i = 8
    while i < count - count % 8:
        j = first + i
        r0 += values[j]
        r1 += values[j + 1]
        r2 += values[j + 2]
        r3 += values[j + 3]
        r4 += values[j + 4]
        r5 += values[j + 5]
        r6 += values[j + 6]
        r7 += values[j + 7]
        i += 8
    total = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < count:
        total += values[first + i]
        i += 1
    return total


@njit(cache=True)
def pairwise_sum(values: FloatArray, first: int, count: int) -> float:
    """Σ values[first:first + count] (1-D) in numpy's pairwise order, so the same rounding as
    ``ndarray.sum`` over a contiguous run: blocks of <= 128 by :func:`_block_sum`, longer runs
    split in two (the first half a multiple of 8) and the halves added. numpy recurses; this
    walks the same tree with an explicit stack (numba cannot cache recursive functions)."""
    if count <= _BLOCK:
        return _block_sum(values, first, count)
    starts = np.empty(64, dtype=np.int64)
    counts = np.empty(64, dtype=np.int64)
    left_done = np.zeros(64, dtype=np.bool_)
    left = np.empty(64)
    top = 0
    starts[0], counts[0] = first, count
    while True:
        while counts[top] > _BLOCK:  # descend into left halves
            half = counts[top] // 2
            half -= half % 8
            starts[top + 1], counts[top + 1] = starts[top], half
            left_done[top + 1] = False
            top += 1
        value = _block_sum(values, starts[top], counts[top])
        while True:  # hand the value to the parent
            if top == 0:
                return value
            top -= 1
            if left_done[top]:
                value = left[top] + value
                continue
            left[top], left_done[top] = value, True
            half = counts[top] // 2
            half -= half % 8
            starts[top + 1], counts[top + 1] = starts[top] + half, counts[top] - half
            left_done[top + 1] = False
            top += 1
            break


@njit(cache=True)
def area_2d(generators: FloatArray) -> float:
    """Area of ⟨c, G⟩, G (2, e): 2 Σ_ij |g_i × g_j| over the nonzero columns (eq. zonoDef's
    volume, 2-D), summed as the reference sums its (e, e) matrix of cross products."""
    e = generators.shape[1]
    a = np.empty(e)
    b = np.empty(e)
    k = 0
    for j in range(e):
        if generators[0, j] != 0.0 or generators[1, j] != 0.0:
            a[k] = generators[0, j]
            b[k] = generators[1, j]
            k += 1
    cross = np.empty(k * k)
    for i in range(k):
        for j in range(k):
            cross[i * k + j] = abs(a[i] * b[j] - b[i] * a[j])
    return 2.0 * pairwise_sum(cross, 0, k * k)


@njit(cache=True)
def full_rank_2d(generators: FloatArray) -> bool:
    """``zonotope.full_rank`` for G (2, e): s_min > e·eps·s_max from 2×2 minors."""
    e = generators.shape[1]
    if e < 2:
        return False
    p = q = r = 0.0
    for j in range(e):
        a, b = generators[0, j], generators[1, j]
        p += a * a
        q += b * b
        r += a * b
    if p + q == 0.0:
        return False
    s_max2 = 0.5 * (p + q) + np.sqrt(0.25 * (p - q) ** 2 + r * r)
    cross = np.empty(e * e)
    for i in range(e):
        for j in range(e):
            c = generators[0, i] * generators[1, j] - generators[1, i] * generators[0, j]
            cross[i * e + j] = c * c
    s_prod = np.sqrt(0.5 * pairwise_sum(cross, 0, e * e))
    return s_prod > e * np.finfo(np.float64).eps * s_max2


@njit(cache=True)
def facet_normal(generators: FloatArray, j: int) -> tuple[float, float, bool]:
    """The unit normal (n0, n1) of column j of G (2, e), g_j turned by +90°, and whether
    g_j is nonzero (without one, (0, 0, False))."""
    v0, v1 = -generators[1, j], generators[0, j]
    norm = np.sqrt(v0 * v0 + v1 * v1)
    if not norm > 0.0:
        return 0.0, 0.0, False
    return v0 / norm, v1 / norm, True


@njit(cache=True)
def contains_2d(center: FloatArray, generators: FloatArray, points: FloatArray,
                tol: float) -> NDArray[np.bool_]:
    """Whether each point (k, 2) lies in the full-rank 2-D ⟨c, G⟩ (``center`` (2,), G (2, e)),
    shape (k,) bool: |nᵀ(x - c)| <= Σ_i |nᵀg_i| + tol for the unit normal n of every
    nonzero column (the facet normals, parallel repeats only repeating a test)."""
    e = generators.shape[1]
    k = points.shape[0]
    inside = np.ones(k, dtype=np.bool_)
    terms = np.empty(e)
    for j in range(e):
        n0, n1, nonzero = facet_normal(generators, j)
        if not nonzero:
            continue
        for i in range(e):
            terms[i] = abs(n0 * generators[0, i] + n1 * generators[1, i])
        bound = pairwise_sum(terms, 0, e) + tol
        for p in range(k):
            offset = abs((points[p, 0] - center[0]) * n0 + (points[p, 1] - center[1]) * n1)
            if not offset <= bound:
                inside[p] = False
    return inside


@njit(cache=True)
def meet_2d(first_center: FloatArray, first_generators: FloatArray, second_center: FloatArray,
            second_generators: FloatArray, tol: float) -> int:
    """Whether 2-D ⟨c1, G1⟩ and ⟨c2, G2⟩ (centers (2,), generators (2, e1), (2, e2)) meet:
    c1 - c2 ∈ ⟨0, [G1, -G2]⟩ up to ``tol`` by :func:`contains_2d`, as
    ``overlap.zonotopes_disjoint`` tests it. 1 if they meet, 0 if not, -1 if [G1, -G2] is
    rank-deficient (no half-space test: the caller's LP decides)."""
    e1 = first_generators.shape[1]
    difference = np.empty((2, e1 + second_generators.shape[1]))
    difference[:, :e1] = first_generators
    difference[:, e1:] = -second_generators
    if not full_rank_2d(difference):
        return -1
    offset = np.empty((1, 2))
    offset[0, 0] = first_center[0] - second_center[0]
    offset[0, 1] = first_center[1] - second_center[1]
    return 1 if contains_2d(np.zeros(2), difference, offset, tol)[0] else 0


@njit(cache=True)
def row_sum(values: FloatArray) -> float:
    """Σ of a 1-D array in numpy's pairwise order."""
    contiguous = np.ascontiguousarray(values)
    return pairwise_sum(contiguous, 0, contiguous.shape[0])


@njit(cache=True)
def folded_sorted(generators: FloatArray) -> FloatArray:
    """The columns (2, e) folded into the upper half-plane and sorted by angle (stable)."""
    g = generators.copy()
    for j in range(g.shape[1]):
        if g[1, j] < 0 or (g[1, j] == 0 and g[0, j] < 0):
            g[0, j] = -g[0, j]
            g[1, j] = -g[1, j]
    angle = np.empty(g.shape[1])
    for j in range(g.shape[1]):
        angle[j] = np.arctan2(g[1, j], g[0, j])
    return np.ascontiguousarray(g[:, np.argsort(angle, kind="mergesort")])


@njit(cache=True)
def vertices_2d(center: FloatArray, generators: FloatArray) -> FloatArray:
    """``Zonotope.vertices`` of ⟨c, G⟩ (``center`` (2,), G (2, e)), shape (k, 2), with its
    arithmetic: zero columns dropped, folded, sorted, runs of parallel columns summed in order,
    then c - Σg followed by the cumulative sum of 2g_i and -2g_i (the centre alone without
    generators)."""
    g = folded_sorted(nonzero_columns(generators))
    e = g.shape[1]
    if e == 0:
        return center.reshape(1, 2).copy()
    merged = np.empty((2, e))
    count = -1
    for j in range(e):
        if j == 0 or _not_parallel(g[:, j - 1], g[:, j]):
            count += 1
            merged[0, count], merged[1, count] = g[0, j], g[1, j]
        else:
            merged[0, count] += g[0, j]
            merged[1, count] += g[1, j]
    g = np.ascontiguousarray(merged[:, :count + 1])
    k = g.shape[1]
    start = np.array([center[0] - row_sum(g[0]), center[1] - row_sum(g[1])])
    vertices = np.empty((2 * k, 2))
    vertices[0] = start
    path = np.zeros(2)
    for step in range(2 * k - 1):
        sign = 2.0 if step < k else -2.0
        column = step % k
        path[0] += sign * g[0, column]
        path[1] += sign * g[1, column]
        vertices[step + 1, 0] = start[0] + path[0]
        vertices[step + 1, 1] = start[1] + path[1]
    return vertices


@njit(cache=True)
def _not_parallel(a: FloatArray, b: FloatArray) -> bool:
    """Whether consecutive sorted columns a, b (2,) start a new run (``_merge_parallel``)."""
    cross = a[0] * b[1] - a[1] * b[0]
    scale = np.sqrt(a[0] * a[0] + a[1] * a[1]) * np.sqrt(b[0] * b[0] + b[1] * b[1])
    return abs(cross) > PARALLEL_RTOL * scale


@njit(cache=True)
def volume_gain_2d(generators: FloatArray, normal: FloatArray, radius: float) -> FloatArray:
    """``gains.volume_gain_vertices`` for G (2, e), h (2,) and r: every candidate λ = 0 or
    g_i / (hᵀg_i) scored in closed form, the best (first of the least) returned, shape (2,);
    the reference's arithmetic, its sums in numpy's pairwise order."""
    e = generators.shape[1]
    cand0 = np.zeros(e + 1)
    cand1 = np.zeros(e + 1)
    c = 1
    a = np.empty(e)
    b = np.empty(e)
    k = 0
    for i in range(e):
        g0, g1 = generators[0, i], generators[1, i]
        hg = normal[0] * g0 + normal[1] * g1
        if abs(hg) > 1e-12 * np.sqrt(g0 * g0 + g1 * g1):
            cand0[c], cand1[c] = g0 / hg, g1 / hg
            c += 1
        if g0 != 0 or g1 != 0:
            a[k], b[k] = g0, g1
            k += 1
    cross = np.empty(k * k)
    for i in range(k):
        for j in range(k):
            cross[i * k + j] = abs(a[i] * b[j] - b[i] * a[j])
    base = 0.5 * pairwise_sum(cross, 0, k * k)
    cuts = np.empty(e)
    best, best_value = 0, 0.0
    for n in range(c):
        for i in range(e):
            cuts[i] = abs(cand1[n] * generators[0, i] - cand0[n] * generators[1, i])
        value = base * abs(1.0 - (cand0[n] * normal[0] + cand1[n] * normal[1])) \
            + radius * pairwise_sum(cuts, 0, e)
        if n == 0 or value < best_value or (np.isnan(value) and not np.isnan(best_value)):
            best, best_value = n, value
    return np.array([cand0[best], cand1[best]])


@njit(cache=True)
def girard_reduce(generators: FloatArray, max_generators: int) -> FloatArray:
    """Girard's reduction of G (n, e) to at most ``max_generators`` (>= n) columns: zero columns
    dropped; the max_generators - n largest by ‖g‖₁ − ‖g‖∞ kept (stable order); the rest
    enclosed in the axis-aligned box diag(Σ_j |g_j|), its zero columns dropped."""
    n = generators.shape[0]
    g = nonzero_columns(generators)
    k = g.shape[1]
    if k <= max_generators:
        return g
    score = np.empty(k)
    for j in range(k):
        total, largest = 0.0, 0.0
        for i in range(n):
            total += abs(g[i, j])
            largest = max(largest, abs(g[i, j]))
        score[j] = -(total - largest)
    order = np.argsort(score, kind="mergesort")
    kept = max_generators - n
    rest = np.empty(k - kept)
    radius = np.empty(n)
    for i in range(n):
        for j in range(k - kept):
            rest[j] = abs(g[i, order[kept + j]])
        radius[i] = pairwise_sum(rest, 0, k - kept)
    boxed = 0
    for i in range(n):
        if radius[i] != 0.0:
            boxed += 1
    out = np.zeros((n, kept + boxed))
    for j in range(kept):
        for i in range(n):
            out[i, j] = g[i, order[j]]
    column = kept
    for i in range(n):
        if radius[i] != 0.0:
            out[i, column] = radius[i]
            column += 1
    return out


@njit(cache=True)
def _reflect(v: FloatArray, vv: float, matrix: FloatArray, first: int, first_column: int) -> None:
    """matrix[first:, first_column:] <- (I - 2vvᵀ/vᵀv) matrix[first:, first_column:] in place
    (Householder reflection; v (rows,) is read from row ``first`` on, vv = vᵀv)."""
    for col in range(first_column, matrix.shape[1]):
        dot = 0.0
        for i in range(first, matrix.shape[0]):
            dot += v[i] * matrix[i, col]
        factor = 2.0 * dot / vv
        for i in range(first, matrix.shape[0]):
            matrix[i, col] -= factor * v[i]


@njit(cache=True)
def _project(normals: FloatArray, generators: FloatArray) -> FloatArray:
    """HG (m, e) for H (m, n) and G (n, e), each entry summed over i in order."""
    m, e = normals.shape[0], generators.shape[1]
    hg = np.zeros((m, e))
    for s in range(m):
        for j in range(e):
            for i in range(generators.shape[0]):
                hg[s, j] += normals[s, i] * generators[i, j]
    return hg


@njit(cache=True)
def nonzero_columns(matrix: FloatArray) -> FloatArray:
    """The columns of ``matrix`` (n, e) that have a nonzero entry, contiguous, in order."""
    keep = np.zeros(matrix.shape[1], dtype=np.bool_)
    for j in range(matrix.shape[1]):
        for i in range(matrix.shape[0]):
            if matrix[i, j] != 0.0:
                keep[j] = True
    return np.ascontiguousarray(matrix[:, keep])


@njit(cache=True)
def frobenius_gain(generators: FloatArray, normals: FloatArray, radii: FloatArray) -> FloatArray:
    """Λ (n, m) minimizing ‖G - Λ HG‖_F² + ‖Λ diag(r)‖_F² (Prop. 1, Frobenius gain), G (n, e),
    H (m, n), r (m,) > 0: the least-squares solution of [HG, diag(r)]ᵀ Λᵀ ≈ [G, 0]ᵀ by
    Householder QR ([HG, diag(r)] has rank m as r > 0, so R is invertible)."""
    return _gain(generators, _project(normals, generators), radii)


@njit(cache=True)
def _gain(generators: FloatArray, hg: FloatArray, radii: FloatArray) -> FloatArray:
    """:func:`frobenius_gain` from HG (m, e) already computed."""
    n, e = generators.shape
    m = hg.shape[0]
    rows = e + m
    a = np.zeros((rows, m))  # [HG, diag(r)]ᵀ
    b = np.zeros((rows, n))  # [G, 0]ᵀ
    for j in range(e):
        for s in range(m):
            a[j, s] = hg[s, j]
        for i in range(n):
            b[j, i] = generators[i, j]
    for s in range(m):
        a[e + s, s] = radii[s]
    v = np.empty(rows)
    for s in range(m):
        norm = 0.0
        for i in range(s, rows):
            norm += a[i, s] * a[i, s]
        norm = np.sqrt(norm)
        alpha = -norm if a[s, s] >= 0.0 else norm
        for i in range(s, rows):
            v[i] = a[i, s]
        v[s] -= alpha
        vv = 0.0
        for i in range(s, rows):
            vv += v[i] * v[i]
        _reflect(v, vv, a, s, s)
        _reflect(v, vv, b, s, 0)
    gain = np.empty((n, m))
    for col in range(n):  # back substitution R Λᵀ = (Qᵀ[G, 0]ᵀ)[:m]
        for s in range(m - 1, -1, -1):
            total = b[s, col]
            for t in range(s + 1, m):
                total -= a[s, t] * gain[col, t]
            gain[col, s] = total / a[s, s]
    return gain


@njit(cache=True)
def intersect_frobenius(center: FloatArray, generators: FloatArray, normals: FloatArray,
                        values: FloatArray, radii: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Prop. 1 with the Frobenius gain: c' = c + Λ(y - Hc) (eq. C_lambda) and
    G' = [(I - ΛH)G, Λ diag(r)] (eq. G_lambda), zero columns dropped; c (n,), G (n, e),
    H (m, n), y and r (m,) -> c' (n,), G' (n, <= e + m)."""
    hg = _project(normals, generators)
    return _apply_gain(center, generators, hg, _gain(generators, hg, radii), normals, values,
                       radii)


@njit(cache=True)
def _dot_column(normal: FloatArray, matrix: FloatArray, col: int) -> float:
    """hᵀ matrix[:, col] for h (n,), summed in index order from the first product (in 2-D
    h0·m0 + h1·m1, without a leading 0.0 that would turn a -0.0 into +0.0)."""
    total = normal[0] * matrix[0, col]
    for i in range(1, normal.shape[0]):
        total += normal[i] * matrix[i, col]
    return total


@njit(cache=True, inline="always")
def sequential_volume_gain(rank_test: RankTest, strip_gain: StripGain, generators: FloatArray,
                           normals: FloatArray, values: FloatArray, radii: FloatArray,
                           center: FloatArray) -> FloatArray:
    """``gains._sequential(choose)`` for ⟨c, G⟩ (n, e) and m unit-normal strips: the strips one
    after another, λ_j = 0 where strip j covers the current set, the one-strip Frobenius gain
    λ = G (hG)ᵀ / (|hG|² + r²) where ``rank_test`` (compiled, G -> bool) finds the current set
    rank-deficient, else ``strip_gain`` (compiled, (G, h, r) -> λ (n,)); the joint Λ (n, m).
    2-D: :func:`full_rank_2d` and :func:`volume_gain_2d`; n-D: their versions in
    :mod:`~sse_cosim.sets.volume_gain_kernels`. Inlined into its caller, as
    :func:`smallest_volume_correction`."""
    n, m = generators.shape[0], normals.shape[0]
    total = np.zeros((n, m))
    c = center.copy()
    g = generators.copy()
    for j in range(m):
        normal, value, radius = normals[j], values[j], radii[j]
        e = g.shape[1]
        hg = np.empty(e)
        for col in range(e):
            hg[col] = _dot_column(normal, g, col)
        mid = normal[0] * c[0]
        for i in range(1, n):
            mid += normal[i] * c[i]
        half = pairwise_sum(np.abs(hg), 0, e)
        if mid - half >= value - radius and mid + half <= value + radius:
            continue
        if not rank_test(g):
            scale = pairwise_sum(hg * hg, 0, e) + radius * radius
            lam = np.empty(n)
            for i in range(n):
                lam[i] = pairwise_sum(g[i] * hg, 0, e) / scale
        else:
            lam = strip_gain(g, normal, radius)
        if not lam.any():
            continue
        for k in range(j):
            t = _dot_column(normal, total, k)
            for i in range(n):
                total[i, k] -= lam[i] * t
        for i in range(n):
            total[i, j] = lam[i]
            c[i] += lam[i] * (value - mid)
        grown = np.empty((n, e + 1))
        for i in range(n):
            for col in range(e):
                grown[i, col] = g[i, col] - lam[i] * hg[col]
            grown[i, e] = lam[i] * radius
        g = nonzero_columns(grown)
    return total


@njit(cache=True)
def _updated(generators: FloatArray, hg: FloatArray, gain: FloatArray,
             radii: FloatArray) -> FloatArray:
    """G' = [(I - ΛH)G, Λ diag(r)] (eq. G_lambda) from HG (m, e); G (n, e), Λ (n, m)."""
    n, e = generators.shape
    m = hg.shape[0]
    full = np.empty((n, e + m))
    for i in range(n):
        for s in range(m):
            full[i, e + s] = gain[i, s] * radii[s]
        for j in range(e):
            total = generators[i, j]
            for s in range(m):
                total -= gain[i, s] * hg[s, j]
            full[i, j] = total
    return full


@njit(cache=True)
def _apply_gain(center: FloatArray, generators: FloatArray, hg: FloatArray, gain: FloatArray,
                normals: FloatArray, values: FloatArray, radii: FloatArray
                ) -> tuple[FloatArray, FloatArray]:
    """Prop. 1 for the gain Λ (n, m): c' = c + Λ(y - Hc) (eq. C_lambda) and G' (eq. G_lambda,
    :func:`_updated`), zero columns dropped; raises ValueError unless both are finite."""
    n, m = gain.shape
    innovation = values.copy()  # y - Hc
    for s in range(m):
        for i in range(n):
            innovation[s] -= normals[s, i] * center[i]
    new_center = center.copy()
    for i in range(n):
        for s in range(m):
            new_center[i] += gain[i, s] * innovation[s]
    full = _updated(generators, hg, gain, radii)
    if not (np.isfinite(new_center).all() and np.isfinite(full).all()):
        raise ValueError("zonotope center and generators must be finite")
    return new_center, nonzero_columns(full)


@njit(cache=True, inline="always")
def smallest_volume_correction(volume: Volume, sequential: FloatArray, center: FloatArray,
                               generators: FloatArray, normals: FloatArray, values: FloatArray,
                               radii: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Prop. 1 with the ``volume`` gain for ⟨c, G⟩ (n, e) and unit-normal strips (H (m, n), y
    and r (m,)), given the sequential gain Λ (n, m) (:func:`sequential_volume_gain`): of that,
    the Frobenius gain and Λ = 0, the gain whose G' has the least ``volume`` (compiled,
    G -> float; the first of the least, a NaN before any number, as ``np.argmin``), applied by
    eqs. C_lambda and G_lambda, zero columns dropped; -> c' (n,), G' (n, <= e + m).
    ``gains._smallest_volume`` and ``gains.apply_gain`` (reference:
    ``gains.volume_correction_reference``).

    Like :func:`sequential_volume_gain` it is inlined into its caller (numba's
    ``inline="always"``): there the kernels passed in are the caller's globals, so the
    caller's machine code can be cached (a compiled function that receives a kernel as an
    argument and calls it holds the kernel's address, which numba does not cache)."""
    hg = _project(normals, generators)
    return _apply_gain(center, generators, hg,
                       smallest_volume_gain(volume, sequential, generators, hg, radii),
                       normals, values, radii)


@njit(cache=True, inline="always")
def smallest_volume_gain(volume: Volume, sequential: FloatArray, generators: FloatArray,
                         hg: FloatArray, radii: FloatArray) -> FloatArray:
    """Of the sequential gain Λ (n, m), the Frobenius gain and Λ = 0, the one whose G' (from G
    (n, e) and HG (m, e)) has the least ``volume`` (the first of the least, a NaN before any
    number, as ``np.argmin``): the choice of :func:`smallest_volume_correction` (inlined, as
    it is)."""
    n, m = generators.shape[0], hg.shape[0]
    candidates = (sequential, _gain(generators, hg, radii), np.zeros((n, m)))
    best, best_volume = 0, 0.0
    for k in range(3):
        size = volume(_updated(generators, hg, candidates[k], radii)) if k < 2 \
            else volume(generators)
        if k == 0 or size < best_volume or (np.isnan(size) and not np.isnan(best_volume)):
            best, best_volume = k, size
    return candidates[best]


@njit(cache=True)
def volume_correction_2d(center: FloatArray, generators: FloatArray, normals: FloatArray,
                         values: FloatArray, radii: FloatArray
                         ) -> tuple[FloatArray, FloatArray]:
    """:func:`smallest_volume_correction` for a 2-D ⟨c, G⟩ (H (m, 2)): the sequential vertex
    gain (:func:`full_rank_2d`, :func:`volume_gain_2d`), sizes by :func:`area_2d`;
    -> c' (2,), G' (2, <= e + m)."""
    sequential = sequential_volume_gain(full_rank_2d, volume_gain_2d, generators, normals,
                                        values, radii, center)
    return smallest_volume_correction(area_2d, sequential, center, generators, normals,
                                      values, radii)


@njit(cache=True)
def block_volume_correction(center: FloatArray, generators: FloatArray, normals: FloatArray,
                            values: FloatArray, radii: FloatArray, first: int
                            ) -> tuple[FloatArray, FloatArray]:
    """Prop. 1 for ⟨c, G⟩ (n, e) and unit-normal strips (H (m, n), y and r (m,)) whose normals
    are zero outside the 2-D block of coordinates ``first``, ``first + 1``, with a gain that
    is zero outside the block: the block's ``volume`` gain (that of :func:`volume_correction_2d`
    on ⟨c_b, G_b⟩ and the block's normals), lifted. Every other coordinate keeps its centre and
    generators exactly (its entries of the new columns are zero); -> c' (n,), G' (n, <= e + m),
    zero columns dropped."""
    n, m = generators.shape[0], normals.shape[0]
    block_center = center[first:first + 2].copy()
    block = np.ascontiguousarray(generators[first:first + 2])
    block_normals = np.ascontiguousarray(normals[:, first:first + 2])
    sequential = sequential_volume_gain(full_rank_2d, volume_gain_2d, block, block_normals,
                                        values, radii, block_center)
    hg = _project(block_normals, block)
    gain = np.zeros((n, m))
    gain[first:first + 2] = smallest_volume_gain(area_2d, sequential, block, hg, radii)
    return _apply_gain(center, generators, hg, gain, normals, values, radii)


@njit(cache=True)
def unit_strips(normals: FloatArray, values: FloatArray, radii: FloatArray
                ) -> tuple[bool, FloatArray, FloatArray, FloatArray]:
    """``Strips.normalized`` on arrays H (m, n), y and r (m,): whether every row of H already
    has norm 1.0, and the rows, values and radii divided by ‖h_j‖ (sqrt of Σ_i h_ji² summed
    in order, as numpy sums a short row)."""
    m, n = normals.shape
    unit_normals = np.empty((m, n))
    unit_values = np.empty(m)
    unit_radii = np.empty(m)
    already = True
    for j in range(m):
        squares = 0.0
        for i in range(n):
            squares += normals[j, i] * normals[j, i]
        norm = np.sqrt(squares)
        already &= norm == 1.0
        for i in range(n):
            unit_normals[j, i] = normals[j, i] / norm
        unit_values[j] = values[j] / norm
        unit_radii[j] = radii[j] / norm
    return already, unit_normals, unit_values, unit_radii

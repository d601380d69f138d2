"""Compiled kernel (numba, cached on disk) of the ``enclose`` intersection: a zonotope cut by
strips, exactly as a convex polygon, enclosed in a zonotope along fixed directions.

:func:`enclose_intersection` is :func:`~sse_cosim.sets.enclosure.enclose_intersection_reference`
(the NumPy reference, whose docstrings carry the method and its proofs) step by step on plain
float64 arrays: the zonotope's vertices, Sutherland-Hodgman clipping by every strip, the unit
directions, the least-perimeter enclosure (weighted L1 centre over the arrangement's vertices,
the symmetric polygon's scales), the re-centering for area and the containment check with its
margin. Each helper names the reference function it follows. Sums of more than two terms run
in numpy's pairwise order (:func:`~sse_cosim.sets.kernels.pairwise_sum`); two-term dot
products may round differently from numpy's BLAS calls, so results agree with the reference
up to rounding (``tests/sets/test_sets_enclosure_kernel.py``). Soundness does not rest on
that agreement: as in the reference, the containment inequalities are re-evaluated here in
floating point with the margin, and the scales raised until each holds, or the enclosure is
rejected.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from sse_cosim.sets.kernels import (
    FloatArray,
    area_2d,
    facet_normal,
    folded_sorted,
    full_rank_2d,
    pairwise_sum,
    row_sum,
    unit_strips,
    vertices_2d,
    volume_correction_2d,
)

MARGIN = 1e-10
"""Safety margin of the containment test, relative to the size of the input set: covers the
rounding of the clipped polygon's vertices and of the zonotope's half-widths."""

PARALLEL_SIN = 1e-9
"""Directions whose angle has a sine below this are merged into one."""

REFINE_STEPS = 1
"""Re-centering steps after the least-perimeter enclosure (``enclosure.enclose_polygon``)."""


@njit(cache=True)
def zonotope_vertices(generators: FloatArray) -> FloatArray:
    """Vertices (k, 2) of ⟨0, G⟩, G (2, e), counter-clockwise from the lowest
    (:func:`vertices_2d` about the origin)."""
    return vertices_2d(np.zeros(2), generators)


@njit(cache=True)
def clip_polygon(vertices: FloatArray, normal: FloatArray, bound: float) -> FloatArray:
    """``enclosure.clip_polygon``: the convex polygon (k, 2) cut to {x : nᵀx <= bound}
    (Sutherland-Hodgman; vertices on the line count as inside; empty: shape (0, 2))."""
    k = vertices.shape[0]
    if k == 0:
        return vertices
    s = np.empty(k)
    inside_count = 0
    for i in range(k):
        s[i] = vertices[i, 0] * normal[0] + vertices[i, 1] * normal[1] - bound
        if s[i] <= 0:
            inside_count += 1
    if inside_count == k:
        return vertices
    if inside_count == 0:
        return np.zeros((0, 2))
    out = np.empty((2 * k, 2))
    count = 0
    for i in range(k):
        after = (i + 1) % k
        inside = s[i] <= 0
        if inside:
            out[count] = vertices[i]
            count += 1
        if inside != (s[after] <= 0):
            t = s[i] / (s[i] - s[after])
            out[count, 0] = vertices[i, 0] + t * (vertices[after, 0] - vertices[i, 0])
            out[count, 1] = vertices[i, 1] + t * (vertices[after, 1] - vertices[i, 1])
            count += 1
    return out[:count].copy()


@njit(cache=True)
def clip_to_strips(vertices: FloatArray, normals: FloatArray, values: FloatArray,
                   radii: FloatArray) -> FloatArray:
    """``enclosure.clip_to_strips``: the polygon (k, 2) cut to every |h_jᵀx - y_j| <= r_j."""
    for j in range(normals.shape[0]):
        vertices = clip_polygon(vertices, normals[j], values[j] + radii[j])
        vertices = clip_polygon(vertices, -normals[j], radii[j] - values[j])
        if vertices.shape[0] == 0:
            break
    return vertices


@njit(cache=True)
def unit_directions(generators: FloatArray) -> FloatArray:
    """``enclosure.unit_directions``: the distinct directions (2, k) of the columns of G (2, e),
    unit, folded, sorted by angle, near-parallel ones merged; none for tiny columns."""
    e = generators.shape[1]
    norms = np.empty(e)
    largest = 0.0
    for j in range(e):
        norms[j] = np.hypot(generators[0, j], generators[1, j])
        largest = max(largest, norms[j])
    keep = norms > PARALLEL_SIN * largest
    if not keep.any():
        return np.zeros((2, 0))
    g = np.ascontiguousarray(generators[:, keep])
    kept_norms = norms[keep]
    for j in range(g.shape[1]):
        g[0, j] /= kept_norms[j]
        g[1, j] /= kept_norms[j]
    g = folded_sorted(g)
    chosen = np.empty(g.shape[1], dtype=np.int64)
    chosen[0] = 0
    count = 1
    for i in range(1, g.shape[1]):
        last = chosen[count - 1]
        if abs(g[0, last] * g[1, i] - g[1, last] * g[0, i]) > PARALLEL_SIN:
            chosen[count] = i
            count += 1
    if count > 1:  # the first and the last direction can be parallel across the fold
        first, last = chosen[0], chosen[count - 1]
        if abs(g[0, first] * g[1, last] - g[1, first] * g[0, last]) <= PARALLEL_SIN:
            count -= 1
    return np.ascontiguousarray(g[:, chosen[:count]])


@njit(cache=True)
def _angles(directions: FloatArray) -> FloatArray:
    theta = np.empty(directions.shape[1])
    for i in range(directions.shape[1]):
        theta[i] = np.arctan2(directions[1, i], directions[0, i])
    return theta


@njit(cache=True)
def _gaps(theta: FloatArray) -> FloatArray:
    """The angle from each direction to the next, around the half-turn (k,)."""
    k = theta.shape[0]
    gap = np.empty(k)
    for i in range(k - 1):
        gap[i] = theta[i + 1] - theta[i]
    gap[k - 1] = theta[0] + np.pi - theta[k - 1]
    return gap


@njit(cache=True)
def tangent_weights(directions: FloatArray) -> FloatArray:
    """``enclosure.tangent_weights``: ω_i = tan(Δ_{i-1}/2) + tan(Δ_i/2) (k,)."""
    gaps = _gaps(_angles(directions))
    k = gaps.shape[0]
    weights = np.empty(k)
    for i in range(k):
        weights[i] = np.tan(gaps[i] / 2) + np.tan(gaps[i - 1] / 2)
    return weights


@njit(cache=True)
def weighted_l1_center(normals: FloatArray, middle: FloatArray, weights: FloatArray
                       ) -> FloatArray:
    """``enclosure.weighted_l1_center``: argmin_c Σ_i w_i |n_iᵀc - m_i| over the vertices of
    the arrangement of the lines n_iᵀc = m_i (the first of equal minima, pairs i < j in order)."""
    k = middle.shape[0]
    best = np.zeros(2)
    best_cost = np.inf
    found = False
    terms = np.empty(k)
    for i in range(k):
        for j in range(i + 1, k):
            det = normals[i, 0] * normals[j, 1] - normals[i, 1] * normals[j, 0]
            if not abs(det) > PARALLEL_SIN:
                continue
            x = (middle[i] * normals[j, 1] - middle[j] * normals[i, 1]) / det
            y = (normals[i, 0] * middle[j] - normals[j, 0] * middle[i]) / det
            for t in range(k):
                terms[t] = abs(x * normals[t, 0] + y * normals[t, 1] - middle[t]) * weights[t]
            cost = pairwise_sum(terms, 0, k)
            if not found or cost < best_cost:
                best[0], best[1], best_cost, found = x, y, cost, True
    if not found:
        raise ValueError("weighted_l1_center needs two non-parallel normals")
    return best


@njit(cache=True)
def symmetric_scales(theta: FloatArray, half_widths: FloatArray) -> FloatArray:
    """``enclosure.symmetric_scales`` from the directions' angles ``theta`` (k,): scales α (k,)
    of the symmetric polygon {x : |n_iᵀx| <= h_i}, redundant strips dropped round by round."""
    active = np.arange(theta.shape[0])
    while True:
        t, h = theta[active], half_widths[active]
        k = t.shape[0]
        gap = _gaps(t)
        lengths = np.empty(k)
        for i in range(k):
            prev_gap = gap[i - 1]
            lengths[i] = ((h[i - 1] - h[i] * np.cos(prev_gap)) / np.sin(prev_gap)
                          + (h[(i + 1) % k] - h[i] * np.cos(gap[i])) / np.sin(gap[i]))
        if k <= 2 or lengths.min() >= 0:
            alpha = np.zeros(theta.shape[0])
            for i in range(k):
                alpha[active[i]] = max(lengths[i], 0.0) / 2
            return alpha
        drop = np.zeros(k, dtype=np.bool_)
        dropped = 0
        for i in range(k):
            before, after = lengths[i - 1], lengths[(i + 1) % k]
            if lengths[i] < 0 and lengths[i] <= before and lengths[i] < after:
                drop[i] = True
                dropped += 1
        if dropped == 0 or k - dropped < 2:  # ties, or too few left
            drop[:] = False
            drop[np.argmin(lengths)] = True
        active = active[~drop]


@njit(cache=True)
def _centered(theta: FloatArray, normals: FloatArray, middle: FloatArray, half: FloatArray,
              weights: FloatArray) -> tuple[FloatArray, FloatArray]:
    """``enclosure._centered``: c = argmin Σ w_i |n_iᵀc - m_i|, α the symmetric polygon about c."""
    center = weighted_l1_center(normals, middle, weights)
    widened = np.empty(middle.shape[0])
    for i in range(middle.shape[0]):
        widened[i] = half[i] + abs(normals[i, 0] * center[0] + normals[i, 1] * center[1]
                                   - middle[i])
    return center, symmetric_scales(theta, widened)


@njit(cache=True)
def _product(widths: FloatArray, alpha: FloatArray) -> FloatArray:
    """A α (k,), each entry summed in numpy's pairwise order."""
    out = np.empty(widths.shape[0])
    row = np.empty(widths.shape[1])
    for i in range(widths.shape[0]):
        for j in range(widths.shape[1]):
            row[j] = widths[i, j] * alpha[j]
        out[i] = pairwise_sum(row, 0, row.shape[0])
    return out


@njit(cache=True)
def _quadratic(widths: FloatArray, alpha: FloatArray) -> float:
    """αᵀAα (half the zonotope's area)."""
    return row_sum(_product(widths, alpha) * alpha)


@njit(cache=True)
def _contain(alpha: FloatArray, widths: FloatArray, middle: FloatArray, upper: FloatArray,
             lower: FloatArray, margin: float) -> tuple[bool, FloatArray]:
    """``enclosure._contain``: α raised until (Aα)_i >= max(upper_i - n_iᵀc, n_iᵀc - lower_i)
    + margin holds for every i in floating point; (False, α) if three rounds do not get there."""
    k = alpha.shape[0]
    need = np.maximum(upper - middle, middle - lower) + margin
    used = alpha > 0
    for _ in range(3):
        deficit = need - _product(widths, alpha)
        short = deficit > 0
        if not short.any():
            return True, alpha
        reach = np.zeros(k)
        for i in range(k):
            reach[i] = row_sum(widths[i][used])
        if (reach[short] <= 0).any():
            used = np.ones(k, dtype=np.bool_)
            for i in range(k):
                reach[i] = row_sum(widths[i])
        step = ((deficit[short] + margin) / reach[short]).max()
        alpha = alpha.copy()  # one margin more than needed: rounding cannot undo the step
        for i in range(k):
            if used[i]:
                alpha[i] += step
    return False, alpha


@njit(cache=True)
def enclose_polygon(vertices: FloatArray, directions: FloatArray, size: float
                    ) -> tuple[bool, FloatArray, FloatArray]:
    """``enclosure.enclose_polygon`` with :data:`REFINE_STEPS`: (found, c (2,), G (2, k'))
    with conv(``vertices``) (m, 2) ⊆ ⟨c, G⟩, generators along the sorted unit ``directions``
    (2, k) with zero ones dropped; found is False without two directions or vertices, or when
    the containment check fails."""
    k = directions.shape[1]
    if k < 2 or vertices.shape[0] == 0:
        return False, np.zeros(2), np.zeros((2, 0))
    normals = np.empty((k, 2))
    for i in range(k):
        normals[i, 0], normals[i, 1] = -directions[1, i], directions[0, i]
    widths = np.empty((k, k))
    for i in range(k):
        for j in range(k):
            widths[i, j] = abs(normals[i, 0] * directions[0, j] + normals[i, 1] * directions[1, j])
    lower = np.full(k, np.inf)
    upper = np.full(k, -np.inf)
    for v in range(vertices.shape[0]):
        for i in range(k):
            p = vertices[v, 0] * normals[i, 0] + vertices[v, 1] * normals[i, 1]
            lower[i] = min(lower[i], p)
            upper[i] = max(upper[i], p)
    middle, half = (upper + lower) / 2, (upper - lower) / 2
    theta = _angles(directions)
    center, alpha = _centered(theta, normals, middle, half, tangent_weights(directions))
    area = _quadratic(widths, alpha)
    for _ in range(REFINE_STEPS):
        candidate, scales = _centered(theta, normals, middle, half, alpha)
        candidate_area = _quadratic(widths, scales)
        if candidate_area >= area:
            break
        center, alpha, area = candidate, scales, candidate_area
    alpha = alpha.copy()
    tiny = 1e-12 * max(alpha.max(), 0.0)
    for i in range(k):
        if alpha[i] <= tiny:
            alpha[i] = 0.0  # rounding, not generators
    projected = np.empty(k)
    for i in range(k):
        projected[i] = normals[i, 0] * center[0] + normals[i, 1] * center[1]
    ok, alpha = _contain(alpha, widths, projected, upper, lower, MARGIN * size)
    if not ok:
        return False, np.zeros(2), np.zeros((2, 0))
    used = alpha > 0
    generators = np.ascontiguousarray(directions[:, used] * alpha[used])
    return True, center, generators


@njit(cache=True)
def enclose_intersection(generators: FloatArray, normals: FloatArray, values: FloatArray,
                         radii: FloatArray, direction_generators: FloatArray
                         ) -> tuple[bool, FloatArray, FloatArray, FloatArray]:
    """``enclosure.enclose_intersection_reference`` about the zonotope's centre:
    ⟨0, G⟩ ∩ {|h_jᵀx - y_j| <= r_j} (G (2, e), H (m, 2), y and r (m,); y already shifted by
    -Hc) as a convex polygon P, enclosed along the directions of ``direction_generators``
    (2, d): (found, c (2,), G' (2, k), P (p, 2)), all about the centre; found is False when P
    is empty or no enclosure was accepted."""
    corners = zonotope_vertices(generators)
    polygon = clip_to_strips(corners, normals, values, radii)
    if polygon.shape[0] == 0:
        return False, np.zeros(2), np.zeros((2, 0)), polygon
    size = np.abs(corners).max()
    found, center, enclosure = enclose_polygon(polygon, unit_directions(direction_generators),
                                               size)
    return found, center, enclosure, polygon


@njit(cache=True)
def enclose_points(points: FloatArray, generators: FloatArray
                   ) -> tuple[bool, FloatArray, FloatArray]:
    """A 2-D zonotope holding conv(``points``) (k >= 1, 2), along the directions of
    ``generators`` (2, e) and the axes: (found, c (2,), G (2, k')), worked about the points'
    mean (numbers of the set's size, not of its position), by :func:`enclose_polygon` with the
    points' largest offset from the mean as the size (1 if none); found is False as there."""
    k = points.shape[0]
    total_x = total_y = 0.0
    for i in range(k):  # numpy's mean over axis 0: row after row
        total_x += points[i, 0]
        total_y += points[i, 1]
    origin = np.array([total_x / k, total_y / k])
    e = generators.shape[1]
    columns = np.zeros((2, e + 2))
    columns[:, :e] = generators
    columns[0, e], columns[1, e + 1] = 1.0, 1.0
    centred = np.empty((k, 2))
    size = 0.0
    for i in range(k):
        centred[i, 0], centred[i, 1] = points[i, 0] - origin[0], points[i, 1] - origin[1]
        size = max(size, abs(centred[i, 0]), abs(centred[i, 1]))
    found, center, enclosure = enclose_polygon(centred, unit_directions(columns),
                                               size if size > 0.0 else 1.0)
    return found, origin + center, enclosure


EXACT_RTOL = 1e-8
"""An enclosure whose area is within this of the polygon's counts as exact (nothing that
holds the polygon is smaller)."""

FALLBACK, EXACT, ENCLOSED = 0, 1, 2
"""What :func:`enclose_correction` found: no enclosure (the caller keeps its fallback), an
enclosure within :data:`EXACT_RTOL` of the exact polygon, or one that may be beaten."""


@njit(cache=True)
def polygon_area(vertices: FloatArray) -> float:
    """``enclosure.polygon_area``: shoelace area of the convex polygon (m, 2) (0 if m < 3)."""
    m = vertices.shape[0]
    total = 0.0
    for i in range(m):
        j = (i + 1) % m
        total += vertices[i, 0] * vertices[j, 1] - vertices[i, 1] * vertices[j, 0]
    return 0.5 * abs(total)


@njit(cache=True)
def _support(normal: FloatArray, generators: FloatArray) -> float:
    """Σ_j |nᵀg_j|: the half-width of ⟨c, G⟩ along the unit ``normal``."""
    terms = np.empty(generators.shape[1])
    for j in range(generators.shape[1]):
        terms[j] = abs(normal[0] * generators[0, j] + normal[1] * generators[1, j])
    return pairwise_sum(terms, 0, terms.shape[0])


@njit(cache=True)
def enclose_correction(center: FloatArray, generators: FloatArray, normals: FloatArray,
                       values: FloatArray, radii: FloatArray
                       ) -> tuple[int, FloatArray, FloatArray]:
    """``gains.enclose_correction`` for a 2-D ⟨c, G⟩ and unit-normal strips (H (m, 2), y and r
    (m,)), up to the ``volume`` gain that only the caller has: (status, c', G').

    FALLBACK when G is not full rank, when every strip covers Z, when Z ∩ S is empty or when
    no enclosure is accepted; else the enclosure along Z's generators and the strips' edges,
    EXACT when its area is within :data:`EXACT_RTOL` of the polygon's, ENCLOSED otherwise."""
    none = (np.zeros(2), np.zeros((2, 0)))
    if not full_rank_2d(generators):
        return FALLBACK, none[0], none[1]
    m = normals.shape[0]
    covered = True
    shifted = np.empty(m)
    for j in range(m):
        middle = normals[j, 0] * center[0] + normals[j, 1] * center[1]
        support = _support(normals[j], generators)
        covered &= middle - support >= values[j] - radii[j] and \
            middle + support <= values[j] + radii[j]
        shifted[j] = values[j] - middle
    if covered:
        return FALLBACK, none[0], none[1]
    e = generators.shape[1]
    directions = np.empty((2, e + m))
    directions[:, :e] = generators
    for j in range(m):
        directions[0, e + j], directions[1, e + j] = -normals[j, 1], normals[j, 0]
    found, offset, enclosure, polygon = enclose_intersection(generators, normals, shifted,
                                                             radii, directions)
    if not found:
        return FALLBACK, none[0], none[1]
    exact = area_2d(enclosure) <= polygon_area(polygon) * (1 + EXACT_RTOL)
    return EXACT if exact else ENCLOSED, center + offset, enclosure


@njit(cache=True)
def enclose_or_volume(center: FloatArray, generators: FloatArray, normals: FloatArray,
                      values: FloatArray, radii: FloatArray) -> tuple[FloatArray, FloatArray]:
    """``gains.enclose_correction`` for a 2-D ⟨c, G⟩ and strips (H (m, 2), y and r (m,)) in one
    call: the strips rescaled to unit normals (:func:`~sse_cosim.sets.kernels.unit_strips`),
    then :func:`enclose_correction`, kept when EXACT; else the ``volume`` gain's result
    (:func:`~sse_cosim.sets.kernels.volume_correction_2d`) on FALLBACK, or the smaller in area
    of the two; -> c' (2,), G' (2, e')."""
    _, normals, values, radii = unit_strips(normals, values, radii)
    status, enclosed_center, enclosed = enclose_correction(center, generators, normals,
                                                           values, radii)
    if status == EXACT:
        return enclosed_center, enclosed
    volume_center, volume_generators = volume_correction_2d(center, generators, normals,
                                                            values, radii)
    if status == ENCLOSED and area_2d(enclosed) < area_2d(volume_generators):
        return enclosed_center, enclosed
    return volume_center, volume_generators


@njit(cache=True)
def facet_strips(center: FloatArray, generators: FloatArray
                 ) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``strips.zonotope_facet_strips`` of a full-rank 2-D ⟨c, G⟩: the unit normals (k, 2) of
    its facets (g_j turned by +90°, the first nonzero entry made positive, parallel ones merged
    by their values rounded to 12 decimals, first occurrences in order), values nᵀc and radii
    Σ_j |nᵀg_j| (k,)."""
    e = generators.shape[1]
    normals = np.empty((e, 2))
    keys = np.empty((e, 2))
    count = 0
    for j in range(e):
        u0, u1, nonzero = facet_normal(generators, j)
        if not nonzero:
            continue
        r0, r1 = np.round(u0, 12) + 0.0, np.round(u1, 12) + 0.0
        sign = np.sign(r0) if r0 != 0 else np.sign(r1)
        k0, k1 = r0 * sign + 0.0, r1 * sign + 0.0
        seen = False
        for i in range(count):
            if keys[i, 0] == k0 and keys[i, 1] == k1:
                seen = True
                break
        if not seen:
            keys[count, 0], keys[count, 1] = k0, k1
            normals[count, 0], normals[count, 1] = u0 * sign, u1 * sign
            count += 1
    normals = normals[:count].copy()
    values = np.empty(count)
    radii = np.empty(count)
    for i in range(count):
        values[i] = normals[i, 0] * center[0] + normals[i, 1] * center[1]
        radii[i] = _support(normals[i], generators)
    return normals, values, radii


@njit(cache=True)
def enclose_fusion(centers: FloatArray, generators: FloatArray, starts: NDArray[np.int64],
                   base: int) -> tuple[bool, FloatArray, FloatArray]:
    """``fusion.enclose_fusion`` for k 2-D full-rank zonotopes ⟨c_i, G[:, starts[i]:starts[i+1]]⟩
    (``centers`` (k, 2), ``generators`` (2, E), ``starts`` (k + 1,) int) and the index ``base``
    of the smallest: (found, c, G) of the enclosure of ∩ Z_i along every input's generator
    directions -- the base clipped by the other inputs' facet strips -- or found False when
    the inputs share no point or no enclosure is accepted."""
    k = centers.shape[0]
    total = 0
    for i in range(k):
        if i != base:
            total += starts[i + 1] - starts[i]
    normals = np.empty((total, 2))
    values = np.empty(total)
    radii = np.empty(total)
    count = 0
    for i in range(k):
        if i == base:
            continue
        n_i, v_i, r_i = facet_strips(centers[i], np.ascontiguousarray(
            generators[:, starts[i]:starts[i + 1]]))
        for j in range(n_i.shape[0]):
            normals[count], values[count], radii[count] = n_i[j], v_i[j], r_i[j]
            count += 1
    base_center = centers[base]
    base_generators = np.ascontiguousarray(generators[:, starts[base]:starts[base + 1]])
    for j in range(count):
        values[j] -= normals[j, 0] * base_center[0] + normals[j, 1] * base_center[1]
    found, offset, enclosure, _ = enclose_intersection(
        base_generators, normals[:count].copy(), values[:count].copy(), radii[:count].copy(),
        generators)
    return found, base_center + offset, enclosure

"""Exact 2-D intersections as convex polygons, and zonotope enclosures of them.

This is the geometry behind the ``enclose`` correction (:mod:`sse_cosim.sets.gains`) and the
``enclose`` fusion (:mod:`sse_cosim.sets.fusion`): compute the exact intersection P as a convex
polygon (half-plane clipping, :func:`clip_polygon`), then enclose P in a zonotope whose
generator directions are fixed (:func:`enclose_polygon`). The functions here are the NumPy
reference; the loop runs their compiled twins (:mod:`sse_cosim.sets.enclosure_kernels`), which
the tests check against them.

With fixed unit directions D = [d_1, ..., d_k] and scales α >= 0 the zonotope is
⟨c, D diag(α)⟩; its half-width along the unit normal n_i ⊥ d_i is (Aα)_i with
A_ij = |n_iᵀd_j| (A symmetric, zero diagonal). Such a zonotope is the intersection of the strips
|n_iᵀ(x - c)| <= (Aα)_i over its directions, so it contains P iff for every i

    max_j |n_iᵀ(v_j - c)| <= (Aα)_i          (v_j the vertices of P),

which is linear in (c, α): the least perimeter 4 Σ α_i is an LP (:func:`least_perimeter_lp`,
scipy HiGHS, the reference). It is solved without a solver instead: for a fixed c the smallest
such zonotope, by inclusion and so in area and perimeter alike, is the centrally symmetric
polygon with half-widths h_i(c) = max_j |n_iᵀ(v_j - c)| (:func:`symmetric_scales`), and c
comes from a weighted L1 problem in the plane (:func:`least_perimeter`), then is re-centered
for area (:func:`enclose_polygon`). When D holds every edge direction of P (it does: Z's
generator directions and the strips' edge directions for Z ∩ strips, the inputs' generator
directions for ∩ Z_j), a centrally symmetric P is recovered exactly.

Soundness does not rest on any of that being optimal, nor on rounding: the containment
inequalities are re-evaluated in floating point with a margin (:data:`MARGIN` times the size
of the input), and the scales of the directions in use are raised until every one holds
(:func:`_contain`), or the enclosure is rejected (``None``: the callers then keep the
Proposition 1 / 2 result).
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache

import numpy as np
from numpy.typing import NDArray

from sse_cosim.sets import portable
from sse_cosim.sets.enclosure_kernels import EXACT_RTOL, MARGIN, PARALLEL_SIN, REFINE_STEPS
from sse_cosim.sets.lp import linprog
from sse_cosim.sets.portable import matmul
from sse_cosim.sets.strips import Strips
from sse_cosim.sets.zonotope import FloatArray, Zonotope


def clip_polygon(vertices: FloatArray, normal: FloatArray, bound: float) -> FloatArray:
    """The convex polygon ``vertices`` (k, 2), in order, cut to {x : nᵀx <= bound}.

    Sutherland-Hodgman in one vectorized pass: each vertex inside is kept, and each edge that
    crosses the line contributes its crossing point, in boundary order. Vertices on the line
    count as inside. A segment (k = 2) or a point (k = 1) is clipped the same way; an empty
    result has shape (0, 2).
    """
    if len(vertices) == 0:
        return vertices
    s = matmul(vertices, normal) - bound
    inside = s <= 0
    if inside.all():
        return vertices
    if not inside.any():
        return np.zeros((0, 2))
    after = np.arange(1, len(vertices) + 1) % len(vertices)  # index of the next vertex
    following, s_next = vertices[after], s[after]
    crossing = inside != inside[after]
    t = np.divide(s, s - s_next, out=np.zeros_like(s), where=crossing)
    points = np.stack([vertices, vertices + t[:, None] * (following - vertices)], axis=1)
    return points[np.stack([inside, crossing], axis=1)]


def clip_to_strips(vertices: FloatArray, normals: FloatArray, values: FloatArray,
                   radii: FloatArray) -> FloatArray:
    """The convex polygon ``vertices`` (k, 2) cut to every strip |h_jᵀx - y_j| <= r_j."""
    for normal, value, radius in zip(normals, values, radii, strict=True):
        vertices = clip_polygon(vertices, normal, value + radius)
        vertices = clip_polygon(vertices, -normal, radius - value)
        if len(vertices) == 0:
            break
    return vertices


def unit_directions(generators: FloatArray) -> FloatArray:
    """The distinct directions of the columns of ``generators`` (2, e) as unit vectors (2, k),
    folded into the upper half-plane and sorted by angle; directions closer than
    :data:`PARALLEL_SIN` are merged (the first of each run is kept). Columns shorter than
    :data:`PARALLEL_SIN` times the longest (rounding residue of earlier updates) give none."""
    norms = portable.hypot(generators[0], generators[1])
    keep = norms > PARALLEL_SIN * norms.max(initial=0.0)
    if not keep.any():
        return np.zeros((2, 0))
    g = generators[:, keep] / norms[keep]
    flip = (g[1] < 0) | ((g[1] == 0) & (g[0] < 0))
    g = np.where(flip, -g, g)
    g = g[:, np.argsort(portable.arctan2(g[1], g[0]), kind="stable")]
    keep = [0]
    for i in range(1, g.shape[1]):
        last = g[:, keep[-1]]
        if abs(last[0] * g[1, i] - last[1] * g[0, i]) > PARALLEL_SIN:
            keep.append(i)
    if len(keep) > 1:  # the first and the last direction can be parallel across the fold
        first, last = g[:, keep[0]], g[:, keep[-1]]
        if abs(first[0] * last[1] - first[1] * last[0]) <= PARALLEL_SIN:
            keep.pop()
    return g[:, keep]


def support_intervals(vertices: FloatArray, normals: FloatArray) -> tuple[FloatArray, FloatArray]:
    """[min, max] of n_iᵀv over the vertices (m, 2) for every normal (k, 2): each (k,)."""
    projections = matmul(vertices, normals.T)
    return projections.min(axis=0), projections.max(axis=0)


def _normals(directions: FloatArray) -> FloatArray:
    """n_i = d_i turned by +90° (k, 2): the facet normal of the generator along d_i."""
    return np.stack([-directions[1], directions[0]], axis=1)


def tangent_weights(directions: FloatArray) -> FloatArray:
    """ω_i = tan(Δ_{i-1}/2) + tan(Δ_i/2) for directions sorted by angle in [0, π) (Δ: the gaps
    between consecutive directions, around the half-turn): (k,).

    ω/2 are the scales of the zonotope with these directions circumscribed about the unit
    disc (A ω/2 = 1), and the perimeter of a zonotope with these directions whose every
    direction is an edge is 2 Σ ω_i h_i, with h_i its half-width along n_i.
    """
    theta = portable.arctan2(directions[1], directions[0])
    gaps = np.diff(np.concatenate([theta, theta[:1] + np.pi]))
    return portable.tan(gaps / 2) + portable.tan(np.roll(gaps, 1) / 2)


@cache
def _pairs(k: int) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Every pair i < j of range(k), as two read-only index arrays."""
    first, second = np.triu_indices(k, 1)
    first.setflags(write=False)
    second.setflags(write=False)
    return first, second


def weighted_l1_center(normals: FloatArray, middle: FloatArray, weights: FloatArray
                       ) -> FloatArray:
    """argmin_c Σ_i w_i |n_iᵀc - m_i| (w >= 0): convex and piecewise linear, so a minimum lies
    on a vertex of the arrangement of the lines n_iᵀc = m_i; all of them are scored at once.
    """
    i, j = _pairs(len(middle))
    det = normals[i, 0] * normals[j, 1] - normals[i, 1] * normals[j, 0]
    ok = np.abs(det) > PARALLEL_SIN
    i, j, det = i[ok], j[ok], det[ok]
    points = np.stack([(middle[i] * normals[j, 1] - middle[j] * normals[i, 1]) / det,
                       (normals[i, 0] * middle[j] - normals[j, 0] * middle[i]) / det], axis=1)
    cost = (np.abs(matmul(points, normals.T) - middle) * weights).sum(axis=1)
    return points[int(np.argmin(cost))]


def symmetric_scales(directions: FloatArray, half_widths: FloatArray) -> FloatArray:
    """Scales α (k,) of the centrally symmetric polygon {x : |n_iᵀx| <= h_i} (normals of the
    sorted ``directions``), a zonotope along them: α_i is half its edge along d_i.

    Edge lengths from the support numbers: L_j = (h_prev - h_j cos Δ)/sin Δ + (h_next -
    h_j cos Δ')/sin Δ' around the normals ±n_i (Δ, Δ': the angles to the neighbours). A
    negative L_j marks a redundant strip: its neighbours' normals span n_j positively and their
    lines meet inside it, so their wedge lies in it. Each round drops the strips whose L is
    negative and a local minimum (never two neighbours, so each keeps the wedge that makes it
    redundant) and recomputes, until every edge is >= 0 or two directions are left.
    """
    theta = portable.arctan2(directions[1], directions[0])
    active = np.arange(len(theta))
    while True:
        t, h = theta[active], half_widths[active]
        gap = np.empty_like(t)  # angle from each direction to the next, around the half-turn
        gap[:-1] = t[1:] - t[:-1]
        gap[-1] = t[0] + np.pi - t[-1]
        prev_gap = np.concatenate([gap[-1:], gap[:-1]])
        h_next = np.concatenate([h[1:], h[:1]])
        h_prev = np.concatenate([h[-1:], h[:-1]])
        lengths = ((h_prev - h * portable.cos(prev_gap)) / portable.sin(prev_gap)
                   + (h_next - h * portable.cos(gap)) / portable.sin(gap))
        if len(active) <= 2 or lengths.min() >= 0:
            alpha = np.zeros(len(theta))
            alpha[active] = np.maximum(lengths, 0.0) / 2
            return alpha
        after = np.concatenate([lengths[1:], lengths[:1]])
        before = np.concatenate([lengths[-1:], lengths[:-1]])
        drop = (lengths < 0) & (lengths <= before) & (lengths < after)
        if not drop.any() or len(active) - drop.sum() < 2:  # ties, or too few left
            drop[:] = False
            drop[int(np.argmin(lengths))] = True
        active = active[~drop]


def least_perimeter(vertices: FloatArray, directions: FloatArray
                    ) -> tuple[FloatArray, FloatArray]:
    """(c, α): the least-perimeter zonotope ⟨c, D diag(α)⟩ ⊇ conv(``vertices``) (m, 2) along the
    sorted unit ``directions`` D (2, k >= 2), without an LP.

    For a fixed c the best is the symmetric polygon of half-widths
    h_i(c) = w_i + |n_iᵀc - m_i| (w, m: half-width and middle of the vertices along n_i). Its
    perimeter is at least 2 Σ ω_i h_i(c) (:func:`tangent_weights`: ω/2 is dual feasible for
    the LP, as A ω/2 = 1), with equality when every direction is an edge. c minimizes that
    bound (:func:`weighted_l1_center`), so whenever the result has every direction as an edge
    it is the LP optimum (:func:`least_perimeter_lp`); otherwise it is still an enclosure.
    """
    normals = _normals(directions)
    lower, upper = support_intervals(vertices, normals)
    return _centered(directions, normals, (upper + lower) / 2, (upper - lower) / 2,
                     tangent_weights(directions))


def _centered(directions: FloatArray, normals: FloatArray, middle: FloatArray,
              half: FloatArray, weights: FloatArray) -> tuple[FloatArray, FloatArray]:
    """(c, α) with c = argmin Σ w_i |n_iᵀc - m_i| and α the symmetric polygon about c."""
    center = weighted_l1_center(normals, middle, weights)
    return center, symmetric_scales(directions, half + np.abs(matmul(normals, center) - middle))


def least_perimeter_lp(vertices: FloatArray, directions: FloatArray
                       ) -> tuple[FloatArray, FloatArray] | None:
    """The reference for :func:`least_perimeter`: min Σ α over (c, α >= 0) subject to
    n_iᵀc + (Aα)_i >= max_j n_iᵀv_j and n_iᵀc - (Aα)_i <= min_j n_iᵀv_j (scipy HiGHS, in
    units of the vertices' size); None if the solver fails. Not checked for containment."""
    k = directions.shape[1]
    normals = _normals(directions)
    widths = np.abs(matmul(normals, directions))
    lower, upper = support_intervals(vertices, normals)
    scale = float(np.abs(vertices).max()) or 1.0
    result = linprog(np.concatenate([np.zeros(2), np.ones(k)]),
                     A_ub=np.block([[-normals, -widths], [normals, -widths]]),
                     b_ub=np.concatenate([-upper, lower]) / scale,
                     bounds=[(None, None)] * 2 + [(0, None)] * k, method="highs")
    if result.status != 0:
        return None
    return result.x[:2] * scale, np.maximum(result.x[2:], 0.0) * scale


def enclose_polygon(vertices: FloatArray, directions: FloatArray, size: float,
                    refine: int | None = None) -> tuple[FloatArray, FloatArray] | None:
    """A zonotope ⟨c, G⟩ ⊇ conv(``vertices``) (m, 2) with generators along ``directions``
    (2, k unit vectors sorted by angle in [0, π), pairwise non-parallel: as from
    :func:`unit_directions`); ``size`` is the scale of the input set (the margin of the
    containment test is :data:`MARGIN` × ``size``).

    Starts from the least-perimeter enclosure (:func:`least_perimeter`), then up to
    ``refine`` (default :data:`REFINE_STEPS`) times re-centers to lower the area: moving the
    center off m_i along n_i widens the strip i on both sides, which costs about 2 L_i per
    unit (L_i = 2α_i the edge along d_i), so the new c minimizes Σ α_i |n_iᵀc - m_i|; it is
    kept only if the area drops. Finally α is raised until the containment inequalities hold
    with the margin (:func:`_contain`). Returns (c, G) with zero generators dropped, or None
    if there are fewer than two directions or no vertices.
    """
    if directions.shape[1] < 2 or len(vertices) == 0:
        return None
    normals = _normals(directions)
    widths = np.abs(matmul(normals, directions))
    lower, upper = support_intervals(vertices, normals)
    middle, half = (upper + lower) / 2, (upper - lower) / 2
    center, alpha = _centered(directions, normals, middle, half, tangent_weights(directions))
    area = matmul(matmul(alpha, widths), alpha)  # area / 2
    for _ in range(REFINE_STEPS if refine is None else refine):
        candidate, scales = _centered(directions, normals, middle, half, alpha)
        if matmul(matmul(scales, widths), scales) >= area:
            break
        center, alpha, area = candidate, scales, matmul(matmul(scales, widths), scales)
    alpha[alpha <= 1e-12 * alpha.max(initial=0.0)] = 0.0  # rounding, not generators
    alpha = _contain(alpha, widths, matmul(normals, center), upper, lower, MARGIN * size)
    if alpha is None:
        return None
    used = alpha > 0
    return center, directions[:, used] * alpha[used]


def enclose_intersection_reference(base: Zonotope, strips: Strips, generators: FloatArray
                                   ) -> tuple[Zonotope, FloatArray] | None:
    """``base`` ∩ ``strips`` (2-D, ``base`` full-dimensional) exactly as a convex polygon P,
    enclosed in a zonotope along the directions of the columns of ``generators`` (2, e):
    (the enclosure, P's vertices (m, 2) about ``base``'s center), or None when P is empty or
    no enclosure was accepted. Works about ``base``'s center, so that the clipping and the
    enclosure see numbers of the set's size, not of its position. The NumPy reference of
    :func:`~sse_cosim.sets.enclosure_kernels.enclose_intersection`."""
    corners = Zonotope.unchecked(np.zeros(2), base.generators).vertices()
    polygon = clip_to_strips(corners, strips.normals,
                             strips.values - matmul(strips.normals, base.center), strips.radii)
    if len(polygon) == 0:
        return None
    found = enclose_polygon(polygon, unit_directions(generators), float(np.abs(corners).max()))
    if found is None:
        return None
    center, enclosure_generators = found
    return Zonotope.unchecked(base.center + center, enclosure_generators), polygon


def _contain(alpha: FloatArray, widths: FloatArray, middle: FloatArray, upper: FloatArray,
             lower: FloatArray, margin: float) -> FloatArray | None:
    """α raised until (Aα)_i >= max(upper_i - n_iᵀc, n_iᵀc - lower_i) + margin holds for every
    i in floating point (by up to one more margin), or None if three rounds do not get there.

    Each round adds the same amount to the scales of the directions in use, so no generator
    appears; if those cannot widen the set along some normal (fewer than two of them: a
    point or a segment, e.g. for a polygon that is one), every direction gets it.
    """
    need = np.maximum(upper - middle, middle - lower) + margin
    used = alpha > 0
    for _ in range(3):
        deficit = need - matmul(widths, alpha)
        short = deficit > 0
        if not short.any():
            return alpha
        reach = widths[:, used].sum(axis=1)  # growth of each half-width per unit of α_used
        if (reach[short] <= 0).any():
            used = np.ones_like(used)
            reach = widths.sum(axis=1)
        alpha = alpha.copy()  # one margin more than needed: rounding cannot undo the step
        alpha[used] += ((deficit[short] + margin) / reach[short]).max()
    return None


def polygon_area(vertices: FloatArray) -> float:
    """Area of the convex polygon with ``vertices`` (m, 2) in order (shoelace; 0 if m < 3)."""
    x, y = vertices[:, 0], vertices[:, 1]
    return 0.5 * abs(float(matmul(x, np.roll(y, -1)) - matmul(y, np.roll(x, -1))))


def smaller_enclosure(enclosed: Zonotope, polygon: FloatArray,
                      alternative: Callable[[], Zonotope]) -> Zonotope:
    """The smaller in area of ``enclosed`` and ``alternative()``, two sets that both hold the
    polygon (its vertices (m, 2) in order, in any frame). The alternative is not built when
    ``enclosed`` is within :data:`EXACT_RTOL` of the polygon's area: nothing holding the
    polygon is smaller than it."""
    if enclosed.volume() <= polygon_area(polygon) * (1 + EXACT_RTOL):
        return enclosed
    other = alternative()
    return enclosed if enclosed.volume() < other.volume() else other

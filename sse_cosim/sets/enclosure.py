"""Exact 2-D intersections as convex polygons, and zonotope enclosures of them.

This is the geometry behind the ``enclose`` correction (:mod:`sse_cosim.sets.gains`) and the
``enclose`` fusion (:mod:`sse_cosim.sets.fusion`): compute the exact intersection P as a convex
polygon (half-plane clipping in NumPy, :func:`clip_polygon`), then enclose P in a zonotope whose
generator directions are fixed (:func:`enclose_polygon`).

With fixed unit directions D = [d_1, ..., d_k] and scales α >= 0 the zonotope is
⟨c, D diag(α)⟩; its half-width along the unit normal n_i ⊥ d_i is (Aα)_i with
A_ij = |n_iᵀd_j| (A symmetric, zero diagonal). Such a zonotope is the intersection of the strips
|n_iᵀ(x - c)| <= (Aα)_i over its directions, so it contains P iff for every i

    max_j |n_iᵀ(v_j - c)| <= (Aα)_i          (v_j the vertices of P),

which is linear in (c, α). For a fixed c the smallest such zonotope (by inclusion, hence in
area and perimeter alike) is the symmetric polygon with those half-widths; over c,
:func:`enclose_polygon` minimizes the perimeter 4 Σ α_i (an LP, scipy HiGHS), a convex
problem. When D holds every edge direction of P (it does for Z ∩ strips: Z's generator
directions and the strips' edge directions), a centrally symmetric P is recovered exactly.

Soundness does not rest on the LP's tolerances: the containment inequalities are re-evaluated
in floating point with a small margin (:data:`MARGIN` times the size of the input), and the
scales of the directions in use are raised until every one holds, or the enclosure is
rejected (``None``: the callers then fall back to a Proposition 1 / 2 result).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linprog

from sse_cosim.sets.zonotope import FloatArray

MARGIN = 1e-10
"""Safety margin of the containment test, relative to the size of the input set: covers the
rounding of the clipped polygon's vertices and of the zonotope's half-widths."""

PARALLEL_SIN = 1e-9
"""Directions whose angle has a sine below this are merged into one."""


def clip_polygon(vertices: FloatArray, normal: FloatArray, bound: float) -> FloatArray:
    """The convex polygon ``vertices`` (k, 2), in order, cut to {x : nᵀx <= bound}.

    Sutherland-Hodgman in one vectorized pass: each vertex inside is kept, and each edge that
    crosses the line contributes its crossing point, in boundary order. Vertices on the line
    count as inside. A segment (k = 2) or a point (k = 1) is clipped the same way; an empty
    result has shape (0, 2).
    """
    if len(vertices) == 0:
        return vertices
    s = vertices @ normal - bound
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
    """The distinct directions of the nonzero columns of ``generators`` (2, e) as unit vectors
    (2, k), folded into the upper half-plane and sorted by angle; directions closer than
    :data:`PARALLEL_SIN` are merged (the first of each run is kept)."""
    g = generators[:, (generators[0] != 0) | (generators[1] != 0)]
    if g.shape[1] == 0:
        return np.zeros((2, 0))
    flip = (g[1] < 0) | ((g[1] == 0) & (g[0] < 0))
    g = np.where(flip, -g, g)
    g = g / np.sqrt((g * g).sum(axis=0))
    g = g[:, np.argsort(np.arctan2(g[1], g[0]), kind="stable")]
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


def enclose_polygon(vertices: FloatArray, directions: FloatArray, size: float
                    ) -> tuple[FloatArray, FloatArray] | None:
    """A zonotope ⟨c, G⟩ ⊇ conv(``vertices``) (m, 2) with generators along ``directions``
    (2, k unit vectors, pairwise non-parallel), of least perimeter; ``size`` is the scale of
    the input set (the margin of the containment test is :data:`MARGIN` × ``size``).

    Returns (c, G) with zero generators dropped, or None if there are fewer than two
    directions, the LP fails, or its result cannot be made to contain every vertex.
    """
    k = directions.shape[1]
    if k < 2 or len(vertices) == 0:
        return None
    normals = np.stack([-directions[1], directions[0]], axis=1)  # (k, 2), n_i ⊥ d_i
    widths = np.abs(normals @ directions)  # A_ij = |n_iᵀ d_j|
    projections = vertices @ normals.T  # (m, k)
    upper, lower = projections.max(axis=0), projections.min(axis=0)
    scale = float(np.abs(vertices).max()) or 1.0
    # Variables (c, α), in units of ``scale``: min Σ α s.t. n_iᵀc + (Aα)_i >= upper_i and
    # n_iᵀc - (Aα)_i <= lower_i.
    a_ub = np.block([[-normals, -widths], [normals, -widths]])
    b_ub = np.concatenate([-upper, lower]) / scale
    cost = np.concatenate([np.zeros(2), np.ones(k)])
    result = linprog(cost, A_ub=a_ub, b_ub=b_ub, bounds=[(None, None)] * 2 + [(0, None)] * k,
                     method="highs")
    if result.status != 0:
        return None
    center = result.x[:2] * scale
    alpha = np.maximum(result.x[2:], 0.0) * scale
    alpha[alpha <= 1e-9 * alpha.max(initial=0.0)] = 0.0  # LP noise, not generators
    alpha = _contain(alpha, widths, normals @ center, upper, lower, MARGIN * size)
    if alpha is None:
        return None
    used = alpha > 0
    return center, directions[:, used] * alpha[used]


def _contain(alpha: FloatArray, widths: FloatArray, middle: FloatArray, upper: FloatArray,
             lower: FloatArray, margin: float) -> FloatArray | None:
    """α raised until (Aα)_i >= max(upper_i - n_iᵀc, n_iᵀc - lower_i) + margin holds for every
    i in floating point, or None if three rounds do not get there.

    Each round adds the same amount to the scales of the directions in use, so no generator
    appears; if those cannot widen the set along some normal (fewer than two of them: a
    point or a segment, e.g. for a polygon that is one), every direction gets it.
    """
    need = np.maximum(upper - middle, middle - lower) + margin
    used = alpha > 0
    for _ in range(3):
        deficit = need - widths @ alpha
        short = deficit > 0
        if not short.any():
            return alpha
        reach = widths[:, used].sum(axis=1)  # growth of each half-width per unit of α_used
        if (reach[short] <= 0).any():
            used = np.ones_like(used)
            reach = widths.sum(axis=1)
        alpha = alpha.copy()
        alpha[used] += (deficit[short] / reach[short]).max() * (1 + 1e-9)
    return None

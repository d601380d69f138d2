"""Compiled kernels (numba, cached on disk) of the polygon recursion of
:mod:`sse_cosim.world.assumptions`, on plain float64 arrays.

:func:`admits_walk` runs ``admits``'s recursion over a whole walk,

    I_0 = P_N(p_0, eps),   I_k = (I_{k-1} (+) P_N(v dt)) ∩ P_N(p_k, eps),

with its whole-polygon fast path (:func:`in_polygon`), one step at a time by
:func:`polygon_step`. Its NumPy/shapely reference is ``assumptions.admits_reference``
(``minkowski_sum`` by a merge of edges, ``intersect`` by GEOS);
``tests/world/test_assumption_kernels.py`` compares the two within the bound stated there.

Representation. Every polygon of the recursion has its edges in the N directions of the unit
polygon U = ``unit_polygon(N)`` (P_N's do, and so do Minkowski sums and intersections of such
polygons). Let m_j be the midpoint of U's edge j, from vertex U_j to U_(j+1): its outward
normal, of norm cos(pi/N); P_N(c, r) = {x : m_j·(x - c) <= r |m_j|² for all j}. Such a polygon
A is kept as its *sector vertices* a (N, 2): a_j is the point of A farthest in the direction
U_j, which lies strictly between m_(j-1) and m_j, so a_j is a vertex of A (the same vertex for
neighbouring sectors where A has no edge in between; a point has all N the same). A is the
hull of the a_j, counter-clockwise in j; a_(j-1) and a_j are the ends of A's edge j - 1 (or
the same point), and the extreme points in the direction m_j are a_j and a_(j+1).

- **Sum.** A (+) r U has the sector vertices a_j + r U_j (the extreme points of a Minkowski
  sum add): no merge of edges by angle, nothing for rounding to derange.
- **Intersection** with D = P_N(p, eps), whose sector vertices are p + eps U_j: when every
  support value of the sum G, max(m_j·g_j, m_j·g_(j+1)), is at least D's, G holds D (both
  have their edges in the N directions) and the set is the whole D. Otherwise G is cut by
  each half-plane m_k·x <= b_k of D that G's support value exceeds (the others cannot cut),
  in turn (:func:`_clip`): the sectors whose vertex lies beyond the line form one run around
  k, k + 1 (m_k·g_j is unimodal in j with its top at those two); their new vertex is where the
  boundary enters the line (sectors lo..k) or leaves it (sectors k + 1..hi): the point of
  the edge (g_(lo-1), g_lo) or (g_hi, g_(hi+1)) where the line crosses it, as
  Sutherland-Hodgman computes it. A run of all N sectors is an empty set. With eps = 0, D is
  the point p: in G or not.

Soundness. Every point the kernel computes is a point of the exact operation applied to the
previous step's computed points, up to the rounding of a few operations on coordinates: a
vertex of the sum is a_j + r U_j (one product, one sum); a cut's new vertex is a point of a
segment between two current vertices whose distance to the line is rounded relative to the
segment's ends, whatever the angle between them; a vertex or a half-plane is judged inside
only if it is within rounding of it. So the hull of step k's points lies within r_k of
(hull of step k - 1's (+) P_N(v dt)) ∩ P_N(p_k, eps), where r_k is a few tens of units in
the last place of the walk's coordinates (local frame: relative to its first position) --
below 1e-11 m for a walk within 1 km of its start. The rounding does not add up over the
steps: as P_N(c, rho) (+) disc(r) ⊆ disc(c, rho + r), induction gives that a non-empty set at
every step proves a path for the jitter eps + r and the step v dt + r, r the largest r_k --
five orders of magnitude below ``TOLERANCE_M`` (1e-6 m) and eight below ``least_jitter``'s
rounding up to 1 mm. Conversely the kernel's set holds the exact recursion's for
eps - r / cos(pi/N) and v dt - r / cos(pi/N) (a vertex or a cut is misjudged only where two
values agree up to rounding), so its answers differ from the reference's only for walks
within that of the bounds.

numba caches the machine code in ``__pycache__`` next to this file (ignored by git).
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


@njit(cache=True)
def in_polygon(point: FloatArray, mids: FloatArray, radius: float) -> bool:
    """Whether ``point`` (2,) lies in P_N(0, ``radius``): m_j·x <= radius |m_j|² for each
    midpoint m_j (N, 2) of the unit polygon's edges (``assumptions._in_polygon``)."""
    for j in range(mids.shape[0]):
        m0, m1 = mids[j, 0], mids[j, 1]
        if not m0 * point[0] + m1 * point[1] <= radius * (m0 * m0 + m1 * m1):
            return False
    return True


@njit(cache=True)
def disc(center: FloatArray, radius: float, unit: FloatArray) -> FloatArray:
    """The sector vertices (N, 2) of P_N(center, radius): center + radius U_j (all the centre
    for radius 0)."""
    out = np.empty((unit.shape[0], 2))
    for j in range(unit.shape[0]):
        out[j, 0] = center[0] + radius * unit[j, 0]
        out[j, 1] = center[1] + radius * unit[j, 1]
    return out


@njit(cache=True)
def _row(j: int, n: int, first: int, length: int) -> int:
    """The row of the sector vertices holding sector ``j``'s (any integer, taken mod n): the
    pending block's first row for the ``length`` sectors from ``first`` (see :func:`_clip`)."""
    return first if (j - first) % n < length else j % n


@njit(cache=True)
def _beyond(sectors: FloatArray, row: int, normal: FloatArray, bound: float) -> float:
    """m·s - b for the vertex in ``row``: positive beyond the line m·x = b."""
    return normal[0] * sectors[row, 0] + normal[1] * sectors[row, 1] - bound


@njit(cache=True)
def _crossing(sectors: FloatArray, inside: int, outside: int, normal: FloatArray,
              bound: float) -> tuple[float, float]:
    """Where the segment from the vertex in row ``inside`` (not beyond the line) to the one
    in row ``outside`` (beyond) meets the line (Sutherland-Hodgman's point)."""
    d_in = _beyond(sectors, inside, normal, bound)
    t = d_in / (d_in - _beyond(sectors, outside, normal, bound))
    return (sectors[inside, 0] + t * (sectors[outside, 0] - sectors[inside, 0]),
            sectors[inside, 1] + t * (sectors[outside, 1] - sectors[inside, 1]))


@njit(cache=True)
def _fill(sectors: FloatArray, first: int, length: int) -> None:
    """Write the pending block's vertex (row ``first``) into its other rows."""
    n = sectors.shape[0]
    for j in range(first + 1, first + length):
        sectors[j % n] = sectors[first]


@njit(cache=True)
def _clip(sectors: FloatArray, mids: FloatArray, bound: FloatArray,
         excess: FloatArray) -> bool:
    """Cut the polygon with sector vertices (N, 2) in place by every half-plane
    m_k·x <= bound[k] (``mids`` (N, 2), ``bound`` (N,)) with excess[k] > 0 (N,), k in turn;
    False if nothing is left.

    A cut's run of sectors beyond the line lo..hi (integers taken mod N, around k, k + 1)
    takes the point where the boundary enters the line for the sectors up to k, and the one
    where it leaves for the rest. The second kind is kept pending -- its vertex in row k + 1
    only, :func:`_row` -- as the next cuts usually take that whole block into their runs
    again (each pushes it one sector on), so each cut costs O(1) plus the sectors it newly
    reaches rather than O(N); a pending block that a run does not take is written out."""
    n = sectors.shape[0]
    first = length = 0  # the pending block: `length` sectors from `first`
    for k in range(n):
        if not excess[k] > 0.0:
            continue
        m, b = mids[k], bound[k]
        beyond_k = _beyond(sectors, _row(k, n, first, length), m, b) > 0.0
        beyond_next = _beyond(sectors, _row(k + 1, n, first, length), m, b) > 0.0
        if not (beyond_k or beyond_next):
            continue
        lo = k if beyond_k else k + 1
        hi = k + 1 if beyond_next else k
        if (lo - first) % n < length:  # into the pending block: all of it is beyond
            lo -= (lo - first) % n
        if (hi - first) % n < length:
            hi += length - 1 - (hi - first) % n
        while hi - lo + 1 < n and _beyond(sectors, _row(lo - 1, n, first, length), m, b) > 0.0:
            lo -= 1
            if (lo - first) % n < length:
                lo -= (lo - first) % n
        while hi - lo + 1 < n and _beyond(sectors, _row(hi + 1, n, first, length), m, b) > 0.0:
            hi += 1
            if (hi - first) % n < length:
                hi += length - 1 - (hi - first) % n
        if hi - lo + 1 >= n:
            return False
        enter = _crossing(sectors, _row(lo - 1, n, first, length),
                          _row(lo, n, first, length), m, b)
        leave = _crossing(sectors, _row(hi + 1, n, first, length),
                          _row(hi, n, first, length), m, b)
        if length > 0 and (first - lo) % n > hi - lo:  # the pending block is not in the run
            _fill(sectors, first, length)
        for j in range(lo, k + 1):
            sectors[j % n, 0], sectors[j % n, 1] = enter
        first, length = (k + 1) % n, max(hi - k, 0)
        if length > 0:
            sectors[first, 0], sectors[first, 1] = leave
    _fill(sectors, first, length)
    return True


@njit(cache=True)
def polygon_step(sectors: FloatArray, position: FloatArray, unit: FloatArray,
                 mids: FloatArray, step_m: float, jitter_m: float) -> tuple[bool, bool]:
    """One step of the recursion, in place on the sector vertices (N, 2) of I:
    (I (+) P_N(v dt)) ∩ P_N(p, eps) for p = ``position`` (2,), the unit polygon ``unit``
    (N, 2) and its edge midpoints ``mids`` (N, 2). Returns whether the result is non-empty
    (else ``sectors`` is left undefined) and whether it is the whole P_N(p, eps)."""
    n = unit.shape[0]
    for j in range(n):
        sectors[j, 0] += step_m * unit[j, 0]
        sectors[j, 1] += step_m * unit[j, 1]
    bound = np.empty(n)
    excess = np.empty(n)  # the sum's support value beyond P_N(p, eps)'s, by direction
    for k in range(n):
        m0, m1 = mids[k, 0], mids[k, 1]
        bound[k] = m0 * position[0] + m1 * position[1] + jitter_m * (m0 * m0 + m1 * m1)
        excess[k] = max(_beyond(sectors, k, mids[k], bound[k]),
                        _beyond(sectors, (k + 1) % n, mids[k], bound[k]))
    if (excess >= 0.0).all():  # the sum holds P_N(p, eps)
        sectors[:] = disc(position, jitter_m, unit)
        return True, True
    if jitter_m == 0.0:  # P_N(p, 0) is the point p, and it is not in the sum
        return False, False
    return _clip(sectors, mids, bound, excess), False


@njit(cache=True)
def admits_walk(positions: FloatArray, unit: FloatArray, mids: FloatArray, step_m: float,
                jitter_m: float) -> bool:
    """Whether the recursion stays non-empty along ``positions`` (k, 2) (``assumptions.admits``
    after its cut and shift to the first position): the set starts as the whole P_N(p_0, eps)
    and stays whole, without a polygon operation, while each step p - c lies in P_N(0, v dt)
    (c the centre of the whole set, :func:`in_polygon`); otherwise :func:`polygon_step`, which
    may find the whole polygon again. ``unit`` (N, 2), ``mids`` (N, 2) as there."""
    center = positions[0].copy()
    whole = True
    sectors = np.empty((unit.shape[0], 2))
    step = np.empty(2)
    for k in range(1, positions.shape[0]):
        position = positions[k]
        if whole:
            step[0], step[1] = position[0] - center[0], position[1] - center[1]
            if in_polygon(step, mids, step_m):
                center[:] = position
                continue
            sectors[:] = disc(center, jitter_m, unit)
        nonempty, whole = polygon_step(sectors, position, unit, mids, step_m, jitter_m)
        if not nonempty:
            return False
        if whole:
            center[:] = position
    return True

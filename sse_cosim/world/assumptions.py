"""Does the simulated world keep the estimator's pedestrian assumption? Pure geometry, no SUMO.

The estimator (:mod:`sse_cosim.estimation.motion`) assumes that every pedestrian's position is
p_k = s_k + e_k: a path s whose steps are at most v dt long plus a jitter ||e_k|| <= eps. The
path points that agree with the positions seen so far are

    S_0 = disc(p_0, eps),   S_k = (S_{k-1} (+) disc(v dt)) ∩ disc(p_k, eps),

and the world keeps the assumption up to step k exactly while S_k is not empty (a path exists:
walk back from any point of S_k). S_k is convex; this module follows it with polygons.

Representation and tolerance. ``P_N(c, rho)`` is the regular N-gon inscribed in disc(c, rho)
(vertices on the circle), so disc(c, rho cos(pi/N)) ⊆ P_N(c, rho) ⊆ disc(c, rho). The
recursion run with P_N in place of the discs gives polygons I_k with

    S_k(eps cos(pi/N), v cos(pi/N)) ⊆ I_k ⊆ S_k(eps, v)

(both by induction: Minkowski sum and intersection keep inclusions). Hence I_k non-empty
proves the assumption holds, and I_k empty proves it is broken already for both bounds
shrunk by the factor cos(pi/N). Every step runs with N = :data:`COARSE_SIDES` (cheap); only
when that polygon becomes empty is the pedestrian's walk followed with
N = :data:`FINE_SIDES` (from where it was last followed, so each step is computed at most
once), and a break is reported only if that one is empty too. The fine polygons' vertices
include the coarse ones', so the fine recursion holds the coarse one and is empty no earlier;
where the fine one is not empty, the coarse recursion goes on from it (a subset of S_k). So
the check never misses a break, and reports one only when the walk breaks the model with both
bounds shrunk by the relative :data:`RELATIVE_TOLERANCE` = 1 - cos(pi/4096) = 2.9e-7: at
v dt + eps = 0.55 m, 0.16 µm. Rounding (libm's sin and cos for the vertices, GEOS's
intersections, sums of a few thousand edges) is far below that in the local frame used here
(positions relative to the pedestrian's first one); we state the tolerance as 1e-6 m
(:data:`TOLERANCE_M`) for bounds up to a few metres. A pedestrian whose set is the whole
jitter disc of its latest position (it walks well within the bounds: the usual case) costs
one containment test of two homothetic polygons a step, no polygon operation. After a
reported break the walk's set starts afresh at the break's position.

Compiled. :func:`admits` (and with it :func:`least_jitter`, which the jitter measurement of
:mod:`sse_cosim.world.walker_jitter` bisects with it) runs the recursion in a numba kernel,
:func:`~sse_cosim.world.assumption_kernels.admits_walk`; :func:`admits_reference` is its
NumPy/shapely reference (:func:`advance`: :func:`minkowski_sum` and GEOS's :func:`intersect`).
The kernel's own rounding moves its answer no more than moving both bounds by about 1e-11 m
would, for walks within 1 km of their first position (the kernel module's docstring proves
the bound): five orders of magnitude below :data:`TOLERANCE_M`, and least_jitter rounds up to
1 mm. :class:`PedestrianMotionCheck` keeps the reference's operations (its polygons pass from
the fine recursion to the coarse one, which the kernel's sector form would not hold exactly).

Discs against the estimator's boxes: the estimator's process noise is the box |dx|, |dy| <=
v dt and its jitter the box |e_x|, |e_y| <= eps; each holds the disc of the same radius, so
a walk that keeps the disc model keeps the box model too (this test is the stricter one).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np
import shapely

from sse_cosim.sets import portable
from sse_cosim.world.assumption_kernels import admits_walk

COARSE_SIDES = 64
FINE_SIDES = 4096
RELATIVE_TOLERANCE = 1.0 - portable.cos(math.pi / FINE_SIDES)
TOLERANCE_M = 1e-6
_BISECTION_STEPS = 30
_JITTER_SIDES = 64  # polygons of least_jitter's bisection
_INSIDE_TEST_SIZE = 40_000  # vertex pairs up to which intersect tries B ⊆ A first


@dataclass(frozen=True)
class MotionBounds:
    """The estimator's pedestrian model: speed bound (m/s), jitter (m), step length (s)."""

    speed_mps: float
    jitter_m: float
    step_s: float

    @property
    def step_m(self) -> float:
        """The longest path step, v dt (m)."""
        return self.speed_mps * self.step_s


@dataclass(frozen=True)
class MotionBreak:
    """A pedestrian whose position at ``time`` no admissible path reaches.

    ``distance_m``: how far the position was from the nearest path point the model admits
    after the previous step (the jitter allows ``jitter_m``); ``step_m``: how far it moved in
    that one step; ``needed_jitter_m``: the least jitter (rounded up to 1 mm) that admits
    its walk up to now (None when not computed). A model that bounds the acceleration
    (:mod:`sse_cosim.world.acceleration_assumption`) also gives ``velocity_change_mps``, how
    much the walk's mean velocity changed in that step (m/s), and ``broke``, which bound the
    walk breaks within the jitter, as words ('the acceleration bound', ...; None when not
    computed).
    """

    person: str
    time: float
    distance_m: float
    jitter_m: float
    step_m: float
    needed_jitter_m: float | None = None
    velocity_change_mps: float | None = None
    broke: str | None = None

    @property
    def beyond_m(self) -> float:
        """How far beyond the jitter the position was (m)."""
        return self.distance_m - self.jitter_m


@lru_cache(maxsize=4)
def unit_polygon(sides: int) -> np.ndarray:
    """The regular ``sides``-gon inscribed in the unit circle, counter-clockwise, (sides, 2).

    Its vertices are at the angles pi / COARSE_SIDES + 2 pi j / sides: every vertex of the
    coarse polygon is one of the fine one's, so the fine polygon holds the coarse one."""
    angles = [math.pi / COARSE_SIDES + 2.0 * math.pi * i / sides for i in range(sides)]
    out = np.array([[portable.cos(a), portable.sin(a)] for a in angles])
    out.setflags(write=False)
    return out


def pseudo_angle(vectors: np.ndarray) -> np.ndarray:
    """A key in [0, 4) increasing with the angle of each nonzero vector of ``vectors``
    (m, 2) counter-clockwise from east (the "diamond angle": divisions only, no arctan)."""
    x, y = vectors[:, 0], vectors[:, 1]
    s = np.abs(x) + np.abs(y)
    return np.where(y >= 0, np.where(x >= 0, y / s, 1.0 + np.abs(x) / s),
                    np.where(x < 0, 2.0 + np.abs(y) / s, 3.0 + x / s))


def minkowski_sum(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """A (+) B of convex polygons given by their counter-clockwise vertices (n, 2) and (m, 2)
    (a point or a segment allowed): the vertices of the sum, counter-clockwise, (<= n + m, 2).

    Edges of both merged in order of angle, each polygon entered at the vertex whose
    outgoing edge points the most nearly east (counter-clockwise from east)."""
    ea, ka, sa = _sorted_edges(a)
    eb, kb, sb = _sorted_edges(b)
    start = sa + sb
    edges = np.concatenate([ea, eb])
    if len(edges) == 0:
        return start[np.newaxis, :]
    edges = edges[np.argsort(np.concatenate([ka, kb]), kind="stable")]
    out = np.empty((len(edges), 2))
    out[0] = start
    np.cumsum(edges[:-1], axis=0, out=out[1:])
    out[1:] += start
    return out


def intersect(a: np.ndarray, b: np.ndarray) -> np.ndarray | None:
    """A ∩ B of convex sets given by vertices (n, 2), (m, 2) (polygons counter-clockwise,
    or a point or segment): its vertices (k, 2), counter-clockwise, or None if empty.

    B is returned as it is when every vertex of it lies in the polygon A (the usual case)."""
    if len(a) >= 3 and len(a) * len(b) <= _INSIDE_TEST_SIZE and _inside(a, b):
        return b
    try:
        result = shapely.intersection(_geometry(a), _geometry(b))
    except shapely.errors.GEOSException:  # a sliver GEOS finds invalid: take its hull
        result = shapely.intersection(_hull(a), _hull(b))
    if result.is_empty:
        return None
    if result.geom_type not in ("Polygon", "LineString", "Point"):
        result = result.convex_hull
    if result.geom_type == "Polygon":
        ring = shapely.get_coordinates(result.exterior)
        return ring[:-1] if shapely.is_ccw(result.exterior) else ring[-2::-1].copy()
    return shapely.get_coordinates(result)


def distance(point: np.ndarray, polygon: np.ndarray) -> float:
    """Distance (m) from ``point`` (2,) to the convex set with vertices ``polygon`` (k, 2)."""
    return float(shapely.distance(shapely.Point(point), _geometry(polygon)))


def disc(center: np.ndarray, radius: float, sides: int) -> np.ndarray:
    """P_N(center, radius): the inscribed ``sides``-gon (sides, 2); the point (1, 2) if the
    radius is 0."""
    if radius == 0.0:
        return np.asarray(center, dtype=float).reshape(1, 2)
    return center + radius * unit_polygon(sides)


def advance(previous: np.ndarray, position: np.ndarray, bounds: MotionBounds,
            sides: int) -> np.ndarray | None:
    """One step of the polygon recursion: (I (+) P_N(v dt)) ∩ P_N(p, eps), vertices (k, 2), or
    None if empty; ``previous`` (n, 2) and ``position`` (2,) in the same frame."""
    grown = minkowski_sum(previous, disc(np.zeros(2), bounds.step_m, sides))
    return intersect(grown, disc(position, bounds.jitter_m, sides))


def admits(positions: np.ndarray, bounds: MotionBounds, sides: int = COARSE_SIDES) -> bool:
    """Whether the polygon recursion with ``sides``-gons stays non-empty along ``positions``
    (k, 2): True proves a path exists for ``bounds`` (an inner approximation). While the set
    is the whole polygon P_N(c, eps) of the latest position, a step p - c within P_N(v dt)
    keeps it whole (homothetic polygons: P_N(c, eps) (+) P_N(v dt) holds P_N(p, eps)), with
    no polygon operation. The walk is followed up to its last step longer than v dt only: from
    a path point s_k within eps of p_k, s_k + (p_(k+1) - p_k) is one for p_(k+1) whenever that
    step is at most v dt, so a walk admitted up to there is admitted whole.

    Compiled (:func:`~sse_cosim.world.assumption_kernels.admits_walk`, whose docstring bounds
    its rounding); :func:`admits_reference` is the NumPy/shapely reference."""
    return admits_walk(_to_follow(positions, bounds), unit_polygon(sides),
                       _edge_midpoints(sides), bounds.step_m, bounds.jitter_m)


def admits_reference(positions: np.ndarray, bounds: MotionBounds,
                     sides: int = COARSE_SIDES) -> bool:
    """:func:`admits` by :func:`advance` (``minkowski_sum`` and GEOS's ``intersect``) step by
    step: the reference of the compiled kernel."""
    positions = _to_follow(positions, bounds)
    center: np.ndarray | None = positions[0]
    current: np.ndarray | None = None
    for position in positions[1:]:
        if center is not None:
            if _in_polygon(position - center, bounds.step_m, sides):
                center = position
                continue
            current, center = disc(center, bounds.jitter_m, sides), None
        assert current is not None
        current = advance(current, position, bounds, sides)
        if current is None:
            return False
    return True


def _to_follow(positions: np.ndarray, bounds: MotionBounds) -> np.ndarray:
    """The part of the walk ``positions`` (k, 2) :func:`admits` follows, up to its last step
    longer than v dt (the first position alone without one), relative to its first position:
    (j, 2), contiguous float64."""
    positions = np.asarray(positions, dtype=float)
    steps = np.diff(positions, axis=0)
    longer = np.flatnonzero((steps * steps).sum(axis=1) > bounds.step_m * bounds.step_m)
    positions = positions[:longer[-1] + 2] if len(longer) else positions[:1]
    return np.ascontiguousarray(positions - positions[0])


def least_jitter(positions: np.ndarray, bounds: MotionBounds) -> float:
    """A jitter (m, rounded up to 1 mm) that admits the walk ``positions`` (k, 2) with the speed
    bound of ``bounds``: proven by inner :data:`_JITTER_SIDES`-gons, and at most 0.13 % + 2 mm
    above the least one that does (bisection to 0.5 mm; the polygons' relative 1.2e-3). The
    bisection runs between half the largest step beyond v dt (a step of p is at most v dt +
    2 eps) and the jitter of a path built from the walk (:func:`path_jitter`, which admits
    it)."""
    high = path_jitter(positions, bounds.step_m) / portable.cos(math.pi / _JITTER_SIDES) + 1e-3
    steps = np.diff(positions, axis=0)
    longest = float(np.sqrt((steps * steps).sum(axis=1)).max()) if len(steps) else 0.0
    low = max(bounds.jitter_m, 0.5 * (longest - bounds.step_m))
    for _ in range(_BISECTION_STEPS):
        if high - low <= 5e-4:
            break
        middle = 0.5 * (low + high)
        if admits(positions, MotionBounds(bounds.speed_mps, middle, bounds.step_s),
                  _JITTER_SIDES):
            high = middle
        else:
            low = middle
    return math.ceil(high * 1000.0 - 1e-9) / 1000.0


def path_jitter(positions: np.ndarray, step_m: float) -> float:
    """max_k |p_k - s_k| (m) for a path s with steps of at most ``step_m`` built from the walk
    ``positions`` (k, 2): the mean of the path that pursues the walk forwards at that speed
    (q_0 = p_0, each step toward p_k cut to ``step_m``) and the one that pursues it backwards
    from its end. Both have steps of at most ``step_m``, so their mean does too: this jitter
    admits the walk (an upper bound of the least; about the least for a walk with one jump)."""
    forward = _pursuit(positions, step_m)
    backward = _pursuit(positions[::-1], step_m)[::-1]
    gaps = positions - 0.5 * (forward + backward)
    return float(np.sqrt((gaps * gaps).sum(axis=1)).max()) if len(gaps) else 0.0


def _pursuit(positions: np.ndarray, step_m: float) -> np.ndarray:
    """The path (k, 2) that pursues ``positions`` (k, 2) with steps of at most ``step_m``."""
    out = np.array(positions, dtype=float)
    for k in range(1, len(out)):
        gap = out[k] - out[k - 1]
        length = math.sqrt(float(gap[0] * gap[0] + gap[1] * gap[1]))
        if length > step_m:
            out[k] = out[k - 1] + gap * (step_m / length)
    return out


@dataclass
class _Walk:
    """One pedestrian's walk since its set last started: positions relative to the first
    (k, 2), the coarse polygon (now) and the fine one (at step ``fine_at``)."""

    origin: np.ndarray
    positions: list[np.ndarray] = field(default_factory=list)
    coarse: np.ndarray | None = None
    center: np.ndarray | None = None  # the coarse polygon is P_N(center, eps) (then coarse unset)
    fine: np.ndarray | None = None
    fine_at: int = 0


class WalkCheck(ABC):
    """What the pedestrian checks share: each present pedestrian's walk, followed step by step.

    ``step(time, positions)`` takes each present pedestrian's position (x, y) and returns the
    breaks of this step; a pedestrian absent from a step is forgotten (one that comes back
    starts afresh). A subclass starts a walk (:meth:`_start`) and advances it by one position,
    returning a break if there is one (:meth:`_advance`).
    """

    def __init__(self) -> None:
        self._walks: dict[str, Any] = {}
        self._full: dict[str, list[np.ndarray]] = {}

    def step(self, time: float, positions: Mapping[str, tuple[float, float]]) -> list[MotionBreak]:
        """Check this step's ``positions`` by pedestrian id; the breaks found (usually none)."""
        for gone in [pid for pid in self._walks if pid not in positions]:
            del self._walks[gone]
            del self._full[gone]
        breaks = []
        for pid, xy in positions.items():
            point = np.array([float(xy[0]), float(xy[1])])
            walk = self._walks.get(pid)
            if walk is None:
                self._start(pid, point, [])
                continue
            found = self._advance(pid, walk, time, point)
            if found is not None:
                breaks.append(found)
        return breaks

    @abstractmethod
    def _start(self, pid: str, point: np.ndarray, full: list[np.ndarray]) -> None:
        """Start ``pid``'s walk at ``point`` after the positions ``full`` (kept for a needed
        jitter)."""

    @abstractmethod
    def _advance(self, pid: str, walk: Any, time: float, point: np.ndarray) -> MotionBreak | None:
        """Advance ``walk`` by ``point``; the break at it, if any."""


class PedestrianMotionCheck(WalkCheck):
    """Follows every pedestrian's admissible path points S_k (see the module docstring); one
    that broke starts afresh at its position (:class:`WalkCheck`)."""

    def __init__(self, bounds: MotionBounds, needed_jitter: bool = True) -> None:
        super().__init__()
        self.bounds = bounds
        self.needed_jitter = needed_jitter

    def _start(self, pid: str, point: np.ndarray, full: list[np.ndarray]) -> None:
        walk = _Walk(origin=point, positions=[np.zeros(2)], center=np.zeros(2))
        walk.fine = disc(np.zeros(2), self.bounds.jitter_m, FINE_SIDES)
        self._walks[pid] = walk
        self._full[pid] = [*full, point]

    def _advance(self, pid: str, walk: _Walk, time: float, point: np.ndarray) -> MotionBreak | None:
        local = point - walk.origin
        walk.positions.append(local)
        self._full[pid].append(point)
        if walk.center is not None:
            # (P_N(c, eps) (+) P_N(v dt)) = P_N(c, eps + v dt) holds P_N(p, eps) when p - c lies
            # in P_N(v dt) (homothetic polygons): the set is P_N(p, eps) again
            if _in_polygon(local - walk.center, self.bounds.step_m, COARSE_SIDES):
                walk.center = local
                return None
            walk.coarse = disc(walk.center, self.bounds.jitter_m, COARSE_SIDES)
            walk.center = None
        assert walk.coarse is not None
        here = disc(local, self.bounds.jitter_m, COARSE_SIDES)
        grown = minkowski_sum(walk.coarse, disc(np.zeros(2), self.bounds.step_m, COARSE_SIDES))
        walk.coarse = intersect(grown, here)
        if walk.coarse is here:  # the whole disc again: back to the cheap form
            walk.coarse, walk.center = None, local
            return None
        if walk.coarse is not None:
            return None
        # the coarse polygon is empty: follow the walk with the fine one up to now
        previous = walk.fine
        for k in range(walk.fine_at + 1, len(walk.positions)):
            assert walk.fine is not None
            previous = walk.fine
            walk.fine = advance(walk.fine, walk.positions[k], self.bounds, FINE_SIDES)
            walk.fine_at = k
            if walk.fine is None:
                break
        if walk.fine is not None:
            walk.coarse = walk.fine  # a subset of S_k: the coarse recursion goes on from it
            return None
        assert previous is not None
        found = self._break(pid, walk, time, previous)
        self._start(pid, point, self._full[pid][:-1])
        return found

    def _break(self, pid: str, walk: _Walk, time: float, previous: np.ndarray) -> MotionBreak:
        """The break at the walk's last position; ``previous`` is the fine polygon before it."""
        here, before = walk.positions[-1], walk.positions[-2]
        grown = minkowski_sum(previous, disc(np.zeros(2), self.bounds.step_m, FINE_SIDES))
        moved = here - before
        needed = None
        if self.needed_jitter:
            needed = least_jitter(np.array(self._full[pid]), self.bounds)
        return MotionBreak(person=pid, time=time, distance_m=distance(here, grown),
                           jitter_m=self.bounds.jitter_m,
                           step_m=float(np.sqrt((moved * moved).sum())),
                           needed_jitter_m=needed)


def _sorted_edges(vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The nonzero edges (e, 2) of the closed convex polygon ``vertices`` (n, 2, counter-
    clockwise), their pseudo-angles (e,), and the vertex (2,) the first of them leaves, the
    edges in counter-clockwise order from the first at or after east."""
    if len(vertices) == 1:
        return np.empty((0, 2)), np.empty(0), vertices[0]
    edges = np.empty_like(vertices)
    edges[:-1] = vertices[1:] - vertices[:-1]
    edges[-1] = vertices[0] - vertices[-1]
    keep = (edges[:, 0] != 0.0) | (edges[:, 1] != 0.0)
    starts = vertices[keep]
    edges = edges[keep]
    if len(edges) == 0:
        return edges, np.empty(0), vertices[0]
    keys = pseudo_angle(edges)
    # the wrap of the angles: the edge after the largest drop (not argmin, which may pick the
    # second of two collinear edges and shift the sum by the first)
    first = int(np.argmax(np.roll(keys, 1) - keys))
    order = np.r_[first:len(edges), 0:first]
    return edges[order], keys[order], starts[first]


@lru_cache(maxsize=4)
def _edge_midpoints(sides: int) -> np.ndarray:
    """The midpoints (sides, 2) of the unit polygon's edges (norm cos(pi/sides))."""
    unit = unit_polygon(sides)
    out = 0.5 * (unit + np.roll(unit, -1, axis=0))
    out.setflags(write=False)
    return out


def _in_polygon(point: np.ndarray, radius: float, sides: int) -> bool:
    """Whether ``point`` (2,) lies in P_N(0, ``radius``): on the inner side of every edge,
    m_j . x <= radius |m_j|^2 for each edge midpoint m_j of the unit polygon."""
    mids = _edge_midpoints(sides)
    return bool((mids[:, 0] * point[0] + mids[:, 1] * point[1]
                 <= radius * (mids[:, 0] * mids[:, 0] + mids[:, 1] * mids[:, 1])).all())


def _inside(polygon: np.ndarray, points: np.ndarray) -> bool:
    """Whether every point of ``points`` (m, 2) lies in the convex counter-clockwise
    ``polygon`` (n, 2) (on no edge's outer side)."""
    edges = np.roll(polygon, -1, axis=0) - polygon
    rel_x = points[np.newaxis, :, 0] - polygon[:, np.newaxis, 0]
    rel_y = points[np.newaxis, :, 1] - polygon[:, np.newaxis, 1]
    cross = edges[:, np.newaxis, 0] * rel_y - edges[:, np.newaxis, 1] * rel_x
    return bool((cross >= 0.0).all())


def _hull(vertices: np.ndarray) -> shapely.Geometry:
    """The convex hull of ``vertices`` (n, 2), valid whatever rounding did to them."""
    return shapely.MultiPoint(vertices).convex_hull


def _geometry(vertices: np.ndarray) -> shapely.Geometry:
    """A polygon (>= 3 vertices), segment or point as a shapely geometry."""
    if len(vertices) >= 3:
        return shapely.Polygon(vertices)
    if len(vertices) == 2:
        return shapely.LineString(vertices)
    return shapely.Point(vertices[0])

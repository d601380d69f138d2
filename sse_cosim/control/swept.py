"""The ground a vehicle's body sweeps along its route, as SUMO places the body: pure geometry.

**The model (SUMO's own placement).** SUMO keeps a vehicle's front bumper on its lane's
centre line, at lane position ``sigma`` counted along the route's lanes (each lane's ``length``
attribute; a lane's shape is stretched to it, as ``MSLane::interpolateLanePosToGeometryPos``
does). Its back is the point of the route ``length`` lane metres behind the front (the start
of the first lane while the back is not yet on the network), and the body is the rectangle of
the vehicle's length and width whose front edge is centred on the front point and whose axis
runs along the chord from the back point to the front point (``MSVehicle::computeAngle``;
``sse_cosim.world.sumo`` reports that rectangle as each vehicle's footprint). On a straight
road the chord is the lane and the body is the centre line widened by half the width; on a
corner the chord is shorter than the body, so the body's middle cuts the corner's inside and
its rear end swings out beyond the centre line's half-width band.

**The cover.** Between consecutive *breakpoints* (the lane positions of the route's vertices,
of the vertices plus the length, and extra cuts that keep each piece short and its turn small)
both the front point ``F`` and the back point move linearly, so the chord ``c = F - B`` moves
linearly too and its direction turns monotonically, by some ``dpsi``. Every footprint with its
front in such a piece ``[a, b]`` then lies in

    hull{F_i + R(psi_j) corner_k : i, j in {a, b}, k = 1..4}  (+)  disc(r_max (1 - cos(dpsi/2))),

with ``r_max`` the distance from the front point to a rear corner: a footprint point is
``F + R(psi) q`` with ``F`` on the segment ``[F_a, F_b]`` and ``R(psi) q`` on the arc from
``R(psi_a) q`` to ``R(psi_b) q``, which lies within its sagitta ``|q| (1 - cos(dpsi/2))`` of the
chord between them; the segment plus that chord lie in the hull. A straight piece (no turn) is
covered exactly. The disc is enclosed in an octagon around each hull point, so the cover is a
convex polygon containing every footprint of the piece. Where the front jumps between two lanes
whose ends do not meet, the hull of the footprints before and after the jump covers both.

The union of the covers is therefore a sound over-approximation of every footprint the vehicle
takes along the route (:func:`body_sweep`), and a piece of ground is touched only while the
front is within the pieces whose cover meets it (:func:`touch_intervals`).

Shapes: points are (2,) arrays, polygons shapely geometries; no SUMO here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from itertools import pairwise
from typing import TYPE_CHECKING

import numpy as np
import shapely

if TYPE_CHECKING:
    from sse_cosim.world.roadmap import LaneChange, LaneGeometry

MAX_TURN_RAD = 0.01
"""Largest turn of the body within one piece of the sweep (the cover's rounding: a 12 m bus's
rear corner strays at most 0.15 mm from the hull)."""
MAX_PIECE_M = 0.5
"""Longest turning piece of the sweep along the route (m): how finely the front stations at
which a piece of ground is touched are known on a corner (a straight piece knows them exactly,
whatever its length)."""
POSITION_EPS_M = 0.1
"""SUMO's ``POSITION_EPS``: a lane's shape counts as at least this long when SUMO maps lane
positions onto it (``MSLane``'s length-geometry factor, max(POSITION_EPS, shape length) /
length); along a shorter shape the front reaches the shape's end before the lane's end and
stands there (``PositionVector::positionAtOffset`` stops at its last point). Line 300 of Bad
Hersfeld crosses a junction lane of 0.10 m drawn 0.089 m long: the front stood 6 mm from a
plain stretch's point, and the world's odometer check stopped the run."""
TOUCH_GAP_M = 1e-6
"""Two stretches along which the body touches an area are one unless this far apart (m): the
ends of consecutive pieces of the sweep, worked out on each, differ by a rounding."""
STRAIGHT_RAD = 1e-12
"""A piece whose body turns by no more is straight (its footprints stray at most 1e-11 m from
the rectangles of a body that does not turn)."""
_OCTAGON_ANGLES = np.array([(k + 0.5) * math.pi / 4.0 for k in range(8)])
"""Angles (rad) of the vertices of an octagon around the unit disc whose edges face the axes."""


@dataclass(frozen=True)
class RoutePath:
    """A route's centre line as SUMO drives it: ``points`` (n, 2), their lane positions
    ``sigma`` (n,) (m, each lane's ``length`` attribute) and their stations ``station`` (n,)
    (m, geometric distance along the line, as ``shapely``'s ``project`` measures it).
    ``detours``: where a lane change makes the vehicle's lane uncertain, the other paths its
    body may take meanwhile (:class:`Detour`; the sweep covers them too)."""

    points: np.ndarray
    sigma: np.ndarray
    station: np.ndarray
    detours: tuple[Detour, ...] = ()

    @classmethod
    def of_route(cls, lanes: Sequence[LaneGeometry],
                 changes: Sequence[LaneChange] = ()) -> RoutePath:
        """The path along a route's lanes in order, with its lane changes
        (``RoadMap.route_plan``): for each lane the vehicle may drive on while it changes, a
        detour over the whole edge of the change (SUMO moves a vehicle to the next lane within
        a step, at the lane position it had: lanes of an edge are equally long)."""
        main = cls.of_lanes([(lane.shape, lane.length) for lane in lanes])
        detours = []
        for change in changes:
            for route in change.detours:
                start = float(sum(lane.length for lane in route[:-1]))
                detours.append(Detour(cls.of_lanes([(lane.shape, lane.length)
                                                    for lane in route]),
                                      start, start + route[-1].length))
        return replace(main, detours=tuple(detours))

    def points_at(self, sigma: float) -> list[np.ndarray]:
        """Every point (2,) where SUMO may put a front at lane position ``sigma``: the path's
        (:meth:`point_at`) and each detour's whose stretch holds it."""
        return [self.point_at(sigma)[0], *(d.path.point_at(sigma)[0] for d in self.detours
                                           if d.start_m <= sigma <= d.end_m)]

    @classmethod
    def of_lanes(cls, lanes: Sequence[tuple[np.ndarray, float]]) -> RoutePath:
        """The path along ``lanes``, each a centre line (k, 2) and its length (m), in order;
        a point that repeats the previous one at the same lane position is dropped (a lane's
        start at the previous lane's end), one that SUMO reaches further on is kept (after a
        lane drawn without length, such as a junction passage of a point: SUMO's front stands
        there while its lane position runs over the passage's ``length``; along a lane drawn
        shorter than :data:`POSITION_EPS_M`, it reaches the shape's end early and stands)."""
        points: list[np.ndarray] = []
        sigma: list[float] = []
        offset = 0.0
        for shape, length in lanes:
            shape = np.asarray(shape, dtype=np.float64)
            steps = np.sqrt(((shape[1:] - shape[:-1]) ** 2).sum(axis=1))  # (k - 1,)
            along = np.concatenate([[0.0], np.cumsum(steps)])  # (k,)
            geometric = float(along[-1])
            scale = length / max(geometric, POSITION_EPS_M) if geometric > 0.0 else 0.0
            for point, at in zip(shape, along, strict=True):
                lane_position = offset + float(at) * scale
                if points and float(np.max(np.abs(point - points[-1]))) <= 1e-9 \
                        and lane_position - sigma[-1] <= 1e-9:
                    continue
                points.append(point)
                sigma.append(lane_position)
            if 0.0 < geometric < POSITION_EPS_M:  # the front stands at its end (POSITION_EPS_M)
                points.append(shape[-1])
                sigma.append(offset + length)
            offset += length
        pts = np.array(points)  # (n, 2)
        station = [0.0]
        for p1, p2 in pairwise(pts):
            station.append(station[-1] + ((p2[0] - p1[0]) ** 2 + (p2[1] - p1[1]) ** 2) ** 0.5)
        return cls(pts, np.array(sigma), np.array(station))

    def drive(self, station: float) -> float:
        """The lane position (m, SUMO's distance along the route: its departure position
        plus its odometer) at ``station`` m along the drawn line: each lane's stations map
        linearly onto its length, a gap between two lanes' shapes onto none; before the
        route and beyond it both advance alike (docs/controller.md, "SUMO's distance"). At a
        passage drawn without length, SUMO's front stands at one station over the passage's
        whole length: this gives its far end (where a body must be to have cleared a place
        there), :meth:`drive_before` its near end (where it must stop to stay before it)."""
        if station <= self.station[0]:
            return float(self.sigma[0] + station - self.station[0])
        if station >= self.station[-1]:
            return float(self.sigma[-1] + station - self.station[-1])
        return float(np.interp(station, self.station, self.sigma))

    def drive_before(self, station: float) -> float:
        """:meth:`drive`, but at a passage drawn without length its near end: the least lane
        position with the front at ``station``."""
        k = int(np.searchsorted(self.station, station, side="left"))
        if 0 < k < len(self.station) and self.station[k] == station:
            return float(self.sigma[k])
        return self.drive(station)

    def point_at(self, sigma: float) -> tuple[np.ndarray, float]:
        """The point (2,) at lane position ``sigma`` and its station (m): where SUMO puts a
        front there (:meth:`at`; at a gap between lanes, its far end; beyond the route's
        ends, the end segment extended)."""
        return self.at(sigma, self.segment(sigma))

    def segment(self, sigma: float) -> int:
        """The segment ``i`` (from point i to i + 1) holding lane position ``sigma``: the
        first one whose end lies beyond it (the last one at the route's end)."""
        index = int(np.searchsorted(self.sigma, sigma, side="right")) - 1
        return min(max(index, 0), len(self.points) - 2)

    def at(self, sigma: float, segment: int) -> tuple[np.ndarray, float]:
        """The point (2,) at lane position ``sigma`` on ``segment``, and its station (m)."""
        p1, p2 = self.points[segment], self.points[segment + 1]
        s1, s2 = self.sigma[segment], self.sigma[segment + 1]
        t = 0.0 if s2 <= s1 else (sigma - s1) / (s2 - s1)
        point = p1 + t * (p2 - p1)
        return point, float(self.station[segment] + t * (self.station[segment + 1]
                                                         - self.station[segment]))


@dataclass(frozen=True)
class Detour:
    """While its front is between lane positions ``start_m`` and ``end_m`` (m, SUMO's distance
    along the route), a vehicle's body may lie as along ``path`` instead of its route's path:
    before a lane change, on the lane it entered the edge on, or on a lane it crosses."""

    path: RoutePath
    start_m: float
    end_m: float


@dataclass(frozen=True)
class SweepPiece:
    """The body's cover while its front is between stations ``start_m`` and ``end_m`` (m):
    ``cover`` holds every footprint with its front there; ``straight``: the body does not turn
    and its front moves along its axis ``axis`` (2,) from ``front`` (2,), so each footprint is
    the rectangle behind the front and the stations at which it touches a point are exact;
    ``scale``: stations per metre the front moves (1, but on a detour: its lane's drawn length
    against the route's, :class:`Detour`)."""

    cover: shapely.Polygon
    start_m: float
    end_m: float
    straight: bool
    front: np.ndarray
    axis: np.ndarray
    scale: float = 1.0


def footprint(front: np.ndarray, heading: np.ndarray, length: float,
              width: float) -> np.ndarray:
    """The rectangle behind ``front`` (2,) along the unit ``heading`` (2,): corners (4, 2)
    counter-clockwise from the rear right (as ``Footprint.corners``)."""
    left = np.array([-heading[1], heading[0]])
    rear = front - length * heading
    half = 0.5 * width * left
    return np.array([rear - half, front - half, front + half, rear + half])


def chord_footprint(path: RoutePath, sigma: float, length: float,
                    width: float) -> np.ndarray:
    """SUMO's footprint with the front at lane position ``sigma``: corners (4, 2) (module
    docstring; a test compares it with SUMO's own)."""
    front, _ = path.at(sigma, path.segment(sigma))
    back = _back(path, sigma - length, path.segment(max(sigma - length, 0.0)))
    return footprint(front, _direction(path, front - back), length, width)


def body_sweep(path: RoutePath, length: float, width: float) -> list[SweepPiece]:
    """The covers of every footprint of a body ``length`` x ``width`` (m) whose front runs the
    whole ``path``, and along each of its detours while the front is on the detour's stretch,
    in route order (module docstring); stations are the path's."""
    pieces = _sweep(path, length, width, path, -math.inf, math.inf)
    for detour in path.detours:
        pieces.extend(_sweep(detour.path, length, width, path, detour.start_m, detour.end_m))
    return sorted(pieces, key=lambda p: p.start_m)


def _sweep(path: RoutePath, length: float, width: float, frame: RoutePath, start: float,
           end: float) -> list[SweepPiece]:
    """:func:`body_sweep`'s covers along ``path`` with the front between lane positions
    ``start`` and ``end``, at ``frame``'s stations."""
    cuts = np.unique(np.concatenate([path.sigma, path.sigma + length]))
    cuts = cuts[cuts <= path.sigma[-1]]
    if math.isfinite(start):
        cuts = np.unique(np.r_[start, cuts[(cuts > start) & (cuts < end)], end])
    pieces = []
    for a, b in pairwise(cuts):
        middle = 0.5 * (a + b)
        front_segment = path.segment(middle)
        back_segment = path.segment(max(middle - length, 0.0))
        chords = _chords(path, a, b, front_segment, back_segment, length)
        parts = 1 if chords.straight else max(math.ceil(chords.turn / MAX_TURN_RAD),
                                              math.ceil((b - a) / MAX_PIECE_M))
        edges = [a + (b - a) * k / parts for k in range(parts)] + [b]
        for lo, hi in pairwise(edges):
            pieces.append(_piece(path, lo, hi, front_segment, back_segment, length, width,
                                 frame))
    for i in np.flatnonzero(np.diff(path.sigma) <= 0.0):  # the front jumps a gap
        if not start < path.sigma[i] <= end:
            continue
        before = chord_footprint(path, float(path.sigma[i]) - 1e-12, length, width)
        after = chord_footprint(path, float(path.sigma[i]), length, width)
        cover = shapely.convex_hull(shapely.multipoints(np.vstack([before, after])))
        pieces.append(SweepPiece(cover, _station(frame, path, i), _station(frame, path, i + 1),
                                 False, path.points[i], np.zeros(2)))
    return pieces


def _station(frame: RoutePath, path: RoutePath, i: int) -> float:
    """Point ``i`` of ``path``'s station on ``frame`` (the same path: its own)."""
    if frame is path:
        return float(path.station[i])
    return frame.point_at(float(path.sigma[i]))[1]


def swept_region(pieces: Sequence[SweepPiece]) -> shapely.Geometry:
    """The union of the pieces' covers: every footprint of the sweep lies in it."""
    return shapely.union_all([p.cover for p in pieces])


def ahead_cover(pieces: Sequence[SweepPiece], front_m: float, length: float,
                width: float) -> shapely.Geometry:
    """Every footprint of a body ``length`` x ``width`` (m) whose front is at station
    ``front_m`` or beyond lies in it: the covers of the pieces not yet left behind, the one the
    front is in cut at the front if it is straight (its footprints with the front behind it
    are left out; a turning piece, at most :data:`MAX_PIECE_M` long, is kept whole). The
    ground only the footprints behind ``front_m`` covered is out of the body's way from then
    on, since a vehicle moves forward along its route."""
    covers = []
    for piece in pieces:
        if piece.end_m < front_m:
            continue
        if piece.straight and piece.start_m < front_m:
            ends = [piece.front + (at - piece.start_m) / piece.scale * piece.axis
                    for at in (front_m, piece.end_m)]
            covers.append(shapely.convex_hull(shapely.multipoints(np.vstack(
                [footprint(end, piece.axis, length, width) for end in ends]))))
        else:
            covers.append(piece.cover)
    return shapely.union_all(covers)


def touch_intervals(pieces: Sequence[SweepPiece], area: shapely.Geometry,
                    length: float) -> list[tuple[float, float]]:
    """Each stretch of the route along which the body touches ``area``, in route order:
    ``(start, end)`` (m), the body touching it while its front is between stations ``start``
    and ``end + length``, and not between two stretches (a route that passes the same ground
    twice, out along a street and back along its other side, touches it twice). A straight
    piece gives the exact first and last station (the area's extent along the body's axis), a
    turning one its own ends; stretches that meet or overlap are one."""
    touching = shapely.intersects(np.array([p.cover for p in pieces], dtype=object), area)
    spans: list[tuple[float, float]] = []
    for piece in (p for p, touches in zip(pieces, touching, strict=True) if touches):
        if piece.straight:
            inside = shapely.intersection(piece.cover, area)
            if inside.is_empty:
                continue
            along = _along(shapely.get_coordinates(inside), piece.front, piece.axis)
            spans.append((piece.start_m + piece.scale * max(0.0, float(along.min())),
                          min(piece.end_m,
                              piece.start_m + piece.scale * (float(along.max()) + length))))
        else:
            spans.append((piece.start_m, piece.end_m))
    merged: list[list[float]] = []
    for first, last in sorted(spans):
        if merged and first <= merged[-1][1] + TOUCH_GAP_M:
            merged[-1][1] = max(merged[-1][1], last)
        else:
            merged.append([first, last])
    return [(first, last - length) for first, last in merged]


def _along(points: np.ndarray, origin: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """How far each of ``points`` (k, 2) lies along the unit ``axis`` (2,) from ``origin``
    (2,), shape (k,)."""
    return (points[:, 0] - origin[0]) * axis[0] + (points[:, 1] - origin[1]) * axis[1]


def _back(path: RoutePath, sigma: float, segment: int) -> np.ndarray:
    """The back point (2,) at lane position ``sigma``: the route's start while it is behind it."""
    return path.points[0] if sigma <= 0.0 else path.at(sigma, segment)[0]


def _direction(path: RoutePath, chord: np.ndarray) -> np.ndarray:
    """The unit direction (2,) of ``chord`` (2,); the first segment's while it is zero (the
    body at the route's start, as SUMO turns it along the lane there)."""
    norm = math.hypot(float(chord[0]), float(chord[1]))
    if norm == 0.0:
        chord = path.points[1] - path.points[0]
        norm = math.hypot(float(chord[0]), float(chord[1]))
    return chord / norm


@dataclass(frozen=True)
class _Chords:
    """The body at both ends of a stretch of the route, about ``origin`` (2,), the first
    point of the front's segment: its front points ``front_a``, ``front_b`` and its chords'
    unit directions ``u_a``, ``u_b`` (each (2,)). Working about a point of the route keeps
    the numbers at the route's own scale wherever the network lies: a difference of two
    nearby coordinates is exact, a sum with a coordinate of thousands of metres is not (one
    rounding step at 6,700 m is 9e-13 m, at 5,600 km 9e-10 m)."""

    origin: np.ndarray
    front_a: np.ndarray
    front_b: np.ndarray
    u_a: np.ndarray
    u_b: np.ndarray

    @property
    def turn(self) -> float:
        """How far (rad) the body turns between both ends."""
        u_a, u_b = self.u_a, self.u_b
        return abs(math.atan2(float(u_a[0] * u_b[1] - u_a[1] * u_b[0]),
                              float(u_a[0] * u_b[0] + u_a[1] * u_b[1])))

    @property
    def straight(self) -> bool:
        """Whether the body does not turn (:data:`STRAIGHT_RAD`) and its front moves forward
        along its axis (within 1e-12 m): every footprint between is then the rectangle behind
        its front. One test, for cutting the sweep and for the pieces alike."""
        move = self.front_b - self.front_a
        u_a = self.u_a
        return self.turn <= STRAIGHT_RAD \
            and abs(float(move[0] * u_a[1] - move[1] * u_a[0])) <= 1e-12 \
            and float(move[0] * u_a[0] + move[1] * u_a[1]) >= 0.0


def _chords(path: RoutePath, a: float, b: float, front_segment: int, back_segment: int,
            length: float) -> _Chords:
    """The body with its front at ``a`` and at ``b`` on the given segments, about the front
    segment's first point (:class:`_Chords`)."""
    origin = path.points[front_segment]
    local = RoutePath(path.points - origin, path.sigma, path.station)
    front_a, _ = local.at(a, front_segment)
    front_b, _ = local.at(b, front_segment)
    back_a = _back(local, a - length, back_segment)
    back_b = _back(local, b - length, back_segment)
    chord_a, chord_b = front_a - back_a, front_b - back_b
    if math.hypot(float(chord_a[0]), float(chord_a[1])) == 0.0:
        chord_a = chord_b  # the route's start: the body lies along the first segment
    return _Chords(origin, front_a, front_b, _direction(local, chord_a),
                   _direction(local, chord_b))


def _piece(path: RoutePath, a: float, b: float, front_segment: int, back_segment: int,
           length: float, width: float, frame: RoutePath) -> SweepPiece:
    """The cover of the footprints with the front between lane positions ``a`` and ``b``
    (made about the front segment's first point, then moved to it), at ``frame``'s
    stations."""
    chords = _chords(path, a, b, front_segment, back_segment, length)
    _, start = path.at(a, front_segment)
    _, end = path.at(b, front_segment)
    scale = 1.0
    if frame is not path:
        moved = end - start
        _, start = frame.point_at(a)
        _, end = frame.point_at(b)
        scale = (end - start) / moved if moved > 0.0 else 1.0
    corners = np.vstack([footprint(f, u, length, width) for f in (chords.front_a, chords.front_b)
                         for u in (chords.u_a, chords.u_b)])  # (16, 2)
    cover = shapely.convex_hull(shapely.multipoints(corners))
    turn = chords.turn
    if turn > 0.0:
        reach = math.hypot(length, 0.5 * width)
        cover = _widen(cover, reach * (1.0 - math.cos(0.5 * turn)) + 1e-12, chords.u_a)
    cover = shapely.transform(cover, lambda xy: xy + chords.origin)
    return SweepPiece(cover, start, end, chords.straight, chords.origin + chords.front_a,
                      chords.u_a, scale)


def _widen(polygon: shapely.Geometry, margin: float, axis: np.ndarray) -> shapely.Polygon:
    """The convex hull of ``polygon``'s vertices each surrounded by an octagon around the disc
    of radius ``margin`` with two edges across the unit ``axis`` (2,) (so that a straight
    piece widens by exactly ``margin`` to its sides): contains ``polygon`` (+) disc(margin)."""
    heading = math.atan2(float(axis[1]), float(axis[0])) if np.any(axis) else 0.0
    angles = heading + _OCTAGON_ANGLES  # (8,)
    octagon = np.array([[math.cos(a), math.sin(a)] for a in angles]) / math.cos(math.pi / 8.0)
    points = shapely.get_coordinates(polygon)  # (k, 2)
    around = (points[:, None, :] + margin * octagon[None, :, :]).reshape(-1, 2)
    return shapely.convex_hull(shapely.multipoints(around))

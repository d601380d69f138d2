"""The bus's situational picture: its path, the conflict zones on it, what is hidden, and how
soon a pedestrian could be in each zone.

Pure geometry on the road map (no SUMO). Positions are measured along the bus's route
centre line (the drawn route); the distances the speed policies drive, stop and clear in
(a zone outlook's, a stop line's) are SUMO's distance from the front bumper, which a lane
whose ``length`` differs from its shape's makes longer or shorter than the drawn one
(:meth:`~sse_cosim.control.swept.RoutePath.drive`). The *path ahead* is the centre line
widened to half the bus width plus a margin.

A **conflict zone** is walkable ground that the bus's body sweeps, widened by a pedestrian's
radius: the only places where a pedestrian who stays on walkable ground can touch the bus
(every crossing on the route, and any other walkable ground the route runs over; on the
paper's road, the zebra). The body's sweep is SUMO's placement of the body along the route
(:mod:`sse_cosim.control.swept`): on a straight road the centre line widened by half the
width, on a corner wider (the rear swings out, the side cuts in). Each zone has an extent
``[start_m, end_m]`` along the route: the body touches it only while the front bumper is
between ``start_m`` and ``end_m + length``. A piece of walkable ground longer than
:data:`ZONE_PIECE_M` along the route (a strip of kerb the corridor grazes, joined to the next
at a walking area) is cut into overlapping zones about that long, which together cover it:
the bus has to clear each before anyone could reach it, not the whole strip at once.

Every step the picture says, per zone ahead, the **earliest arrival**: the soonest any
pedestrian can be in the zone, from each known pedestrian's refined region and every walkable
place where an undetected pedestrian may be. The motion model gives it
(:meth:`~sse_cosim.estimation.motion.MotionModel.earliest_arrival_s`). Each source carries
the region its motion assumption bounds, its *path region* U (where the path s may be; the
refined regions and the unobserved area are U grown by the jitter and cut), beside its
position region P (where p = s + e may be). For the speed-bounded models (the path moves at
most v per second, the position strays at most eps from it):

    arrival = max( max(0, distance(U, zone) - eps), max(0, distance(P, zone) - 2 eps) ) / v,

each margin counted once: the path must come within eps of the zone, and from P it starts
within eps of the path too. Both are lower bounds, so their larger one is (a source known
only by its position region, as the ground beyond the window, has the second alone). The
straight-line distance never exceeds the walk on walkable ground, so the arrival is an
under-estimate: sound. A known pedestrian's source also carries its fused state set
(:class:`Source`): a model that bounds the acceleration raises the arrival with the state's
velocity set, from how far the region must move along each of :data:`ARRIVAL_DIRECTIONS`
directions to reach the zone (:class:`~sse_cosim.estimation.motion.Separation`: the zone's
least and the region's largest extent along each direction, from their vertices, so the bound
holds for any shape). Hidden ground carries no state: an undetected pedestrian may be moving
at v_max toward the zone. The speed policies (:mod:`sse_cosim.control.speed`) decide on it.

A zone the bus's body is already on counts only where the footprints to come reach
(:func:`_ahead_of_body`): the ground behind them is out of a forward-moving bus's way.

Hidden ground is tracked in a *window*: within ``interest_radius_m`` of every crossing on the
route and of every conflict zone; walkable ground outside it always counts as occupied. The
paper policy looks at one crossing at a time: the nearest on the route that the bus has not
cleared (:meth:`SceneContext.crossing_at`).

Regions are of one :class:`~sse_cosim.regions.RegionKind`. The route's own geometry (its
centre line, the corridor and the zones cut from it) is drawn once, with shapely, when the
context is built: the corridor's bends are mitred (a mitre holds the round join it replaces),
and the zones are made ``outer`` regions of those shapes.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from itertools import pairwise

import numpy as np
import shapely
import shapely.ops

from sse_cosim.control.kinematics import BusDynamics
from sse_cosim.control.limits import RouteLimits
from sse_cosim.control.swept import (
    RoutePath,
    SweepPiece,
    ahead_cover,
    body_sweep,
    swept_region,
    touch_intervals,
)
from sse_cosim.estimation.motion import MotionModel, Separation, unit_fan
from sse_cosim.regions import Region, RegionKind, apart
from sse_cosim.regions.polygon import OFFSET_MARGIN
from sse_cosim.scenario.model import AutomatedVehicle, Controller
from sse_cosim.sets import Zonotope
from sse_cosim.world.checks.lights import AREA_TOL_M, on_crossing_reach_m
from sse_cosim.world.roadmap import RoadMap
from sse_cosim.world.signals import STOP_FOR, CrossingLights, Signal, SignalState

ZONE_PIECE_M = 4.0  # conflict zones are cut into pieces about this long along the route (m)
_CUT_OVERLAP_M = 0.5  # consecutive pieces overlap by twice this along the route (m)
_PIECE_TOL_M = 1e-6  # a piece this much longer than ZONE_PIECE_M, by rounding, stays whole (m)
_CUT_COVER_M2 = 1e-9  # what the cut pieces may leave of a zone uncovered, by rounding (m²)
LIT_AREA_M2 = 1e-9  # a zone's ground off the red crossings' own ground by less lies on it (m²)
ARRIVAL_DIRECTIONS = 32  # fan of directions along which a known pedestrian's gap is measured
FAN = unit_fan(ARRIVAL_DIRECTIONS)  # (K, 2) unit directions


@dataclass(frozen=True)
class Source:
    """Where a pedestrian may be (``region``: its simulated position), for a known one its
    fused state set (``state``; None: unknown, the model's worst case), and where its path
    may be (``path``: the region the motion assumption bounds, which ``region`` is grown from
    by the jitter; None: not known apart from ``region``); ``off_s``: per signalised crossing
    of ``SceneContext.lit``, how long from now its pedestrian surely stays off that crossing
    (:class:`LightClaims`; 0 or none: nothing known)."""

    region: Region
    state: Zonotope | None = None
    path: Region | None = None
    off_s: tuple[float, ...] = ()  # per SceneContext.lit: how long it surely stays off (s)


@dataclass(frozen=True)
class ConflictZone:
    """Walkable ground the bus sweeps (widened by a pedestrian's radius), and its extent along
    the route (m): the front reaches it at ``start_m``, the rear clears it at ``end_m`` plus
    the bus's length. ``beyond_arrival_s``: the earliest arrival of a pedestrian from the
    walkable ground outside the tracked window (always possibly occupied)."""

    polygon: Region
    start_m: float
    end_m: float
    beyond_arrival_s: float
    ground: shapely.Geometry | None = None  # the piece of walkable ground ``polygon`` holds
    sweep: tuple[SweepPiece, ...] = ()  # the pieces of the body's sweep that meet it
    lit: tuple[int, ...] = ()  # the signalised crossings (SceneContext.lit) it lies on

    @cached_property
    def least_along(self) -> np.ndarray:
        """min over the zone of n.q for each direction n of :data:`FAN`, shape (K,) (computed
        once)."""
        return -self.polygon.support(-FAN)


@dataclass(frozen=True)
class LitCrossing:
    """A signalised crossing whose own ground the route's zones meet: its ``id``, its
    ``lights``, its ``own`` ground (RoadMap.own_grounds: where a walker's centre is only while
    it is on that crossing) and its area grown by how far a walker on it may lie outside it
    (``on_crossing_reach_m``), as regions: ``near`` (outer: holds every walker on the
    crossing) and ``within`` (inner: a walker outside it is off the crossing).
    ``beyond_off``: the ground beyond the tracked window lies off the crossing."""

    id: str
    lights: CrossingLights
    own: shapely.Geometry
    near: Region
    within: Region
    beyond_off: bool


@dataclass(frozen=True)
class RouteCrossing:
    """A crossing the bus's body sweeps: its ``area`` and its extent along the route (m), from
    the nearest to the farthest vertex of its convex hull."""

    area: Region
    start_m: float
    end_m: float


@dataclass(frozen=True)
class StopLine:
    """A signalised stop line on the route: how far along it (m; the end of the lane before a
    junction) and the traffic light link that lets the route on there."""

    at_m: float
    signal: Signal


@dataclass(frozen=True)
class SceneContext:
    """What does not change during a run: the route, walkable ground, the conflict zones."""

    route_line: shapely.LineString
    walkable: Region  # the road map's walkable ground (measured patches included)
    crossings: tuple[RouteCrossing, ...]  # the crossings on the route, nearest first
    bus: AutomatedVehicle
    config: Controller
    pedestrians: MotionModel  # the estimator's: how far and how soon a pedestrian gets
    dynamics: BusDynamics
    window: Region  # where hidden ground is tracked; outside, it counts as occupied
    zones: tuple[ConflictZone, ...]
    kind: RegionKind
    sweep_width_m: float  # the body's sweep: its width and a pedestrian's radius each side
    limits: RouteLimits  # the speed limits along the route (in SUMO's distance)
    path: RoutePath  # the route as SUMO drives it: the drawn line and SUMO's distance on it
    stop_lines: tuple[StopLine, ...] = ()  # the route's signalised stop lines, nearest first
    lit: tuple[LitCrossing, ...] = ()  # the signalised crossings the zones meet
    _relevant: dict[tuple[int, float], Region] = field(default_factory=dict, repr=False)

    @classmethod
    def build(
        cls, roadmap: RoadMap, route_edges: Sequence[str], bus: AutomatedVehicle,
        config: Controller, pedestrians: MotionModel, pedestrian_radius: float,
        step_length: float, kind: RegionKind,
    ) -> SceneContext:
        """Prepare the static geometry for a bus driving ``route_edges`` (regions of
        ``kind``)."""
        route_line = roadmap.route_line(route_edges)
        lanes, changes = roadmap.route_plan(route_edges)
        walkable = roadmap.walkable
        corridor = _widened(route_line, 0.5 * bus.width_m + pedestrian_radius)
        path = RoutePath.of_route(lanes, changes)
        sweep = body_sweep(path, bus.length_m, bus.width_m + 2.0 * pedestrian_radius)
        planned = swept_region(sweep)
        corridor = _with_sweep(corridor, _from_start(planned, route_line), walkable)
        crossings = _route_crossings(route_line, corridor, [c.area for c in roadmap.crossings],
                                     kind)
        swept = []
        for piece, start, end in _swept_walkable(route_line, corridor, walkable):
            region = kind.outer(piece)  # one region for each pass over the piece
            swept.extend((piece, region, *touched)
                         for touched in _touched(sweep, piece, start, end, bus.length_m))
        swept.sort(key=lambda piece: piece[2])
        ground = kind.outer(walkable)
        window = _window(crossings, [(region, start, end) for _, region, start, end, _ in swept],
                         config.interest_radius_m, kind)
        beyond = Source(ground.difference(window))
        lit = _lit_crossings(roadmap, [piece for piece, *_ in swept], beyond.region,
                             pedestrian_radius, kind)
        zones = tuple(
            ConflictZone(region, start, end, _arrival(beyond, region, pedestrians, kind), piece,
                         meeting, tuple(k for k, c in enumerate(lit) if _meets(piece, c.own)))
            for piece, region, start, end, meeting in swept)
        return cls(route_line, ground, crossings, bus, config, pedestrians,
                   BusDynamics.of(bus, config, step_length), window, zones, kind,
                   bus.width_m + 2.0 * pedestrian_radius,
                   RouteLimits.of_lanes(lanes, changes), path,
                   _stop_lines(roadmap, route_edges, route_line), lit)

    def releases(self, signals: Mapping[str, SignalState]) -> list[float]:
        """Per crossing of :attr:`lit`, the least time (s) until its light can let its walkers
        on (0: it does now), from the lights as ``signals`` show them."""
        return [crossing.lights.release_s(signals) for crossing in self.lit]

    def next_stop_line(self, front_s: float) -> StopLine | None:
        """The nearest signalised stop line the front (at ``front_s``) has not passed; None
        if none is left."""
        return next((line for line in self.stop_lines if line.at_m >= front_s), None)

    def crossing_at(self, front_s: float) -> RouteCrossing | None:
        """The nearest crossing on the route that the bus (front at ``front_s``) has not
        cleared with its rear; once it has cleared them all, the last one; None if the route
        has no crossing. (The paper policy's "the crossing".)"""
        for crossing in self.crossings:
            if crossing.end_m + self.bus.length_m > front_s:
                return crossing
        return self.crossings[-1] if self.crossings else None

    def reach_radius(self, front_s: float, front_m: float) -> float:
        """How far from the crossing (:meth:`crossing_at`) an unseen pedestrian can be and
        still reach it before the bus, keeping its nominal speed (:meth:`top_speed`), has
        cleared it; capped by ``interest_radius_m``. (The paper policy's notion of "near the
        crossing".) ``front_s``: the front along the drawn route, ``front_m`` the same in
        SUMO's distance."""
        crossing = self.crossing_at(front_s)
        if crossing is None or crossing.end_m - front_s + self.bus.length_m <= 0:
            return 0.0
        to_clear = self.path.drive(crossing.end_m + self.bus.length_m) - front_m
        radius = self.pedestrians.reach_during_m(to_clear, self.top_speed(front_m, to_clear))
        return min(radius, self.config.interest_radius_m)

    def path_ahead(self, front_s: float, length: float, margin: float) -> Region:
        """The corridor the bus sweeps over the next ``length`` metres, widened by ``margin``."""
        start = min(max(front_s, 0.0), self.route_line.length)
        end = min(front_s + max(length, 0.0), self.route_line.length)
        if end <= start:
            return self.kind.empty()
        centre = route_piece(self.route_line, self.route_stations, start, end)
        return self.kind.outer(_widened(centre, 0.5 * self.bus.width_m + margin))

    def relevant(self, crossing: RouteCrossing, radius: float) -> Region:
        """``crossing``'s area widened by ``radius``; kept, since the reach radius stays at its
        cap while the bus is far from the crossing, and at one value while the bus stands."""
        key = (self.crossings.index(crossing), radius)
        if key not in self._relevant:
            self._relevant[key] = crossing.area.dilate(radius)
        return self._relevant[key]

    @cached_property
    def zone_drives(self) -> tuple[tuple[float, float], ...]:
        """Per zone of :attr:`zones`, SUMO's distances along the route (m) where the front
        reaches its near end (:meth:`~sse_cosim.control.swept.RoutePath.drive_before`) and
        where the rear has cleared it (computed once)."""
        length = self.bus.length_m
        return tuple((self.path.drive_before(zone.start_m), self.path.drive(zone.end_m + length))
                     for zone in self.zones)

    @cached_property
    def route_stations(self) -> np.ndarray:
        """How far along the route each vertex of ``route_line`` but the last lies (m), shape
        (n - 1,): see :func:`route_piece` (computed once)."""
        return route_stations(self.route_line)

    def stopping_distance(self, speed: float) -> float:
        """Reaction distance plus comfortable braking distance plus the stopping margin (m)."""
        cfg = self.config
        braking = speed**2 / (2.0 * self.bus.comfortable_decel_mps2)
        return speed * cfg.reaction_time_s + braking + cfg.stopping_margin_m

    def within_reach(self, front_m: float, speed: float) -> list[int]:
        """The zones whose plans a command can need, with the front at ``front_m`` (SUMO's
        distance) at ``speed`` (:func:`within_reach`)."""
        return within_reach(self.zone_drives, front_m, speed, self.dynamics,
                            self.bus.nominal_speed_mps, self.config.stopping_margin_m)

    def limit_on(self, front_m: float, distance: float) -> float:
        """The slowest speed (m/s) the speed limits may hold the bus to while its front drives
        ``distance`` m on from ``front_m`` (both in SUMO's distance;
        :meth:`~sse_cosim.control.limits.RouteLimits.least`: the limits on that stretch and
        just beyond it)."""
        return self.limits.least(front_m, front_m + distance, self.dynamics.decel)

    def top_speed(self, front_m: float, distance: float) -> float:
        """The fastest speed (m/s) the bus can hold while its front drives ``distance`` m on
        from ``front_m`` (SUMO's distance): its nominal speed, within :meth:`limit_on`."""
        return min(self.bus.nominal_speed_mps, self.limit_on(front_m, distance))

    def standstill_clear_time(self, to_clear: float, limit_mps: float) -> float:
        """Time (s) the bus needs from standstill, at its nominal speed within ``limit_mps``
        (:meth:`limit_on` of the way), to clear a zone whose far end its front must still
        travel ``to_clear`` metres to pass."""
        return self.dynamics.travel_time(to_clear, 0.0,
                                         min(self.bus.nominal_speed_mps, limit_mps))


@dataclass(frozen=True)
class ZoneOutlook:
    """One conflict zone ahead, seen from the bus now (m, s).

    ``to_start_m``: front bumper to the zone (negative once the front is in it);
    ``to_clear_m``: how far the front must still travel until the rear has cleared it (both
    in SUMO's distance, the one the bus's speed drives);
    ``arrival_s``: the earliest time any pedestrian, known or not, can be in it;
    ``in_view_arrival_s``: the earliest time a pedestrian in view (some node detects it now)
    can be in it, infinite if none can; ``index``: the zone's place in
    ``SceneContext.zones``; ``clear_s``: the time the bus needs from standstill to clear it
    (:meth:`SceneContext.standstill_clear_time`); ``limit_mps``: the slowest speed the
    limits may hold the bus to until its rear has cleared it (a pass holds no more;
    :meth:`SceneContext.limit_on`); ``ground``: its walkable ground as far as
    the body can still touch it (:func:`_ahead_of_body`; a check's, the recorder's);
    ``lit``: the signalised crossings whose own ground it meets, each its id, that own ground
    and its lights (the route's geometry and the network's programs, for the checks).
    """

    index: int
    to_start_m: float
    to_clear_m: float
    arrival_s: float
    in_view_arrival_s: float = math.inf
    clear_s: float = 0.0
    ground: shapely.Geometry | None = None
    lit: tuple[tuple[str, shapely.Geometry, CrossingLights], ...] = ()
    limit_mps: float = math.inf


@dataclass(frozen=True)
class Picture:
    """Everything the speed policies decide on, for one step."""

    front_s: float  # bus front along its drawn route (m)
    front_drive_m: float  # the same in SUMO's distance along the route (m)
    speed_mps: float  # the bus's actual speed (m/s)
    # front to the near edge of SceneContext.crossing_at (m); negative once on it; None if the
    # route has no crossing
    distance_to_crossing: float | None
    crossing_ahead: bool
    reach_radius_m: float  # how far from the crossing a pedestrian still matters (paper policy)
    own_occluded_m2: float  # hidden in the bus's own view and possibly holding a pedestrian
    unresolved_occluded_m2: float  # the part of it within the reach radius of the crossing
    pedestrian_near_crossing: bool
    pedestrian_near_path: bool
    pedestrian_in_stopping_distance: bool
    zones: tuple[ZoneOutlook, ...] = ()  # conflict zones not yet cleared, nearest first
    path_clear: bool = True  # from standstill the bus would clear every zone before anyone
    # the nearest signalised stop line ahead: its link, and how far ahead (m) it is while its
    # light tells traffic to stop (STOP_FOR; None while it lets the bus on, or without one;
    # SUMO's distance)
    light: Signal | None = None
    stop_line_m: float | None = None
    limit_mps: float = math.inf  # the speed limit where the front is (SUMO holds the bus to it)


def assess(
    context: SceneContext,
    front_xy: np.ndarray,
    speed: float,
    own_occluded: Region,
    unobserved: Source,
    pedestrian_regions: Iterable[Source],
    in_view: Iterable[Source] = (),
    in_view_beyond: bool = False,
    floors: Mapping[int, float] | None = None,
    signals: Mapping[str, SignalState] | None = None,
    releases: Sequence[float] | None = None,
    route_m: float | None = None,
) -> Picture:
    """The picture at one step.

    ``front_xy`` (2,) is the bus's front bumper; ``speed`` its actual speed; ``own_occluded``
    what its sensors' shadows hide inside their fields of view; ``unobserved`` the walkable
    area where a pedestrian nobody detected may be (every node's views, shared ones included),
    with its path region;
    ``pedestrian_regions`` where each known pedestrian may be, unless outside the window, with
    its state set; ``in_view`` those among them of the pedestrians some node detects now;
    ``in_view_beyond``: whether one of those may be outside the window instead; ``floors``:
    zone index -> an earliest arrival known from earlier steps (:func:`arrival_floors`);
    ``signals``: the scene's traffic lights by id, as they show now (the bus's own stop
    lines read them); ``releases``: :meth:`SceneContext.releases` of them, if the caller
    has it already (else worked out here); ``route_m``: SUMO's distance of the front along
    the route (its odometer; the world checks that it lies at ``front_xy``), else read off
    the drawn front (:meth:`~sse_cosim.control.swept.RoutePath.drive`, where a passage drawn
    without length leaves it between the passage's ends).
    """
    cfg = context.config
    front_s = context.route_line.project(shapely.Point(front_xy))
    front = context.path.drive(front_s) if route_m is None else route_m
    crossing = context.crossing_at(front_s)
    to_crossing = None if crossing is None else crossing.start_m - front_s
    crossing_ahead = (crossing is not None and crossing.end_m > front_s
                      and crossing.start_m - front_s <= cfg.crossing_horizon_m)
    own_hidden = own_occluded.intersection(unobserved.region)
    reach = context.reach_radius(front_s, front)
    relevant = context.relevant(crossing, reach) if crossing is not None and reach > 0 \
        else context.kind.empty()
    hidden_in_reach = own_hidden.intersection(relevant)
    known = [s for s in pedestrian_regions if not s.region.is_empty]
    sets = [s.region for s in known]
    # the corridors ahead only matter to a known pedestrian's region: none, none built
    near_path = context.path_ahead(front_s, cfg.crossing_horizon_m, cfg.path_margin_m) \
        if sets else context.kind.empty()
    stopping = context.path_ahead(front_s, context.path.point_at(
        front + context.stopping_distance(speed))[1] - front_s, 0.0) if sets else \
        context.kind.empty()
    line = context.next_stop_line(front_s)
    if releases is None:
        releases = context.releases(signals or {})
    zones = _outlook(context, front_s, front, speed, [unobserved, *known],
                     [s for s in in_view if not s.region.is_empty], in_view_beyond, floors or {},
                     releases)
    return Picture(
        front_s=float(front_s),
        front_drive_m=front,
        speed_mps=float(speed),
        distance_to_crossing=None if to_crossing is None else float(to_crossing),
        crossing_ahead=bool(crossing_ahead),
        reach_radius_m=float(reach),
        own_occluded_m2=float(own_hidden.area),
        unresolved_occluded_m2=float(hidden_in_reach.area),
        pedestrian_near_crossing=any(s.intersects(relevant) for s in sets),
        pedestrian_near_path=any(s.intersects(near_path) for s in sets),
        pedestrian_in_stopping_distance=any(s.intersects(stopping) for s in sets),
        zones=zones,
        path_clear=all(z.arrival_s > z.clear_s for z in zones),
        light=None if line is None else line.signal,
        stop_line_m=None if line is None or _shows(signals or {}, line.signal) not in STOP_FOR
        else context.path.drive_before(line.at_m) - front,
        limit_mps=context.limits.at(front),
    )


def _shows(signals: Mapping[str, SignalState], signal: Signal) -> str:
    """What ``signal``'s light shows on its link now ("" for a light not in ``signals``)."""
    light, link = signal
    return signals[light].shows(link) if light in signals else ""


def arrival_floors(previous: Picture, elapsed_s: float) -> dict[int, float]:
    """Per zone index, the earliest arrival that ``previous`` (``elapsed_s`` ago) still
    proves: a pedestrian moves no faster than the bound (A1, docs/controller.md), so nobody
    can be in a zone sooner than its earliest arrival then, less the time since.

    The sets alone can bring an arrival nearer by more than that: a dilation holds the exact
    one (:mod:`sse_cosim.regions`), so a region's corner moves up to sqrt(2) times as far as
    the bound (a polygon's cut mitre) in a step. A plan
    proven at one step then fails at the next against the new sets, though not against the
    truth, and the bus brakes in emergency. The floor keeps the picture's arrivals as the
    proof has them."""
    return {z.index: z.arrival_s - elapsed_s for z in previous.zones}


@dataclass
class ArrivalMemory:
    """The last consistent step's picture, kept for the next step's :func:`arrival_floors`.

    A picture made while the picture is inconsistent (a flagged source may have misled it)
    is not kept, and an inconsistent step gets no floors: after a flag the sets alone decide
    until a consistent picture is made again."""

    dt: float
    _last: tuple[int, Picture] | None = None

    def floors(self, step: int, inconsistent: bool) -> dict[int, float]:
        """Per zone index, the earliest arrival the kept picture proves at ``step``."""
        if inconsistent or self._last is None:
            return {}
        then, picture = self._last
        return arrival_floors(picture, (step - then) * self.dt)

    def keep(self, step: int, picture: Picture, inconsistent: bool) -> None:
        """Keep ``picture`` (made at ``step``) unless it was made while inconsistent."""
        self._last = None if inconsistent else (step, picture)


class LightClaims:
    """Which known pedestrians a red light keeps off its crossing, and until when: labelled
    detections only (a key is one pedestrian all run long).

    At a step where a signalised crossing's light holds its walkers (the release ``R > 0``,
    :meth:`SceneContext.releases`) and a pedestrian's region misses the crossing's area
    (``LitCrossing.near``), that pedestrian is off the crossing, so it stays off until now +
    R (the ``pedestrian_lights`` assumption). The claim holds while it lasts, whatever the
    region does later: a walker waiting at the kerb, its region reaching onto the crossing by
    its noise, is known to wait. A step whose picture is inconsistent (a flagged source may
    have misled the regions) drops every claim and makes none, as :class:`ArrivalMemory`
    does."""

    def __init__(self, context: SceneContext) -> None:
        self.context = context
        self._until: dict[tuple[str, int], float] = {}  # (key, crossing) -> off until (s)

    def update(self, now_s: float, regions: Mapping[str, Region], releases: Sequence[float],
               inconsistent: bool) -> dict[str, tuple[float, ...]]:
        """Each key's ``off_s`` (see :class:`Source`) at ``now_s``, its claims renewed from
        ``regions`` (key -> the pedestrian's region) and ``releases`` (per crossing)."""
        if inconsistent:
            self._until = {}
            return {}
        lit = self.context.lit
        for key, region in regions.items():
            for i, (crossing, release) in enumerate(zip(lit, releases, strict=True)):
                if release > 0.0 and not region.intersects(crossing.near):
                    self._until[(key, i)] = max(self._until.get((key, i), 0.0), now_s + release)
        self._until = {claim: until for claim, until in self._until.items() if until > now_s}
        return {key: tuple(self._until.get((key, i), now_s) - now_s for i in range(len(lit)))
                for key in regions}


def within_reach(drives: Sequence[tuple[float, float]], front_m: float, speed: float,
                 dynamics: BusDynamics, top_mps: float, margin_m: float) -> list[int]:
    """The zones (indices into ``drives``, in route order) whose plans a command can need:
    ``drives`` holds per zone, in route order, where the front reaches it and where the rear
    has cleared it (m, SUMO's distance), the front is at ``front_m`` and the bus at ``speed``,
    its commands at most ``top_mps``. A zone is left out when it begins at least a
    comfortable stop (:meth:`~sse_cosim.control.kinematics.BusDynamics.stopping_distance` at
    ``top_mps`` or ``speed``, the faster) and ``margin_m`` (the stopping margin) beyond where
    the last stop can be ordered -- after any command's look-ahead, or after the far end of a
    nearer zone kept (a pass of it). Every plan then stops before it, whatever its arrival
    (docs/controller.md, "Zones beyond the plans' reach"), and so before every zone beyond
    it: no arrival need be worked out for them."""
    stop = dynamics.stopping_distance(max(speed, top_mps)) + margin_m
    reach = dynamics.lookahead_distance(speed, top_mps) + stop
    kept = []
    for index, (start, end) in enumerate(drives):
        if start - front_m >= reach:
            break
        kept.append(index)
        reach = max(reach, end - front_m + stop)
    return kept


def _outlook(context: SceneContext, front_s: float, front: float, speed: float,
             sources: Sequence[Source], in_view: Sequence[Source], in_view_beyond: bool,
             floors: Mapping[int, float], releases: Sequence[float]) -> tuple[ZoneOutlook, ...]:
    """The zones the bus has not yet cleared and a plan can reach
    (:meth:`SceneContext.within_reach` at ``speed``), as far as its body can still touch them
    (:func:`_ahead_of_body`), with the earliest arrival from ``sources`` (and from beyond the
    window; never before its ``floors``) and from the pedestrians in view alone: their regions
    ``in_view``, and beyond the window if ``in_view_beyond`` (every source to every such zone
    in one distance call). A zone on the own ground of a signalised crossing whose light
    holds its walkers (``releases``: per ``context.lit`` the least time until it can let them
    on, 0 if it does now) gets the later arrival its lights allow (:func:`_lit_arrival`).
    ``front_s`` is the front along the drawn route, ``front`` the same in SUMO's distance."""
    length, drives = context.bus.length_m, context.zone_drives
    ahead = [(index, _ahead_of_body(context, zone, front_s), drives[index][1] - front)
             for index in context.within_reach(front, speed)
             if (zone := context.zones[index]).end_m + length > front_s]
    ahead = [(index, zone, to_clear) for index, zone, to_clear in ahead
             if not zone.polygon.is_empty]
    zones = [zone for _, zone, _ in ahead]
    beyond = np.array([zone.beyond_arrival_s for zone in zones])
    arrivals = np.minimum(beyond, _arrivals(sources, zones, context.pedestrians, context.kind))
    in_view_arrivals = np.minimum(beyond if in_view_beyond else math.inf, _arrivals(
        in_view, zones, context.pedestrians, context.kind))
    every, seen = HeldSplits(sources, context.kind), HeldSplits(in_view, context.kind)
    for k, zone in enumerate(zones):
        held = [(context.lit[i], releases[i]) for i in zone.lit if releases[i] > 0.0]
        if held and zone.ground is not None:
            arrivals[k] = _lit_arrival(context, zone, held, every, True)
            in_view_arrivals[k] = _lit_arrival(context, zone, held, seen, in_view_beyond)
    limits = [context.limit_on(front, to_clear) for _, _, to_clear in ahead]
    return tuple(
        ZoneOutlook(index, drives[index][0] - front, to_clear,
                    max(float(arrival), floors.get(index, 0.0)), float(in_view_arrival),
                    context.standstill_clear_time(to_clear, limit), zone.ground,
                    tuple((c.id, c.own, c.lights) for c in (context.lit[i] for i in zone.lit)),
                    limit)
        for (index, zone, to_clear), arrival, in_view_arrival, limit
        in zip(ahead, arrivals, in_view_arrivals, limits, strict=True))


class HeldSplits:
    """Sources split at signalised crossings, each split made once a step: ``sources`` (those
    not empty), and per crossing their parts near its area and off it (:func:`_held_arrivals`;
    the zones on one crossing share them)."""

    def __init__(self, sources: Sequence[Source], kind: RegionKind) -> None:
        self.sources = [s for s in sources if not s.region.is_empty]
        self.kind = kind
        self._splits: dict[int, tuple[list[Source], list[Source]]] = {}

    def split(self, index: int, crossing: LitCrossing) -> tuple[list[Source], list[Source]]:
        """The sources' parts near ``crossing``'s area and off it (``SceneContext.lit[index]``;
        a source whose bounding box misses the area's is wholly off it, with no overlay)."""
        if index not in self._splits:
            near, within = crossing.near, crossing.within
            self._splits[index] = (
                [Source(self.kind.empty() if apart(s.region, near)
                        else s.region.intersection(near), s.state) for s in self.sources],
                [Source(s.region if apart(s.region, within) else s.region.difference(within),
                        s.state) for s in self.sources])
        return self._splits[index]


def _lit_arrival(context: SceneContext, zone: ConflictZone,
                 held: Sequence[tuple[LitCrossing, float]], sources: HeldSplits,
                 with_beyond: bool) -> float:
    """The earliest arrival in ``zone`` from ``sources`` (and from beyond the window if
    ``with_beyond``) where its lights hold the walkers of some signalised crossings it lies
    on (``held``: each crossing and how long at least its light holds them, s).

    The zone splits into its ground on each such crossing's own ground and the rest. On the
    rest, the arrival is the usual one. On a crossing's own ground, a walker's centre is only
    while it walks on that crossing, and a walker off the crossing now does not step on before
    the release (the ``pedestrian_lights`` assumption, checked by the world every step); a
    walker on it has its centre in its area (checked too). So each source splits into its part
    near the crossing's area (walkers that may be on it: the usual arrival) and its part off
    the area (walkers off it: no sooner than the release), and its arrival there is the
    smaller of the two, never less than the usual one (:func:`_held_arrivals`)."""
    kind, ground = context.kind, zone.ground
    red = shapely.union_all([crossing.own for crossing, _ in held])
    rest = shapely.difference(ground, red)
    beyond = zone.beyond_arrival_s if with_beyond else math.inf
    best = math.inf
    if rest.area > LIT_AREA_M2:  # less: the overlay's rounding along the own ground's edge
        best = min(beyond, float(_arrivals(sources.sources, [_target(rest, kind)],
                                           context.pedestrians, kind)[0]))
    for crossing, release in held:
        piece = shapely.intersection(ground, crossing.own)
        if piece.area <= 0.0:
            continue
        from_beyond = max(release, beyond) if crossing.beyond_off else beyond
        best = min(best, from_beyond, _held_arrivals(
            sources, _target(piece, kind), context.lit.index(crossing), crossing, release,
            context.pedestrians, kind))
    return best


def _held_arrivals(sources: HeldSplits, target: ConflictZone, index: int,
                   crossing: LitCrossing, release: float, pedestrians: MotionModel,
                   kind: RegionKind) -> float:
    """The earliest arrival at ``target`` (on ``crossing``, ``SceneContext.lit[index]``'s
    own ground) from ``sources`` while the crossing's light holds its walkers at least
    ``release`` (s): per source the larger of its usual arrival and the smaller of its part
    near the crossing's area and (no sooner than the release) its part off it -- or, for a
    pedestrian known to stay off the crossing a while (``Source.off_s``), no sooner than that
    and the release."""
    parts = sources.sources
    if not parts:
        return math.inf
    near, away = sources.split(index, crossing)
    usual = _source_matrix(parts, [target], pedestrians, kind)[:, 0]  # (n,)
    on = _source_matrix(near, [target], pedestrians, kind)[:, 0]
    off = _source_matrix(away, [target], pedestrians, kind)[:, 0]
    held = np.array([s.off_s[index] if s.off_s else 0.0 for s in parts])  # (n,)
    split = np.where(held > 0.0, np.maximum(release, held), np.minimum(on, np.maximum(release,
                                                                                     off)))
    return float(np.maximum(usual, split).min())


def _target(ground: shapely.Geometry, kind: RegionKind) -> ConflictZone:
    """A piece of a zone's ground as a zone to arrive at (its region contains the piece)."""
    return ConflictZone(kind.outer(ground), 0.0, 0.0, math.inf, ground)


def _ahead_of_body(context: SceneContext, zone: ConflictZone, front_s: float) -> ConflictZone:
    """``zone`` as far as the body, its front at ``front_s``, can still touch it.

    Once the front has passed the zone's start, the part of the zone that only footprints
    with the front further back covered is out of the bus's way for good (it moves forward
    along its route): the zone counts where the footprints from ``front_s`` on reach
    (:func:`~sse_cosim.control.swept.ahead_cover`, widened by a pedestrian's radius as the
    sweep is). Without it, hidden ground behind a bus standing with its rear over a sidewalk
    corner keeps an arrival there sooner than the bus can move its rear out, and the bus
    never moves again. A zone not yet reached is whole."""
    if front_s <= zone.start_m or zone.ground is None:
        return zone
    ahead = ahead_cover(zone.sweep, front_s, context.bus.length_m, context.sweep_width_m)
    ground = shapely.intersection(zone.ground, ahead)
    return replace(zone, polygon=context.kind.outer(ground), ground=ground)


def _meeting(sweep: Sequence[SweepPiece], piece: shapely.Geometry) -> tuple[SweepPiece, ...]:
    """The pieces of ``sweep`` whose cover meets ``piece``."""
    covers = np.array([p.cover for p in sweep], dtype=object)
    return tuple(p for p, meets in zip(sweep, shapely.intersects(covers, piece), strict=True)
                 if meets)


def _arrivals(sources: Iterable[Source], zones: Sequence[ConflictZone],
              pedestrians: MotionModel, kind: RegionKind) -> np.ndarray:
    """Earliest time (s) a pedestrian somewhere in ``sources`` can be in each of ``zones``,
    shape (z,) (inf without a source): the soonest over the sources of each one's arrival
    (:func:`_source_matrix`)."""
    parts = [s for s in sources if not s.region.is_empty]
    if not parts or not zones:
        return np.full(len(zones), math.inf)
    return _source_matrix(parts, zones, pedestrians, kind).min(axis=0)


def _source_matrix(sources: Sequence[Source], zones: Sequence[ConflictZone],
                   pedestrians: MotionModel, kind: RegionKind) -> np.ndarray:
    """Each source's earliest arrival at each zone, shape (n, z) (inf from an empty region):
    the larger of the model's two bounds where it has a path region (from the path region,
    the jitter counted once, at the zone; from the position region, twice), else the
    position region's."""
    polygons = [zone.polygon for zone in zones]
    arrivals = _source_arrivals(sources, [s.region for s in sources], polygons, zones,
                                pedestrians, kind, of_path=False)  # (n, z)
    pathed = [i for i, s in enumerate(sources) if s.path is not None and not s.path.is_empty]
    if pathed:
        arrivals[pathed] = np.maximum(arrivals[pathed], _source_arrivals(
            [sources[i] for i in pathed], [sources[i].path for i in pathed], polygons, zones,
            pedestrians, kind, of_path=True))
    return arrivals


def _source_arrivals(sources: Sequence[Source], regions: Sequence[Region],
                     polygons: Sequence[Region], zones: Sequence[ConflictZone],
                     pedestrians: MotionModel, kind: RegionKind, of_path: bool) -> np.ndarray:
    """The model's earliest arrival from each of ``regions`` (source i's region or path
    region, ``of_path`` says which) at each zone, shape (n, z): with the source's state set
    and the fan's separation where the model uses them, else from the distance alone (all
    such sources in one call)."""
    distances = kind.distances(regions, polygons)  # (n, z)
    if not pedestrians.uses_state:
        return pedestrians.earliest_arrival_s(distances, of_path=of_path)
    arrival = np.empty_like(distances)
    least = np.array([zone.least_along for zone in zones])  # (z, K)
    for i, (source, region) in enumerate(zip(sources, regions, strict=True)):
        separation = None if source.state is None else \
            Separation(FAN, least - region.support(FAN)[None, :])
        arrival[i] = pedestrians.earliest_arrival_s(distances[i], source.state, separation,
                                                    of_path=of_path)
    return arrival


def _arrival(source: Source, zone: Region, pedestrians: MotionModel,
             kind: RegionKind) -> float:
    """Earliest time (s) a pedestrian somewhere in ``source`` can be in ``zone``."""
    return float(_arrivals([source], [ConflictZone(zone, 0.0, 0.0, math.inf)], pedestrians,
                           kind)[0])


def route_stations(line: shapely.LineString) -> np.ndarray:
    """How far along ``line`` each of its vertices but the last lies, shape (n - 1,), summed
    segment by segment as ``shapely.ops.substring`` sums them."""
    stations, current = [], 0.0
    for p1, p2 in pairwise(line.coords):
        stations.append(current)
        current += ((p2[0] - p1[0]) ** 2 + (p2[1] - p1[1]) ** 2) ** 0.5
    return np.array(stations)


def route_piece(line: shapely.LineString, stations: np.ndarray, start: float,
                end: float) -> shapely.LineString:
    """``shapely.ops.substring(line, start, end)`` for 0 <= start < end <= length, the same
    line string: the points at ``start`` and ``end`` with the vertices strictly between, found
    from the ``stations`` of :func:`route_stations` instead of a walk along the line."""
    ends = shapely.get_coordinates(shapely.line_interpolate_point(line, [start, end]))  # (2, 2)
    between = np.flatnonzero((stations > start) & (stations < end))
    inner = shapely.get_coordinates(line)[between]  # (k, 2)
    return shapely.linestrings(np.vstack([ends[:1], inner, ends[1:]]))


def _route_crossings(route_line: shapely.LineString, corridor: shapely.Geometry,
                     areas: Sequence[shapely.Polygon],
                     kind: RegionKind) -> tuple[RouteCrossing, ...]:
    """The crossings among ``areas`` that the ``corridor`` around the route overlaps (touching
    is not enough), with their extent along the route, nearest first."""
    crossings = []
    for area in areas:
        if shapely.intersection(corridor, area).area <= 0.0:
            continue
        along = [route_line.project(shapely.Point(p)) for p in _boundary_points(area)]
        crossings.append(RouteCrossing(kind.outer(area), min(along), max(along)))
    return tuple(sorted(crossings, key=lambda c: c.start_m))


def _window(crossings: Sequence[RouteCrossing], swept: Sequence[tuple[Region, float, float]],
            radius: float, kind: RegionKind) -> Region:
    """Where hidden ground is tracked: within ``radius`` of every crossing on the route and of
    every swept piece of walkable ground that no crossing covers."""
    covered = kind.union_all([c.area for c in crossings])
    others = [piece for piece, _, _ in swept if not covered.covers(piece)]
    return kind.union_all([*(c.area for c in crossings), *others]).dilate(radius)


def _swept_walkable(route_line: shapely.LineString, corridor: shapely.Geometry,
                    walkable: shapely.Geometry) -> list[tuple[shapely.Geometry, float, float]]:
    """Each connected piece of walkable ground inside the ``corridor`` around the route, cut
    into pieces of about :data:`ZONE_PIECE_M` along it (:func:`_cut_along`), with its extent
    along the route (:func:`_extent`), in route order."""
    reach = shapely.hausdorff_distance(corridor, route_line) + 1.0  # beyond every corridor point
    pieces = [piece for whole in shapely.get_parts(shapely.intersection(corridor, walkable))
              if whole.area > 0.0 for piece in _cut_along(whole, route_line, reach)]
    return sorted(pieces, key=lambda piece: piece[1])


def _extent(part: shapely.Geometry, route_line: shapely.LineString) -> tuple[float, float]:
    """``part``'s extent along the route (m): the min and max of its vertices' projections."""
    along = shapely.line_locate_point(route_line, shapely.points(shapely.get_coordinates(part)))
    return float(along.min()), float(along.max())


def _cut_along(part: shapely.Geometry, route_line: shapely.LineString,
               reach: float) -> list[tuple[shapely.Geometry, float, float]]:
    """``part`` cut into polygons each within about :data:`ZONE_PIECE_M` of route along it,
    each with its extent (:func:`_extent`): ``part`` ∩ the route's stretch [a - d, b + d]
    widened by ``reach`` (farther than any point of the corridor; flat ends), for consecutive
    [a, b] of that length (d = :data:`_CUT_OVERLAP_M`: overlapping stretches leave no gap at a
    gentle bend). Outside a sharper bend near a stretch's end, the flat ends of consecutive
    stretches leave a wedge of ``part`` that neither holds: each such wedge is a piece of its
    own. The pieces must cover ``part`` (checked: else ``part`` stays whole), so every place
    of it is in a zone; they may overlap, which only repeats a place.

    Why: a long strip of kerb inside the corridor (sidewalk slivers joined at a walking area)
    would be one zone the bus has to clear whole before anyone could reach any of it (line 300
    of Bad Hersfeld stood for good before 256 m of sidewalk along a bending street, kept whole
    for three wedges of 0.1 m² together)."""
    first, last = _extent(part, route_line)
    if last - first <= ZONE_PIECE_M + _PIECE_TOL_M:
        return [(part, first, last)]
    count = math.ceil((last - first) / ZONE_PIECE_M)
    edges = np.linspace(first, last, count + 1)
    cuts = []
    for a, b in pairwise(edges.tolist()):
        stretch = shapely.ops.substring(route_line, max(a - _CUT_OVERLAP_M, 0.0),
                                        min(b + _CUT_OVERLAP_M, route_line.length))
        cuts.extend(shapely.get_parts(shapely.intersection(
            part, stretch.buffer(reach, cap_style="flat"))))
    cuts = [c for c in cuts if c.area > 0.0]
    wedges = shapely.difference(part, shapely.union_all(cuts))
    if wedges.area > _CUT_COVER_M2:
        cuts.extend(w for w in shapely.get_parts(wedges) if w.area > 0.0)
        if shapely.difference(part, shapely.union_all(cuts)).area > _CUT_COVER_M2:
            return [(part, first, last)]
    return [(cut, *_extent(cut, route_line)) for cut in cuts]


def _lit_crossings(roadmap: RoadMap, pieces: Sequence[shapely.Geometry], beyond: Region,
                   radius_m: float, kind: RegionKind) -> tuple[LitCrossing, ...]:
    """The signalised crossings whose own ground (RoadMap.own_grounds) some of the zones'
    ``pieces`` meet; ``beyond``: the ground beyond the tracked window; ``radius_m``: the
    pedestrians' body radius (how far a walker on a crossing may lie outside its area)."""
    lit = []
    reach = on_crossing_reach_m(radius_m)
    for crossing in roadmap.crossings:
        own = roadmap.own_grounds.get(crossing.id)
        if own is None:
            continue
        if not any(_meets(piece, own) for piece in pieces):
            continue
        near = kind.outer(crossing.area.buffer(reach + AREA_TOL_M, join_style="mitre"))
        lit.append(LitCrossing(crossing.id, roadmap.crossing_lights(crossing), own, near,
                               kind.inner(crossing.area.buffer(reach, join_style="mitre")),
                               not beyond.intersects(near)))
    return tuple(lit)


def _meets(piece: shapely.Geometry, ground: shapely.Geometry) -> bool:
    """Whether ``piece`` and ``ground`` share some area."""
    return shapely.intersection(piece, ground).area > 0.0


def _stop_lines(roadmap: RoadMap, route_edges: Sequence[str],
                route_line: shapely.LineString) -> tuple[StopLine, ...]:
    """The signalised stop lines of a route: the end of each lane of it whose connection
    into the next edge a traffic light controls (RoadMap.link_signals), along ``route_line``."""
    lanes = [lane for lane in roadmap.route_lanes(route_edges) if not lane.id.startswith(":")]
    lines = [StopLine(float(route_line.project(shapely.Point(a.shape[-1]))),
                      roadmap.link_signals[(a.id, b.id)])
             for a, b in pairwise(lanes) if (a.id, b.id) in roadmap.link_signals]
    return tuple(sorted(lines, key=lambda line: line.at_m))


def _with_sweep(corridor: shapely.Geometry, sweep: shapely.Geometry,
                walkable: shapely.Geometry) -> shapely.Geometry:
    """The ground the body (widened by a pedestrian's radius) sweeps: the ``corridor`` around
    the centre line, joined with the body's ``sweep`` where that reaches walkable ground the
    corridor misses (on a corner: the rear swinging out, the side cutting in). On a straight
    route the sweep adds none (beyond rounding, 1e-9 m) and the corridor stays as it was."""
    beyond = shapely.difference(shapely.intersection(sweep, walkable), corridor.buffer(1e-9))
    return corridor if beyond.area <= 0.0 else shapely.union(corridor, sweep)


def _from_start(region: shapely.Geometry, route_line: shapely.LineString) -> shapely.Geometry:
    """``region`` without the ground behind the route's start (across its first segment): a
    bus placed less than its length into its first lane sticks out there, where the scenario
    puts it, not where the controller drives it (as the corridor's flat end had it)."""
    points = shapely.get_coordinates(route_line)  # (n, 2)
    start, ahead = points[0], points[1] - points[0]
    ahead = ahead / math.hypot(float(ahead[0]), float(ahead[1]))
    far = route_line.length + region.length + 1.0
    left = np.array([-ahead[1], ahead[0]]) * far
    behind = shapely.Polygon([start + left, start - left, start - left - far * ahead,
                              start + left - far * ahead])
    return shapely.difference(region, behind)


def _touched(sweep: Sequence[SweepPiece], piece: shapely.Geometry, start: float, end: float,
             length: float) -> list[tuple[float, float, tuple[SweepPiece, ...]]]:
    """``piece``'s extents along the route, each with the pieces of the sweep that meet it
    there: one per stretch along which the body touches it (a route that passes the same
    ground twice gives two zones of that ground, each to clear on its own pass, and not one
    to clear over the whole way between; :func:`~sse_cosim.control.swept.touch_intervals`).
    With one stretch, the projections of its vertices (``start``, ``end``) widened to every
    front station at which the sweep touches it (a corner's body reaches ground that does not
    project where the front is); within 1e-9 m the projections stand, so a straight route
    keeps the same numbers."""
    meeting = _meeting(sweep, piece)
    intervals = touch_intervals(meeting, piece, length)
    if len(intervals) > 1:
        return [(first, last, tuple(p for p in meeting
                                    if p.end_m >= first and p.start_m <= last + length))
                for first, last in intervals]
    first, last = intervals[0] if intervals else (start, end)
    return [((start if first >= start - 1e-9 else first), (end if last <= end + 1e-9 else last),
             meeting)]


def _widened(line: shapely.LineString, half_width: float) -> shapely.Geometry:
    """``line`` swept by a disc of radius ``half_width``, with flat ends: its bends mitred, so
    that the polygon holds every round join it stands for, and widened by GEOS's shortcuts'
    margin (:data:`~sse_cosim.regions.polygon.OFFSET_MARGIN`: a route's bends of less than a
    milliradian get no join)."""
    return line.buffer(half_width * (1.0 + OFFSET_MARGIN), cap_style="flat", join_style="mitre")


def _boundary_points(polygon: shapely.Geometry) -> np.ndarray:
    """Vertices of a polygon's exterior, shape (k, 2)."""
    return np.asarray(shapely.get_coordinates(polygon.convex_hull.exterior))

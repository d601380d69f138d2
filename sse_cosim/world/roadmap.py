"""The road's geometry as plain shapely/numpy data, read once from the ``.net.xml``.

Pure: no SUMO process is needed, so the controller and the sensor models can use it on their
own. Coordinates are SUMO network metres (x east, y north); the network keeps its source
coordinates (no offset), so the paper's crossing node C is at (200, 0).

Lane kinds follow the cross-section of ``sumo_net/``: a *sidewalk* admits pedestrians and no
road vehicles (pedestrians only on the paper's road; a footpath shared with bicycles counts
too), a *parking strip* admits parked vehicles only (vClass ``custom1``), a *driving lane*
admits road vehicles (passenger cars, buses, ...) and no pedestrians. A network may hold any
number of crossings, none included; the road map holds them all.

*Walkable ground* (:attr:`RoadMap.walkable`), where the estimator assumes every pedestrian's
centre is: the sidewalks, walking areas and crossings, and the patches where SUMO's lone
walkers were measured to leave them (``ground_patches``, :mod:`sse_cosim.world.walker_jitter`;
the world fills them before a run, :meth:`RoadMap.with_ground_patches`, and checks every step
that each pedestrian is on it), with the junctions' ground grown by the scenario's
``estimator.junction_ground_margin_m`` (a crowd pushes walkers off it).
"""

from __future__ import annotations

import functools
import math
import os
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from itertools import pairwise
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import shapely
import sumolib

from sse_cosim.errors import UserError
from sse_cosim.regions.polygon import PolygonRegion
from sse_cosim.world.extent import SceneExtent, scene_extent
from sse_cosim.world.signals import CrossingLights, Phase, Program, Signal

if TYPE_CHECKING:
    from sse_cosim.scenario.model import Scenario

PARKED_VCLASS = "custom1"
"""vClass of parked vehicles; the parking strips admit it only."""
DRIVING_VCLASSES = ("passenger", "bus")
PROGRESS_ABOVE_BYTES = 5_000_000
"""A network file larger than this (a town) reports its reading on stderr."""
WALKABLE_TOL_M = 1e-9
"""How far (m) a pedestrian's centre may lie off :attr:`RoadMap.walkable` and still count as on
it: the rounding of SUMO's positions along the edge of a walking area (a walker on the town
cut's ``:1384946487_w1`` followed its edge 6.9e-14 m outside it), far above the rounding of a
coordinate of a network of kilometres (about 1e-13 m) and far below the tolerance to which the
recorder checks that every set holds its pedestrian (1e-7 m)."""
WALKABLE_COARSEN_M = 1e-9
"""The walkable ground holds the union of its parts and is kept within six times this (m) of
it, in fewer vertices (:meth:`~sse_cosim.regions.PolygonRegion.coarsen`): a measured patch is a
walker's positions dilated, and its union with the ground leaves corners that stray from a
straight edge by nanometres (the town cut's ground falls to about a third of its vertices),
which every region cut from the ground would keep, at the cost of every overlay and offset of
the step."""


OWN_GROUND_TOL_M = 1e-6
"""How far (m) beyond the other walkable ground a crossing's own ground begins: SUMO's positions
beside it round within far less (:attr:`RoadMap.own_grounds`)."""
MITRE_LIMIT = 5.0
"""The mitre limit of the other ground's offset in :attr:`RoadMap.own_grounds` (shapely's
default): no point of the offset lies farther than this many times the offset from the ground
it grows, so ground farther from a crossing than :func:`_reach` cannot cut it."""
IN_ORDER = frozenset({"static", "actuated", "delay_based"})
"""Signal program types whose phases run in order (unless a phase names its successor)."""

LaneLink = tuple[int, int, str]
"""A connection between the driving lanes of two consecutive edges: the index of its lane on
the first, on the second, and the internal lane between them ("" for none)."""


@dataclass(frozen=True)
class LaneGeometry:
    """One lane: its centreline ``shape`` (k, 2), ``width`` and ``length`` (m), and its speed
    limit (m/s)."""

    id: str
    edge_id: str
    index: int
    shape: np.ndarray
    width: float
    length: float
    speed_mps: float

    def polygon(self) -> shapely.Polygon:
        """The lane's area: the centreline widened by half the width to each side."""
        return lane_area(self.shape, self.width)


@dataclass(frozen=True)
class LaneChange:
    """A change of lanes a vehicle makes on edge ``edge_id``: from lane index ``from_index``,
    on which it enters the edge, to ``to_index``, by which it leaves it, once its body is
    on the edge (:meth:`RoadMap.route_plan`). ``detours``: for each lane it may be on
    meanwhile but the last, the route's lanes up to and including that lane of the edge."""

    edge_id: str
    from_index: int
    to_index: int
    detours: tuple[tuple[LaneGeometry, ...], ...]


@dataclass(frozen=True)
class Crossing:
    """One pedestrian crossing: its SUMO edge ``id``, the junction ``node`` it lies in, its
    ``area`` (the crossing lane widened to its width) and the ``signals`` of the links that let
    walkers onto it (none: no pedestrian light)."""

    id: str
    node: str
    area: shapely.Polygon
    signals: tuple[Signal, ...] = ()


@dataclass(frozen=True, eq=False)
class RoadMap:
    """The road: crossings, sidewalks, lanes and edge lengths (see module docstring).

    ``crossings`` holds every crossing of the network, ordered by id;
    ``sidewalks`` is the union of the sidewalk lanes and the walking areas; ``driving_lanes``
    holds the lanes of normal edges that road vehicles use, ``parking_lanes`` the parking
    strips, ``sidewalk_lanes`` the sidewalks, ``internal_lanes`` the vehicle lanes inside
    junctions (ids start with ':'). ``edge_lengths`` covers the normal edges;
    ``lane_links[(from_edge, to_edge)]`` lists the connections between the driving lanes of
    two edges (:data:`LaneLink`: from which lane index to which, and the internal lane between).
    A road map built for a
    scene (:func:`load_scene_roadmap`) holds the edges near it only
    (:mod:`sse_cosim.world.extent`), and ``net`` the network it was read from.
    ``ground_patches[node]`` is the ground SUMO's lone walkers were measured to need beyond
    the plain :attr:`ground` at a junction (none measured: empty); ``walking_areas`` the union
    of the walking areas; ``junction_margin_m`` how far the junctions' ground (walking areas,
    crossings, patches) is grown in :attr:`walkable`.
    """

    net_path: Path
    crossings: tuple[Crossing, ...]
    sidewalks: shapely.Polygon | shapely.MultiPolygon
    driving_lanes: dict[str, LaneGeometry]
    parking_lanes: dict[str, LaneGeometry]
    sidewalk_lanes: dict[str, LaneGeometry]
    internal_lanes: dict[str, LaneGeometry]
    edge_lengths: dict[str, float]
    lane_links: dict[tuple[str, str], tuple[LaneLink, ...]] = field(default_factory=dict)
    link_signals: dict[tuple[str, str], Signal] = field(default_factory=dict)
    programs: dict[tuple[str, str], Program] = field(default_factory=dict)
    # an internal lane -> the internal lane it leads into (a passage split at an internal
    # junction: a left turn waiting inside the junction)
    internal_next: dict[str, str] = field(default_factory=dict)
    ground_patches: dict[str, shapely.Geometry] = field(default_factory=dict)
    walking_areas: shapely.Geometry = field(default_factory=shapely.Polygon)
    junction_margin_m: float = 0.0
    stray_m: float = 0.0  # how far a walker off a signalised crossing may reach into its area
    net: sumolib.net.Net | None = field(default=None, compare=False, repr=False)

    @functools.cached_property
    def ground(self) -> shapely.Geometry:
        """The sidewalks, walking areas and crossings, as the network draws them."""
        return shapely.union(self.sidewalks, self.crossing_area)

    @functools.cached_property
    def walkable(self) -> shapely.Geometry:
        """The walkable ground every consumer uses: :attr:`ground` and the measured patches,
        so it holds every position SUMO's lone walkers were measured at, and the junctions'
        ground grown by :attr:`junction_margin_m` (a mitred offset, which holds the disc's:
        :meth:`~sse_cosim.regions.PolygonRegion.dilate`), coarsened by
        :data:`WALKABLE_COARSEN_M`."""
        patches = [self.ground_patches[node] for node in sorted(self.ground_patches)]
        parts = [self.ground, *patches]
        if self.junction_margin_m > 0:
            junctions = shapely.union_all([self.walking_areas, self.crossing_area, *patches])
            parts.append(PolygonRegion(junctions).dilate(self.junction_margin_m).shape)
        if len(parts) == 1:
            return self.ground
        return PolygonRegion(shapely.union_all(parts)).coarsen(WALKABLE_COARSEN_M).shape

    def with_ground_patches(self, patches: dict[str, shapely.Geometry],
                            junction_margin_m: float = 0.0, stray_m: float = 0.0) -> RoadMap:
        """This road map with ``patches`` (junction -> ground) as its ``ground_patches``, the
        junctions' ground grown by ``junction_margin_m`` in :attr:`walkable`, and ``stray_m``
        (the position jitter) as how far a walker beside a signalised crossing may reach into
        its area (:attr:`own_grounds`)."""
        return replace(self, ground_patches=dict(patches), junction_margin_m=junction_margin_m,
                       stray_m=stray_m)

    @functools.cached_property
    def crossing_area(self) -> shapely.Geometry:
        """The union of every crossing's area (empty without crossings)."""
        return shapely.union_all([c.area for c in self.crossings])

    @functools.cached_property
    def lights(self) -> tuple[str, ...]:
        """The traffic lights of its signalised driving links and crossings, sorted."""
        return tuple(sorted({light for light, _ in self.link_signals.values()}
                            | {light for c in self.crossings for light, _ in c.signals}))

    def crossing_lights(self, crossing: Crossing) -> CrossingLights:
        """``crossing``'s lights: its signals and their programs (none for a zebra)."""
        lights = {light for light, _ in crossing.signals}
        return CrossingLights(crossing.signals, {key: program for key, program
                                                 in self.programs.items() if key[0] in lights})

    @functools.cached_property
    def own_grounds(self) -> dict[str, shapely.Geometry]:
        """Each signalised crossing's own ground, by id: its area less every other walkable
        ground (sidewalks, walking areas, the other crossings, the measured patches) grown by
        :attr:`junction_margin_m`, :attr:`stray_m` and :data:`OWN_GROUND_TOL_M` -- where a
        walker's centre can only be while it walks on that crossing (the ``pedestrian_lights``
        check holds SUMO to it: SUMO's walkers on a walking area reach into a crossing's area,
        0.09 m on tests/networks/two_lanes/, within the position jitter). Each crossing is
        cut by the pieces of ground near it only (:attr:`_ground_pieces`), not the whole town's
        (36 s a crossing on the whole converted town before)."""
        grow = self.junction_margin_m + self.stray_m + OWN_GROUND_TOL_M
        pieces, tree, owners = self._ground_pieces
        grounds = {}
        for k, crossing in enumerate(self.crossings):
            if not crossing.signals:
                continue
            near = tree.query(crossing.area, predicate="dwithin", distance=_reach(grow))
            others = shapely.union_all([pieces[i] for i in sorted(near) if owners[i] != k])
            grounds[crossing.id] = shapely.difference(
                crossing.area, others.buffer(grow, join_style="mitre", mitre_limit=MITRE_LIMIT))
        return grounds

    @functools.cached_property
    def _ground_pieces(self) -> tuple[list[shapely.Geometry], shapely.STRtree, list[int]]:
        """The walkable ground in pieces (each part of the sidewalks, each crossing's area,
        each measured patch's parts), their tree, and each piece's crossing (its index in
        :attr:`crossings`; -1 for the others)."""
        patches = [self.ground_patches[node] for node in sorted(self.ground_patches)]
        pieces = [*shapely.get_parts(self.sidewalks), *(c.area for c in self.crossings),
                  *(part for patch in patches for part in shapely.get_parts(patch))]
        sidewalk_parts = int(shapely.get_num_geometries(self.sidewalks))
        owners = [-1] * sidewalk_parts + list(range(len(self.crossings)))
        owners += [-1] * (len(pieces) - len(owners))
        return pieces, shapely.STRtree(pieces), owners

    @functools.cached_property
    def crossing_ids(self) -> frozenset[str]:
        """The SUMO edge ids of the crossings."""
        return frozenset(c.id for c in self.crossings)

    @functools.cached_property
    def _crossing_tree(self) -> shapely.STRtree:
        return shapely.STRtree([c.area for c in self.crossings])

    def crossings_meeting(self, body: shapely.Geometry) -> tuple[str, ...]:
        """The ids of the crossings whose areas meet ``body`` (a vehicle's footprint), sorted."""
        hits = self._crossing_tree.query(body, predicate="intersects")
        return tuple(sorted(self.crossings[int(k)].id for k in hits))

    def lane(self, lane_id: str) -> LaneGeometry:
        """Any lane known to the map, by id; KeyError when there is none."""
        for group in (self.driving_lanes, self.parking_lanes, self.sidewalk_lanes,
                      self.internal_lanes):
            if lane_id in group:
                return group[lane_id]
        raise KeyError(lane_id)

    def lane_polygon(self, lane_id: str) -> shapely.Polygon:
        """The area of lane ``lane_id`` (driving lane, parking strip, sidewalk or internal)."""
        return self.lane(lane_id).polygon()

    def route_length(self, edge_ids: Sequence[str]) -> float:
        """Length (m) of a vehicle route in SUMO's distance: the lengths of the lanes it
        drives (:meth:`route_lanes`)."""
        return sum(lane.length for lane in self.route_lanes(edge_ids))

    def route_line(self, edge_ids: Sequence[str]) -> shapely.LineString:
        """The centre line a vehicle drives along a route (:meth:`route_lanes`), from the
        start of the first edge, as drawn (the lanes' shapes: its length is ``route_length``
        only where each lane's shape is as long as the lane; docs/controller.md, "SUMO's
        distance")."""
        coords = np.concatenate([lane.shape for lane in self.route_lanes(edge_ids)])
        keep = np.r_[True, np.any(np.abs(np.diff(coords, axis=0)) > 1e-9, axis=1)]
        return shapely.LineString(coords[keep])

    def route_lanes(self, edge_ids: Sequence[str]) -> list[LaneGeometry]:
        """The lanes a vehicle drives along a route, in order (:meth:`route_plan`): on each
        edge the lane it leaves by, and the junction passages between them."""
        return self.route_plan(edge_ids)[0]

    def route_changes(self, edge_ids: Sequence[str]) -> tuple[LaneChange, ...]:
        """The lane changes a vehicle makes along a route (:meth:`route_plan`), in order."""
        return self.route_plan(edge_ids)[1]

    def route_plan(self, edge_ids: Sequence[str]
                   ) -> tuple[list[LaneGeometry], tuple[LaneChange, ...]]:
        """The lanes a vehicle drives along a route and the lane changes it makes
        (:func:`lane_plan`): where the route can be driven lane to lane, on each edge the
        rightmost driving lane that leads on (where SUMO keeps a vehicle on an empty road)
        and no change; where it cannot, on an edge entered on a lane that does not lead on,
        a change to the nearest one that does, made on that edge. The lanes are those left
        by (an edge of a change: its lane after it), with the junction passages between."""
        for edge_id in edge_ids:
            if not self._edge_lanes.get(edge_id):
                raise self._missing(edge_id, "normal edge" if edge_id in self.edge_lengths
                                    else "edge", "a driving lane")
        def indices(edge_id: str) -> list[int]:
            return [g.index for g in self._edge_lanes[edge_id]]

        try:
            plan = lane_plan(edge_ids, indices, self.lane_links)
        except NoLanePlan as stuck:
            raise UserError(str(self.net_path), f"route {' '.join(edge_ids)!r}",
                            f"cannot be driven: no lane of edge {stuck.edges[0]!r} that the "
                            f"vehicle reaches leads onto edge {stuck.edges[1]!r}, even with "
                            "lane changes (to neighbouring driving lanes, on one edge)",
                            "route it over edges that connect, or add the connection to the "
                            "network (docs/own_network.md)") from None
        lanes: list[LaneGeometry] = []
        changes = []
        for edge_id, (entry, leave, via) in zip(edge_ids, plan, strict=True):
            if entry != leave:
                step = 1 if leave > entry else -1
                changes.append(LaneChange(edge_id, entry, leave, tuple(
                    (*lanes, self._edge_lane(edge_id, index))
                    for index in range(entry, leave, step))))
            lanes.append(self._edge_lane(edge_id, leave))
            lanes.extend(self._internal(lane) for lane in self._passage(via))
        return lanes, tuple(changes)

    def _edge_lane(self, edge_id: str, index: int) -> LaneGeometry:
        """Driving lane ``index`` of normal edge ``edge_id``."""
        return next(g for g in self._edge_lanes[edge_id] if g.index == index)

    @functools.cached_property
    def _edge_lanes(self) -> dict[str, list[LaneGeometry]]:
        """Each normal edge's driving lanes, rightmost first (made once)."""
        lanes: dict[str, list[LaneGeometry]] = {}
        for lane in sorted(self.driving_lanes.values(), key=lambda g: g.index):
            lanes.setdefault(lane.edge_id, []).append(lane)
        return lanes

    def _passage(self, via: str) -> list[str]:
        """The internal driving lanes from ``via`` on, in order: it, then each one it leads
        into (none for "": a connection without a passage)."""
        passage: list[str] = []
        while via and via not in passage:
            passage.append(via)
            via = self.internal_next.get(via, "")
        return passage

    def _internal(self, lane_id: str) -> LaneGeometry:
        """The internal driving lane ``lane_id`` (a junction passage of a route)."""
        if lane_id not in self.internal_lanes:
            raise self._missing(lane_id, "junction lane", "a driving lane's passage")
        return self.internal_lanes[lane_id]

    def _missing(self, item: str, kind: str, what: str) -> UserError:
        """The one-line refusal of a lookup the network cannot answer: ``item`` (a ``kind``)
        is no ``what`` here (a road pedestrians walk on has no driving lane)."""
        return UserError(str(self.net_path), f"{kind} {item!r}", f"is not {what} of this "
                         "network (buses and cars drive on lanes that no pedestrian walks on)",
                         "give the roads sidewalks (netconvert --sidewalks.guess, "
                         "docs/own_network.md) and route vehicles over driving lanes")


def require_pedestrian_ground(roadmap: RoadMap, source: str, field: str) -> None:
    """A UserError naming ``source`` and ``field`` (the network's) unless the network has
    sidewalks and a crossing, which a scenario's pedestrian needs."""
    missing = [what for what, found in (("sidewalk", roadmap.sidewalk_lanes),
                                        ("crossing", roadmap.crossings)) if not found]
    if missing:
        raise UserError(source, field, f"the network has no {' and no '.join(missing)}, which "
                        "the scenario's pedestrians need",
                        "convert it with netconvert --sidewalks.guess --crossings.guess "
                        "(docs/own_network.md), or set pedestrians.<id>.present = false")


def lane_area(shape: np.ndarray, width: float) -> shapely.Polygon:
    """A centreline widened by ``width / 2`` to each side, cut square at both ends."""
    line = shapely.LineString(shape)
    return line.buffer(width / 2.0, cap_style="flat", join_style="mitre")


@functools.lru_cache(maxsize=8)
def _load_cached(path: str, mtime_ns: int) -> RoadMap:
    del mtime_ns  # part of the cache key only
    return _read(Path(path))


def load_roadmap(net_path: str | os.PathLike[str]) -> RoadMap:
    """The RoadMap of the ``.net.xml`` at ``net_path`` (read once per path and version)."""
    path = Path(net_path).resolve()
    if not path.is_file():
        raise UserError(str(path), "", "network file not found",
                        "build it with sse_cosim.world.network.build_network")
    return _load_cached(str(path), path.stat().st_mtime_ns)


def _geometry(lane: sumolib.net.lane.Lane) -> LaneGeometry:
    return LaneGeometry(
        id=lane.getID(),
        edge_id=lane.getEdge().getID(),
        index=lane.getIndex(),
        shape=np.asarray(lane.getShape(), dtype=float)[:, :2],
        width=float(lane.getWidth()),
        length=float(lane.getLength()),
        speed_mps=float(lane.getSpeed()),
    )


def is_sidewalk(lane: sumolib.net.lane.Lane) -> bool:
    """Pedestrians and no road vehicles (a footpath shared with bicycles counts)."""
    return lane.allows("pedestrian") and not any(lane.allows(c) for c in DRIVING_VCLASSES)


def is_parking_strip(lane: sumolib.net.lane.Lane) -> bool:
    """Parked vehicles only."""
    return lane.getPermissions() == {PARKED_VCLASS}


def is_driving_lane(lane: sumolib.net.lane.Lane) -> bool:
    """Road vehicles, no pedestrians."""
    return not lane.allows("pedestrian") and any(lane.allows(c) for c in DRIVING_VCLASSES)


def load_scene_roadmap(net_path: str | os.PathLike[str], scenario: Scenario) -> RoadMap:
    """The RoadMap of the part of the ``.net.xml`` at ``net_path`` that ``scenario``'s scene
    can use (:mod:`sse_cosim.world.extent`; the whole network with route files), holding the
    network read (``net``) for the demand planner. Read anew on every call; on a large
    network (a town) each stage says on stderr what it did and how long it took."""
    path = Path(net_path).resolve()
    if not path.is_file():
        raise UserError(str(path), "", "network file not found",
                        "build it with sse_cosim.world.network.build_network")
    progress = _Progress(path)
    net = _read_net(path, progress)
    return _build(path, net, scene_extent(scenario, net), progress)


class _Progress:
    """Progress lines on stderr while a large network loads (quiet for small ones)."""

    def __init__(self, path: Path) -> None:
        self.size = path.stat().st_size
        self.on = self.size > PROGRESS_ABOVE_BYTES
        self.start = time.perf_counter()

    def say(self, text: str) -> None:
        if self.on:
            print(f"{text} ({time.perf_counter() - self.start:.1f} s)", file=sys.stderr,
                  flush=True)


def _read(path: Path) -> RoadMap:
    progress = _Progress(path)
    return _build(path, _read_net(path, progress), None, progress)


def _read_net(path: Path, progress: _Progress) -> sumolib.net.Net:
    if progress.on:
        print(f"reading network {path.name} ({progress.size / 1e6:.0f} MB)...",
              file=sys.stderr, flush=True)
    try:
        net = sumolib.net.readNet(str(path), withInternal=True, withPedestrianConnections=True,
                                   withPrograms=True)
    except Exception as exc:  # sumolib raises plain exceptions on broken XML
        raise UserError(str(path), "", f"cannot read the network ({exc})",
                        "rebuild it from the sources (delete sumo_net/build/)") from None
    progress.say(f"network: {len(net.getEdges(withInternal=False))} edges read")
    return net


def _build(path: Path, net: sumolib.net.Net, extent: SceneExtent | None,
           progress: _Progress) -> RoadMap:
    """The RoadMap of ``net``'s edges in ``extent`` (all of them without one)."""
    driving: dict[str, LaneGeometry] = {}
    parking: dict[str, LaneGeometry] = {}
    sidewalk: dict[str, LaneGeometry] = {}
    internal: dict[str, LaneGeometry] = {}
    internal_next: dict[str, str] = {}
    edge_lengths: dict[str, float] = {}
    crossings: list[sumolib.net.edge.Edge] = []
    walking_areas: list[shapely.Polygon] = []
    entries: dict[str, list[Signal]] = {}  # crossing -> the signals of the links onto it
    for edge in net.getEdges(withInternal=True):
        if extent is not None and not extent.holds(edge):
            continue
        function = edge.getFunction()
        if function == "crossing":
            crossings.append(edge)
            continue
        if function == "walkingarea":
            for conn in edge.getLane(0).getOutgoing():
                if conn.getTLSID() and conn.getToLane().getEdge().getFunction() == "crossing":
                    entries.setdefault(conn.getToLane().getEdge().getID(), []).append(
                        (conn.getTLSID(), int(conn.getTLLinkIndex())))
            ring = np.asarray(edge.getLane(0).getShape(), dtype=float)[:, :2]
            if len(ring) >= 3:
                poly = shapely.make_valid(shapely.Polygon(ring))
                if poly.area > 1e-6:
                    walking_areas.append(poly)
            continue
        if function == "internal":
            for lane in edge.getLanes():
                if is_driving_lane(lane):
                    internal[lane.getID()] = _geometry(lane)
                    internal_next.update((lane.getID(), c.getViaLaneID())
                                         for c in lane.getOutgoing() if c.getViaLaneID())
            continue
        edge_lengths[edge.getID()] = float(edge.getLength())
        for lane in edge.getLanes():
            if is_sidewalk(lane):
                sidewalk[lane.getID()] = _geometry(lane)
            elif is_parking_strip(lane):
                parking[lane.getID()] = _geometry(lane)
            elif is_driving_lane(lane):
                driving[lane.getID()] = _geometry(lane)
    sidewalk_union = shapely.union_all(
        [g.polygon() for g in sidewalk.values()] + walking_areas)
    walking_area_union = shapely.union_all(walking_areas)
    progress.say(f"road map: {len(edge_lengths)} edges "
                 f"{'in all' if extent is None else 'near the scene'}")
    return RoadMap(
        net_path=path,
        crossings=tuple(sorted((_crossing(edge, entries.get(edge.getID(), ()))
                                for edge in crossings), key=lambda c: c.id)),
        sidewalks=sidewalk_union,
        driving_lanes=driving,
        parking_lanes=parking,
        sidewalk_lanes=sidewalk,
        internal_lanes=internal,
        edge_lengths=edge_lengths,
        lane_links=_lane_links(net, extent),
        link_signals=_link_signals(net, extent),
        programs=_programs(net),
        internal_next=internal_next,
        walking_areas=walking_area_union,
        net=None if extent is None else net,
    )


def _crossing(edge: sumolib.net.edge.Edge, signals: Sequence[Signal]) -> Crossing:
    """A crossing edge as a :class:`Crossing`, with the ``signals`` of the links onto it."""
    lane = edge.getLane(0)
    area = lane_area(np.asarray(lane.getShape(), dtype=float)[:, :2], float(lane.getWidth()))
    return Crossing(edge.getID(), edge.getFromNode().getID(), area, tuple(sorted(signals)))


def _link_signals(net: sumolib.net.Net, extent: SceneExtent | None = None
                  ) -> dict[tuple[str, str], Signal]:
    """The traffic light link of each signalised connection between the driving lanes of
    two normal edges (of ``extent``), by (from lane, to lane)."""
    result: dict[tuple[str, str], Signal] = {}
    for edge in net.getEdges(withInternal=False):
        if extent is not None and not extent.holds(edge):
            continue
        for lane in edge.getLanes():
            for conn in lane.getOutgoing():
                if conn.getTLSID() and is_driving_lane(lane):
                    result[(lane.getID(), conn.getToLane().getID())] = (
                        conn.getTLSID(), int(conn.getTLLinkIndex()))
    return result


def _programs(net: sumolib.net.Net) -> dict[tuple[str, str], Program]:
    """Every signal program the network defines, by (traffic light, program id): each
    phase's state and shortest duration (``minDur`` where the program is actuated); the
    phases of a static, actuated or delay-based program that names no successor phase run in
    order (:class:`~sse_cosim.world.signals.Program`)."""
    result: dict[tuple[str, str], Program] = {}
    for light in net.getTrafficLights():
        for program_id, program in light.getPrograms().items():
            phases = program.getPhases()
            actuated = program.getType() != "static"
            result[(light.getID(), program_id)] = Program(
                program_id,
                tuple(Phase(p.state, float(p.minDur if actuated and p.minDur >= 0
                                           else p.duration)) for p in phases),
                in_order=program.getType() in IN_ORDER and not any(p.next for p in phases),
                static=program.getType() == "static", offset_s=float(program.getOffset()))
    return result


def _lane_links(net: sumolib.net.Net, extent: SceneExtent | None = None
                ) -> dict[tuple[str, str], tuple[LaneLink, ...]]:
    """For consecutive normal edges (of ``extent``): the connections between their driving
    lanes, sorted."""
    result: dict[tuple[str, str], tuple[LaneLink, ...]] = {}
    for edge in net.getEdges(withInternal=False):
        if extent is not None and not extent.holds(edge):
            continue
        for to_edge, conns in edge.getOutgoing().items():
            if to_edge.getFunction():  # walking areas and crossings
                continue
            links = sorted((c.getFromLane().getIndex(), c.getToLane().getIndex(),
                            c.getViaLaneID() or "") for c in conns
                           if is_driving_lane(c.getFromLane()) and is_driving_lane(c.getToLane()))
            if links:
                result[(edge.getID(), to_edge.getID())] = tuple(links)
    return result


def _reach(grow: float) -> float:
    """How far (m) from a crossing's area the ground grown by ``grow`` (m) with mitred corners
    can cut it: :data:`MITRE_LIMIT` times the offset, and a metre for rounding."""
    return MITRE_LIMIT * grow + 1.0


def lane_chain(edges: Sequence[str], lanes: Callable[[str], Sequence[int]],
               links: Mapping[tuple[str, str], Sequence[LaneLink]]
               ) -> list[tuple[int, str]] | None:
    """Per edge of a route its lane index and the internal lane into the next edge ("" for
    the last edge, or a connection without one): on each edge the rightmost lane (the least
    index of ``lanes(edge)``) from which the rest of the route can be driven lane to lane
    over ``links``; None if none can (:func:`lane_plan` then plans lane changes). Pure: no
    network here."""
    able = _able_lanes(edges, lanes, links)
    if not able[0]:
        return None
    chain, lane = [], min(able[0])
    for k, (a, b) in enumerate(pairwise(edges)):
        _, lane_b, via = min(link for link in links[(a, b)]
                             if link[0] == lane and link[1] in able[k + 1])
        chain.append((lane, via))
        lane = lane_b
    return [*chain, (lane, "")]


class NoLanePlan(ValueError):
    """No lane of the first of ``edges`` (a pair of consecutive route edges) that a vehicle
    reaches leads onto the second, even with lane changes (:func:`lane_plan`)."""

    def __init__(self, edges: tuple[str, str]) -> None:
        super().__init__(f"no lane of {edges[0]!r} leads onto {edges[1]!r}")
        self.edges = edges


def lane_plan(edges: Sequence[str], lanes: Callable[[str], Sequence[int]],
              links: Mapping[tuple[str, str], Sequence[LaneLink]]
              ) -> list[tuple[int, int, str]]:
    """Per edge of a route the lane index it is entered on, the one it is left by, and the
    internal lane into the next edge ("" for the last edge, or a connection without one).

    Where :func:`lane_chain` finds a chain, that one, with no change. Otherwise the plan with
    the fewest lane changes, each to a neighbouring driving lane (``lanes``: an edge's driving
    lanes; a change crosses none that is not one) on the edge it is needed on; of plans as
    good, the one on the rightmost lanes, edge by edge. The first edge is left by the lane it
    is entered on (the departure lane). Raises :class:`NoLanePlan` naming the last pair of
    edges where no lane reached leads on. Pure: no network here."""
    chain = lane_chain(edges, lanes, links)
    if chain is not None:
        return [(index, index, via) for index, via in chain]
    last = len(edges) - 1
    # per edge, per lane it is entered on: (changes from there on, lane it is left by, next
    # edge's entry lane, internal lane into it), from the last edge back
    best: list[dict[int, tuple[float, int, int, str]]] = [{}] * len(edges)
    best[last] = {entry: (0.0, entry, entry, "") for entry in lanes(edges[last])}
    for k in range(last - 1, -1, -1):
        best[k] = {}
        for entry in lanes(edges[k]):
            options = [(abs(leave - entry) + best[k + 1][target][0], leave, target, via)
                       for leave in ([entry] if k == 0
                                     else sorted(_neighbours(lanes(edges[k]), entry)))
                       for link_from, target, via in links.get((edges[k], edges[k + 1]), ())
                       if link_from == leave and target in best[k + 1]]
            best[k][entry] = min(options, default=(math.inf, entry, entry, ""))
    broken = [k for k in range(last) if not any(math.isfinite(option[0])
                                                for option in best[k].values())]
    if broken:  # the last edge whose lanes lead onto none that leads on from the next
        raise NoLanePlan((edges[broken[-1]], edges[broken[-1] + 1]))
    entry = min(best[0], key=lambda index: (best[0][index][0], index))
    plan = []
    for k in range(len(edges)):
        _, leave, target, via = best[k][entry]
        plan.append((entry, leave, via))
        entry = target
    return plan


def _neighbours(lanes: Sequence[int], index: int | None) -> set[int]:
    """The lanes of ``lanes`` (an edge's driving lanes' indices) reached from ``index`` by
    changes to neighbouring ones: the unbroken run of indices that holds it (none for
    None)."""
    if index is None or index not in lanes:
        return set()
    own, low, high = set(lanes), index, index
    while low - 1 in own:
        low -= 1
    while high + 1 in own:
        high += 1
    return set(range(low, high + 1))


def _able_lanes(edges: Sequence[str], lanes: Callable[[str], Sequence[int]],
                links: Mapping[tuple[str, str], Sequence[LaneLink]]) -> list[set[int]]:
    """Per edge the lanes from which the rest of the route can be driven lane to lane."""
    able = [set(lanes(edges[-1]))]
    for a, b in reversed(list(pairwise(edges))):
        able.insert(0, {i for i, j, _ in links.get((a, b), ()) if j in able[0]}
                    & set(lanes(a)))
    return able

"""The scenario's actors as SUMO demand: checks against the network, the pedestrian's plan, the
route file. Pure Python (sumolib); no SUMO process is needed.

Ids: every actor's SUMO id is its id in the scenario (``[automated.bus]`` is vehicle ``bus``,
``[pedestrians.p3]`` person ``p3``), and each has a type of the same id. Every type has
``speedDev="0"`` and ``sigma="0"`` (no random speed factors, no dawdling), so one seed gives one
run. The checks run per actor; an error names the field with the actor's id
(``pedestrians.p3.start_pos_m``).

Each pedestrian walks an explicit path: its start sidewalk, the walking area, a zebra, the
walking area on the far side, its end sidewalk; the zebra its ``crossing`` names, or else, of
the network's crossings, the one that makes the walk shortest. (Left to SUMO's router, a
pedestrian whose end lies far down the opposite sidewalk would rather cross at the dead end of
the road.)

Every pedestrian exists from t=0: the estimator assumes that an undetected pedestrian has been
somewhere on walkable ground since the start, so it may not appear later where sensors already
saw nobody. Its plan is a stop at its start position until its walk starts, then the walk,
timed so that it steps onto the zebra at its ``steps_onto_crossing_s`` within half a step:

* **Timing.** How long the walk from the start to the zebra takes is SUMO's own time, not a
  length divided by a speed: SUMO's walker crosses a walking area on its own path, which is
  shorter than the walking area's ``length`` attribute (2.64 m against 2.82 m on the paper
  road, several metres on a converted town's corners). A :data:`WalkTimer` (the world passes
  :class:`sse_cosim.world.walk_probe.ProbeTimer`: each pedestrian alone on its walk in a short
  SUMO session, before the run) gives the steps from the walk's start to the first step on
  the zebra's lane; the walk starts that long before ``steps_onto_crossing_s``, rounded to the
  nearest step. A time the walk cannot make is an error naming the earliest one.
* **Priority.** A pedestrian does not wait at the kerb for vehicles, also where the crossing
  is not prioritised (netconvert's ``--crossings.guess`` makes every crossing it adds one):
  its vType ignores every approaching vehicle (:func:`pedestrian_vtype`), so it steps out in
  front of the bus as the scenario says. The world checks during the run that it did
  (:class:`sse_cosim.world.sumo.SumoWorld`).

SUMO draws a waiting person beside the sidewalk, so :class:`PedestrianPlan` says where it
stands: where its walk will begin.

Every vehicle keeps its speed: a speed above the limit of a lane on its route is an error, as
SUMO would silently hold the vehicle to the limit.
"""

from __future__ import annotations

import difflib
import itertools
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING
from xml.sax.saxutils import quoteattr

import sumolib

from sse_cosim.errors import UserError
from sse_cosim.estimation.motion import acceleration_bound
from sse_cosim.files import write_text_atomic
from sse_cosim.scenario.model import (
    AutomatedVehicle,
    ParkedVehicle,
    Pedestrian,
    Scenario,
    Vehicle,
    present,
)
from sse_cosim.world.roadmap import (
    DRIVING_VCLASSES,
    PARKED_VCLASS,
    LaneGeometry,
    RoadMap,
    is_driving_lane,
    is_sidewalk,
)
from sse_cosim.world.signals import WALKERS_GO
from sse_cosim.world.walkgraph import WalkGraph

if TYPE_CHECKING:
    from sse_cosim.world.walk_probe import ProbeTimer

VEHICLE_VCLASS = "passenger"  # the class of the scenario's other moving vehicles
PARKED_DURATION_S = 1.0e7  # "for ever": a parked vehicle's stop outlasts any run
ROUTE_FILE_NAME = "scenario.rou.xml"
# SUMO's striping model splits a sidewalk into stripes this wide (its default; the run's
# configuration sets it, so that standing_point knows where a walk begins)
STRIPE_WIDTH_M = 0.64
_EPS = 1e-9  # tolerance of time comparisons in steps
NEAREST_EDGES = 5  # how many edge ids a mistyped one is answered with
# A pedestrian's vType ignores approaching vehicles whose speed is at most this (SUMO's
# jmIgnoreFoeSpeed, with jmIgnoreFoeProb 1): every road vehicle.
IGNORE_FOE_SPEED_MPS = 1000.0


@dataclass(frozen=True)
class PedestrianPlan:
    """When and where the pedestrian waits and walks.

    ``path`` lists the edges it walks (sidewalks, walking areas, the crossing), ``crossing``
    its zebra; ``distance_to_crossing_m`` the walk from its start to the zebra along the
    network's lengths; ``standing_xy`` its centre (network coordinates) while it waits at its
    start, which is where its walk begins; from t=0 until ``walk_start_s`` it stands there,
    then it walks, and SUMO's walker takes ``walk_to_crossing_s`` (whole steps) to step onto
    the zebra: at ``steps_on_s = walk_start_s + walk_to_crossing_s``, within half a step of
    ``crossing_time_s`` (the configured time).
    """

    path: tuple[str, ...]
    crossing: str
    distance_to_crossing_m: float
    standing_xy: tuple[float, float]
    walk_start_s: float
    walk_to_crossing_s: float
    crossing_time_s: float

    @property
    def steps_on_s(self) -> float:
        """When SUMO's walker steps onto the zebra (s): its walk's start plus its walk."""
        return round(self.walk_start_s + self.walk_to_crossing_s, 6)


@dataclass(frozen=True)
class WalkToCrossing:
    """A pedestrian's planned walk, for a :data:`WalkTimer`: ``path`` from ``start_pos_m`` on
    its first edge to ``end_pos_m`` on its last (``length_m`` long along the network), over
    ``crossing``, at ``speed_mps``, with a body of ``radius_m``."""

    path: tuple[str, ...]
    start_pos_m: float
    end_pos_m: float
    length_m: float
    crossing: str
    speed_mps: float
    radius_m: float


# How long each pedestrian's walk takes from its start to its first step on its crossing (s,
# whole steps of ``step_s``), by pedestrian id: SUMO's time (sse_cosim.world.walk_probe).
WalkTimer = Callable[[Mapping[str, WalkToCrossing], float], dict[str, float]]


@dataclass(frozen=True)
class ActorPlan:
    """Everything the route file needs beyond the scenario: each automated vehicle's
    departure lane and each present pedestrian's plan, by id."""

    automated_lanes: dict[str, LaneGeometry]
    pedestrians: dict[str, PedestrianPlan]


def plan_actors(scenario: Scenario, net_path: Path, roadmap: RoadMap, source: str,
                timer: WalkTimer | None = None) -> ActorPlan:
    """Check the actors against the network (UserError naming ``source`` and the field) and plan
    the automated vehicles' lanes and the pedestrians' walks, timed by ``timer`` (default: a
    :class:`~sse_cosim.world.walk_probe.ProbeTimer` of the network in a temporary folder,
    walking the speed ramp of the scenario's motion model if it bounds the acceleration: the
    safety campaign's feasibility is the run's)."""
    net = net_of(net_path, roadmap)  # read once
    lanes = {vid: _check_automated(net, roadmap, vid, av, source)
             for vid, av in present(scenario.automated).items()}
    for vid, parked in present(scenario.parked).items():
        _check_parked(net, vid, parked, source)
    for vid, vehicle in present(scenario.vehicles).items():
        _check_vehicle(net, vid, vehicle, source)
    dt = scenario.simulation.step_length_s
    pedestrians = present(scenario.pedestrians)
    walks, times = _timed_walks(scenario, net, net_path, source, timer)
    plans = {pid: _time_pedestrian(net, pid, pedestrians[pid], walk, times[pid], dt, source)
             for pid, walk in walks.items()}
    for pid, plan in plans.items():
        _check_light(pid, plan, roadmap, dt, source)
    return ActorPlan(automated_lanes=lanes, pedestrians=plans)


def walk_times(scenario: Scenario, net_path: Path, roadmap: RoadMap, source: str,
               timer: WalkTimer | None = None) -> dict[str, float]:
    """How long each pedestrian's walk takes from its start to its first step on its crossing
    (s, whole steps), as :func:`plan_actors` times it: the earliest ``steps_onto_crossing_s``
    it can make. UserError (naming ``source``) for a walk the network does not have."""
    net = net_of(net_path, roadmap)
    return _timed_walks(scenario, net, net_path, source, timer)[1]


def _timed_walks(scenario: Scenario, net: sumolib.net.Net, net_path: Path, source: str,
                 timer: WalkTimer | None) -> tuple[dict[str, WalkToCrossing], dict[str, float]]:
    """Every present pedestrian's walk to its crossing (checked to cross an automated
    vehicle's route) and its time by ``timer`` (default: the network's probe walker)."""
    dt = scenario.simulation.step_length_s
    pedestrians = present(scenario.pedestrians)
    if not pedestrians:
        return {}, {}
    graph = WalkGraph(net)  # built once, for every pedestrian
    walks = {pid: _pedestrian_walk(net, pid, ped, source, graph)
             for pid, ped in pedestrians.items()}
    routes = {vid: av.route_edges for vid, av in present(scenario.automated).items()}
    for pid, walk in walks.items():
        _check_crossing_on_route(net, pid, scenario.pedestrians[pid], walk.path, routes, source)
    if timer is None:
        timer = walk_timer(scenario, net_path)
    return walks, timer(walks, dt)


def walk_timer(scenario: Scenario, net_path: Path) -> ProbeTimer:
    """The network's probe walker for ``scenario``: lone SUMO walkers ramping their speed as
    the scenario's motion model bounds the acceleration (none without a bound)."""
    from sse_cosim.world.walk_probe import ProbeTimer  # imported here: it imports demand

    dt = scenario.simulation.step_length_s
    return ProbeTimer(net_path, accel_mps2=acceleration_bound(scenario.estimator, dt))


def write_route_file(scenario: Scenario, plan: ActorPlan, path: Path) -> Path:
    """The SUMO route file with the scenario's types, vehicles and pedestrians."""
    actors = [
        *(_automated(vid, av, plan.automated_lanes[vid])
          for vid, av in present(scenario.automated).items()),
        *(_parked(vid, parked) for vid, parked in present(scenario.parked).items()),
        *(_vehicle(vid, vehicle) for vid, vehicle in present(scenario.vehicles).items()),
        *(_pedestrian(pid, ped, plan.pedestrians[pid])
          for pid, ped in present(scenario.pedestrians).items()),
    ]
    # departures in time order (SUMO requires it); at one time in the order of the tables
    entries = sorted(enumerate(actors), key=lambda e: (e[1][1], e[0]))
    text = "\n".join([
        '<?xml version="1.0" encoding="UTF-8"?>',
        f"<!-- Generated by sse_cosim.world from scenario {scenario.name!r}; do not edit. -->",
        '<routes xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" '
        'xsi:noNamespaceSchemaLocation="http://sumo.dlr.de/xsd/routes_file.xsd">',
        *(actor[0] for actor in actors),
        *(entry[1][2] for entry in entries),
        "</routes>",
        "",
    ])
    return write_text_atomic(path, text)


Entry = tuple[str, float, str]  # (its vType element, departure time (s), its element)


def _automated(vid: str, av: AutomatedVehicle, lane: LaneGeometry) -> Entry:
    """The vehicle and its type; it departs on ``lane`` at its nominal speed within the lane's
    limit (SUMO refuses a faster departure)."""
    vtype = _element("vType", id=vid, vClass=av.vehicle_class, guiShape=av.vehicle_class,
                     length=av.length_m, width=av.width_m, accel=av.accel_mps2,
                     decel=av.comfortable_decel_mps2, emergencyDecel=av.emergency_decel_mps2,
                     apparentDecel=av.comfortable_decel_mps2, maxSpeed=av.nominal_speed_mps,
                     speedFactor=1, speedDev=0, sigma=0)
    return vtype, av.depart_s, _driving(vid, av.depart_s, lane.index, av.depart_pos_m,
                                        min(av.nominal_speed_mps, lane.speed_mps),
                                        av.route_edges)


def _parked(vid: str, parked: ParkedVehicle) -> Entry:
    vtype = _element("vType", id=vid, vClass=PARKED_VCLASS, guiShape="truck",
                     length=parked.length_m, width=parked.width_m, speedFactor=1, speedDev=0,
                     sigma=0)
    return vtype, 0.0, (
        f'    <vehicle id={quoteattr(vid)} type={quoteattr(vid)} depart="0" '
        f'departLane="{parked.lane_index}" departPos="{_num(parked.end_pos_m)}" '
        f'departSpeed="0">\n'
        f"        <route edges={quoteattr(parked.edge)}/>\n"
        f'        <stop lane={quoteattr(f"{parked.edge}_{parked.lane_index}")} '
        f'endPos="{_num(parked.end_pos_m)}" duration="{_num(PARKED_DURATION_S)}"/>\n'
        f"    </vehicle>")


def _vehicle(vid: str, vehicle: Vehicle) -> Entry:
    vtype = _element("vType", id=vid, vClass=VEHICLE_VCLASS, guiShape=VEHICLE_VCLASS,
                     length=vehicle.length_m, width=vehicle.width_m, maxSpeed=vehicle.speed_mps,
                     speedFactor=1, speedDev=0, sigma=0)
    return vtype, vehicle.depart_s, _driving(vid, vehicle.depart_s, vehicle.lane_index,
                                             vehicle.depart_pos_m, vehicle.speed_mps,
                                             vehicle.route_edges)


def _driving(vid: str, depart_s: float, lane: int, depart_pos_m: float, speed_mps: float,
             route_edges: Sequence[str]) -> str:
    """A vehicle of its own type ``vid`` that departs at ``depart_s`` on ``lane`` of its
    route's first edge, at ``depart_pos_m`` and ``speed_mps``."""
    return (f'    <vehicle id={quoteattr(vid)} type={quoteattr(vid)} depart="{_num(depart_s)}" '
            f'departLane="{lane}" departPos="{_num(depart_pos_m)}" '
            f'departSpeed="{_num(speed_mps)}">\n'
            f'        <route edges={quoteattr(" ".join(route_edges))}/>\n'
            f"    </vehicle>")


def pedestrian_vtype(type_id: str, walking_speed_mps: float, radius_m: float) -> str:
    """The vType element of a pedestrian walking at ``walking_speed_mps`` (exactly: no speed
    factor, no deviation) with a body of ``radius_m`` (SUMO's length and width: its
    diameter). It ignores approaching vehicles at crossings (``jmIgnoreFoeProb="1"``, for
    every vehicle up to :data:`IGNORE_FOE_SPEED_MPS`): it steps onto an unprioritised
    crossing when its walk gets there, as on a zebra, instead of waiting at the kerb for a
    gap. It still stops at a red pedestrian light."""
    size = 2.0 * radius_m
    return _element("vType", id=type_id, vClass="pedestrian", length=size, width=size,
                    desiredMaxSpeed=walking_speed_mps, maxSpeed=walking_speed_mps,
                    speedFactor=1, speedDev=0, jmIgnoreFoeProb=1,
                    jmIgnoreFoeSpeed=IGNORE_FOE_SPEED_MPS)


def _pedestrian(pid: str, ped: Pedestrian, plan: PedestrianPlan) -> Entry:
    vtype = pedestrian_vtype(pid, ped.walking_speed_mps, ped.radius_m)
    return vtype, 0.0, (
        f'    <person id={quoteattr(pid)} type={quoteattr(pid)} depart="0" '
        f'departPos="{_num(ped.start_pos_m)}">\n'
        f"        <stop edge={quoteattr(ped.start_edge)} endPos=\"{_num(ped.start_pos_m)}\" "
        f'until="{_num(plan.walk_start_s)}"/>\n'
        f'        <walk edges={quoteattr(" ".join(plan.path))} '
        f'arrivalPos="{_num(ped.end_pos_m)}"/>\n'
        f"    </person>")


# --- checks -------------------------------------------------------------------------------


def read_net(net_path: Path) -> sumolib.net.Net:
    """The network at ``net_path`` as the planner reads it (internal edges, walking links)."""
    return sumolib.net.readNet(str(net_path), withInternal=True, withPedestrianConnections=True)


def net_of(net_path: Path, roadmap: RoadMap) -> sumolib.net.Net:
    """The network the road map holds (``roadmap.net``), or read from ``net_path``."""
    return read_net(net_path) if roadmap.net is None else roadmap.net


def _edge(net: sumolib.net.Net, edge_id: str, field: str, source: str) -> sumolib.net.edge.Edge:
    if not net.hasEdge(edge_id) or net.getEdge(edge_id).getFunction():
        raise UserError(source, field, f"the network has no edge {edge_id!r}",
                        f"use an edge id of the network; the nearest: "
                        f"{', '.join(nearest_edges(net, edge_id))}")
    return net.getEdge(edge_id)


def nearest_edges(net: sumolib.net.Net, edge_id: str, count: int = NEAREST_EDGES) -> list[str]:
    """The ``count`` normal edge ids of ``net`` that read most like ``edge_id`` (difflib's
    similarity), most alike first; a typo's answer stays short on a town's network."""
    names = sorted(e.getID() for e in net.getEdges(withInternal=False))
    return difflib.get_close_matches(edge_id, names, n=count, cutoff=0.0)


def _check_pos(net: sumolib.net.Net, edge_id: str, pos: float, field: str, source: str) -> None:
    length = net.getEdge(edge_id).getLength()
    if pos > length:
        raise UserError(source, field, f"{pos:g} m lies beyond the end of edge {edge_id!r} "
                        f"({length:g} m long)", f"use a position between 0 and {length:g}")


def _check_route(net: sumolib.net.Net, edges: list[str], vclass: str, field: str,
                 source: str) -> None:
    for edge_id in edges:
        edge = _edge(net, edge_id, field, source)
        if not edge.allows(vclass):
            raise UserError(source, field, f"edge {edge_id!r} has no lane for vClass {vclass}",
                            "route the vehicle over driving lanes")
    for a, b in itertools.pairwise(edges):
        conns = net.getEdge(a).getOutgoing().get(net.getEdge(b), [])
        if not any(c.getFromLane().allows(vclass) and c.getToLane().allows(vclass) for c in conns):
            raise UserError(source, field, f"edge {b!r} does not follow edge {a!r} for a "
                            f"{vclass}", "list consecutive, connected edges")


def _check_speed(net: sumolib.net.Net, edges: list[str], vclass: str, speed: float, field: str,
                 source: str) -> None:
    """``speed`` is within the limit of every lane the vehicle may use on its route (SUMO would
    hold it to the limit, and refuse a faster departure): a traffic vehicle keeps one speed."""
    lane, limit = _route_limit(net, edges, vclass, min)
    if speed > limit + 1e-9:
        raise UserError(source, field, f"{speed:g} m/s is above the speed limit of lane "
                        f"{lane!r} on the route ({limit:g} m/s), which SUMO would hold the "
                        "vehicle to", f"use at most {limit:g} m/s")


def _check_nominal(net: sumolib.net.Net, edges: list[str], vclass: str, speed: float,
                   field: str, source: str) -> None:
    """An automated vehicle's nominal ``speed`` is within the fastest limit on its route: it
    drives each lane at most at the lane's limit (its controller plans with the limits ahead,
    :mod:`sse_cosim.control.limits`), so a nominal speed above every limit could never be
    driven, and its levels (fractions of it) would not mean what they say."""
    lane, limit = _route_limit(net, edges, vclass, max)
    if speed > limit + 1e-9:
        raise UserError(source, field, f"{speed:g} m/s is above every speed limit on the "
                        f"route (the fastest, lane {lane!r}, allows {limit:g} m/s): the "
                        "vehicle could never drive it", f"use at most {limit:g} m/s")


def _route_limit(net: sumolib.net.Net, edges: list[str], vclass: str,
                 pick: Callable[..., sumolib.net.lane.Lane]) -> tuple[str, float]:
    """The lane ``pick`` (min or max) chooses by speed limit among the lanes a ``vclass``
    vehicle may use on its route, and that limit (m/s)."""
    lane = pick(_route_lanes(net, edges, vclass), key=lambda candidate: candidate.getSpeed())
    return str(lane.getID()), float(lane.getSpeed())


def _route_lanes(net: sumolib.net.Net, edges: list[str],
                 vclass: str) -> list[sumolib.net.lane.Lane]:
    """The lanes of ``edges`` that admit ``vclass``, and the junction lanes between them."""
    lanes = [lane for e in edges for lane in net.getEdge(e).getLanes() if lane.allows(vclass)]
    for a, b in itertools.pairwise(edges):
        for conn in net.getEdge(a).getOutgoing().get(net.getEdge(b), []):
            if conn.getFromLane().allows(vclass) and conn.getViaLaneID():
                lanes.append(net.getLane(conn.getViaLaneID()))
    return lanes


def _check_lane(net: sumolib.net.Net, edge_id: str, index: int, vclass: str, field: str,
                source: str) -> None:
    lanes = net.getEdge(edge_id).getLanes()
    if index >= len(lanes):
        raise UserError(source, field, f"edge {edge_id!r} has no lane {index} "
                        f"(lanes 0..{len(lanes) - 1})", "use an existing lane index")
    if not lanes[index].allows(vclass):
        allowed = [lane.getIndex() for lane in lanes if lane.allows(vclass)]
        raise UserError(source, field, f"lane {index} of edge {edge_id!r} does not admit "
                        f"vClass {vclass}", f"use lane {', '.join(map(str, allowed)) or '-'}")


def _check_automated(net: sumolib.net.Net, roadmap: RoadMap, vid: str, av: AutomatedVehicle,
                     source: str) -> LaneGeometry:
    """Check an automated vehicle's route, speed, departure and lane changes (each on an edge
    longer than the vehicle); its departure lane: the first of the lanes its controller plans
    on (``RoadMap.route_lanes``), one that leads on along the route."""
    field, vclass = f"automated.{vid}", av.vehicle_class
    _check_route(net, av.route_edges, vclass, f"{field}.route_edges", source)
    _check_driving_lanes(net, av.route_edges, f"{field}.route_edges", source)
    _check_nominal(net, av.route_edges, vclass, av.nominal_speed_mps,
                   f"{field}.nominal_speed_mps", source)
    _check_pos(net, av.route_edges[0], av.depart_pos_m, f"{field}.depart_pos_m", source)
    for change in roadmap.route_changes(av.route_edges):
        length = roadmap.edge_lengths[change.edge_id]
        if length <= av.length_m:
            raise UserError(source, f"{field}.route_edges", f"the vehicle has to change from "
                            f"lane {change.from_index} to lane {change.to_index} on edge "
                            f"{change.edge_id!r} to follow its route, but the edge "
                            f"({length:.2f} m) is not longer than the vehicle "
                            f"({av.length_m:g} m): it changes lanes once its body is on it",
                            "route it over edges it can drive lane to lane, or add the "
                            "connection to the network (docs/own_network.md)")
    return roadmap.route_lanes(av.route_edges)[0]


def _check_driving_lanes(net: sumolib.net.Net, edges: list[str], field: str,
                         source: str) -> None:
    """Each edge of an automated vehicle's route has a driving lane (buses or cars, no
    pedestrians), which the road map follows; a road shared with walkers has none."""
    for edge_id in edges:
        edge = net.getEdge(edge_id)
        if not any(is_driving_lane(lane) for lane in edge.getLanes()):
            kind = f" ({edge.getType()})" if edge.getType() else ""
            raise UserError(source, field, f"edge {edge_id!r}{kind} has no driving lane (a lane "
                            "for buses or cars that pedestrians do not walk on): pedestrians "
                            "walk on its road lanes, as on a street without sidewalks",
                            "route the vehicle over streets with sidewalks; a network without "
                            "any gets them from netconvert --sidewalks.guess "
                            "(docs/own_network.md)")


def _check_vehicle(net: sumolib.net.Net, vid: str, vehicle: Vehicle, source: str) -> None:
    field, edges = f"vehicles.{vid}", vehicle.route_edges
    _check_route(net, edges, VEHICLE_VCLASS, f"{field}.route_edges", source)
    _check_speed(net, edges, VEHICLE_VCLASS, vehicle.speed_mps, f"{field}.speed_mps", source)
    _check_pos(net, edges[0], vehicle.depart_pos_m, f"{field}.depart_pos_m", source)
    _check_lane(net, edges[0], vehicle.lane_index, VEHICLE_VCLASS, f"{field}.lane_index",
                source)


def _check_parked(net: sumolib.net.Net, vid: str, parked: ParkedVehicle, source: str) -> None:
    field = f"parked.{vid}"
    edge = _edge(net, parked.edge, f"{field}.edge", source)
    lanes = edge.getLanes()
    if parked.lane_index >= len(lanes):
        raise UserError(source, f"{field}.lane_index", f"edge {parked.edge!r} has no lane "
                        f"{parked.lane_index} (lanes 0..{len(lanes) - 1})",
                        "use the parking strip's index (1)")
    lane = lanes[parked.lane_index]
    drivers = [c for c in DRIVING_VCLASSES if lane.allows(c)]
    if drivers or not lane.allows(PARKED_VCLASS):
        why = (f": it admits vClass {' and '.join(drivers)}, and a vehicle parked on a lane "
               "that cars or buses drive on blocks them" if drivers else "")
        raise UserError(source, f"{field}.lane_index", f"lane {parked.lane_index} of edge "
                        f"{parked.edge!r} is not a parking strip{why}", _parking_fix(edge, field))
    length = lanes[parked.lane_index].getLength()
    if not parked.length_m <= parked.end_pos_m <= length:
        raise UserError(source, f"{field}.end_pos_m", f"{parked.end_pos_m:g} m does not fit a "
                        f"{parked.length_m:g} m vehicle on edge {parked.edge!r} "
                        f"({length:g} m long)",
                        f"use a front position between {parked.length_m:g} and {length:g}")


def _parking_fix(edge: sumolib.net.edge.Edge, field: str) -> str:
    """Where to park instead: the edge's parking strips (lanes that admit vClass custom1 and
    no bus or car), or how to add one."""
    strips = [str(ln.getIndex()) for ln in edge.getLanes() if ln.allows(PARKED_VCLASS)
              and not any(ln.allows(c) for c in DRIVING_VCLASSES)]
    if strips:
        return f"park it on lane {', '.join(strips)} (a parking strip)"
    return (f"edge {edge.getID()!r} has no parking strip: park it on an edge that has one, or "
            f'add one (a lane with allow="{PARKED_VCLASS}" beside the driving lanes, '
            f"docs/own_network.md), or set {field}.present = false")


# --- the pedestrian -----------------------------------------------------------------------


def _sidewalk(net: sumolib.net.Net, edge_id: str, field: str, source: str) -> None:
    edge = _edge(net, edge_id, field, source)
    if not any(is_sidewalk(lane) for lane in edge.getLanes()):
        raise UserError(source, field, f"edge {edge_id!r} has no sidewalk (a lane for "
                        "pedestrians and no bus or car)",
                        "start and end the pedestrian on an edge with a sidewalk")


def _pedestrian_walk(net: sumolib.net.Net, pid: str, ped: Pedestrian, source: str,
                     graph: WalkGraph | None = None) -> WalkToCrossing:
    """Check a pedestrian and plan its walk over the network's pedestrian ``graph`` (built
    here unless given): over its ``crossing`` if it names one, else the shortest walk over
    any crossing of the network."""
    field = f"pedestrians.{pid}"
    _sidewalk(net, ped.start_edge, f"{field}.start_edge", source)
    _sidewalk(net, ped.end_edge, f"{field}.end_edge", source)
    _check_pos(net, ped.start_edge, ped.start_pos_m, f"{field}.start_pos_m", source)
    _check_pos(net, ped.end_edge, ped.end_pos_m, f"{field}.end_pos_m", source)
    graph = WalkGraph(net) if graph is None else graph
    crossings = graph.crossings
    if ped.crossing is not None:
        if ped.crossing not in crossings:
            nearest = difflib.get_close_matches(ped.crossing, sorted(crossings),
                                                n=NEAREST_EDGES, cutoff=0.0)
            raise UserError(source, f"{field}.crossing", f"the network has no crossing "
                            f"{ped.crossing!r}", "name a crossing of the network; the nearest: "
                            f"{', '.join(nearest) or '(none: the network has no crossing)'}")
        crossings = [ped.crossing]
    path = pedestrian_path(net, (ped.start_edge, ped.start_pos_m), (ped.end_edge, ped.end_pos_m),
                           crossings, graph)
    if path is None:
        over = f" over {ped.crossing}" if ped.crossing is not None else " over a zebra"
        raise UserError(source, f"{field}.crossing" if ped.crossing else f"{field}.end_edge",
                        f"no walk from {ped.start_edge!r}{over} to {ped.end_edge!r}",
                        f"name a crossing between them in {field}.crossing, or leave it out"
                        if ped.crossing else
                        "end the pedestrian on a sidewalk across the road from its start")
    crossing = next(e for e in path if net.getEdge(e).getFunction() == "crossing")
    return WalkToCrossing(path=tuple(path), start_pos_m=ped.start_pos_m, end_pos_m=ped.end_pos_m,
                          length_m=walk_length(net, path, ped.start_pos_m, ped.end_pos_m),
                          crossing=crossing, speed_mps=ped.walking_speed_mps,
                          radius_m=ped.radius_m)


def _time_pedestrian(net: sumolib.net.Net, pid: str, ped: Pedestrian, walk: WalkToCrossing,
                     walk_s: float, dt: float, source: str) -> PedestrianPlan:
    """The plan of a pedestrian whose walk takes ``walk_s`` (whole steps) from its start to
    its first step on the crossing: it starts walking at the step nearest to
    ``steps_onto_crossing_s - walk_s``; a negative one is an error naming the earliest time."""
    field = f"pedestrians.{pid}"
    wanted = ped.steps_onto_crossing_s
    start_step = math.floor((wanted - walk_s) / dt + 0.5 + _EPS)
    if start_step < 0:
        earliest = round(walk_s, 6)
        raise UserError(source, f"{field}.steps_onto_crossing_s",
                        f"{wanted:g} s cannot be reached: SUMO's walker takes {walk_s:.6g} s at "
                        f"{ped.walking_speed_mps:g} m/s from {field}.start_pos_m to the crossing "
                        f"{walk.crossing}, so it steps onto it at {earliest:.6g} s at the "
                        "earliest",
                        f"use {earliest:.6g} s or later, or a {field}.start_pos_m nearer the "
                        "crossing")
    return PedestrianPlan(
        path=walk.path,
        crossing=walk.crossing,
        distance_to_crossing_m=distance_to_crossing(net, walk.path, ped.start_pos_m),
        standing_xy=standing_point(net, walk.path, ped.start_pos_m, ped.radius_m),
        walk_start_s=round(start_step * dt, 6),
        walk_to_crossing_s=round(walk_s, 6),
        crossing_time_s=wanted,
    )


def _check_light(pid: str, plan: PedestrianPlan, roadmap: RoadMap, dt: float,
                 source: str) -> None:
    """A pedestrian whose crossing has a pedestrian light steps onto it while the light lets
    its walkers go, for the whole step (a static program, whose greens are known in advance:
    :meth:`~sse_cosim.world.signals.Program.windows`); else a UserError naming the next time
    it can. The light a snapshot at time t shows is SUMO's at t + dt (:mod:`walk_probe`)."""
    crossing = next((c for c in roadmap.crossings if c.id == plan.crossing), None)
    if crossing is None or not crossing.signals:
        return
    field = f"pedestrians.{pid}.steps_onto_crossing_s"
    steps_on = plan.steps_on_s
    for light, link in crossing.signals:
        programs = [program for (owner, _), program in roadmap.programs.items()
                    if owner == light]
        if len(programs) != 1 or not programs[0].static:
            raise UserError(source, field, f"the pedestrian light {light!r} of its crossing "
                            f"{crossing.id} runs no single static program, so its greens "
                            "cannot be known in advance", "plan the step-out at a crossing "
                            "without a light or with a static program, or walk the pedestrian "
                            "from a route file (network.route_files)")
        program = programs[0]
        greens = program.windows(link, WALKERS_GO, steps_on, steps_on + 2 * program.cycle_s)
        if greens and greens[0][0] <= steps_on + _EPS and steps_on + dt <= greens[0][1] + _EPS:
            continue
        fits = [math.ceil(max(start, steps_on) / dt - _EPS) * dt for start, end in greens
                if math.ceil(max(start, steps_on) / dt - _EPS) * dt + dt <= end + _EPS]
        hint = f", e.g. {fits[0]:g} s, when its walkers' next green has begun" if fits else ""
        raise UserError(source, field, f"{steps_on:g} s falls while the pedestrian light "
                        f"{light!r} of its crossing {crossing.id} holds its walkers (SUMO's "
                        "walker would wait there, off its time)",
                        f"use a time within a green of that light{hint} (its program: "
                        f"{program.cycle_s:g} s a cycle, from t = {program.offset_s:g} s)")


def _check_crossing_on_route(net: sumolib.net.Net, pid: str, ped: Pedestrian,
                             path: Sequence[str], routes: dict[str, list[str]],
                             source: str) -> None:
    """The zebra of a pedestrian's walk crosses an automated vehicle's route (it steps onto it
    at ``steps_onto_crossing_s``, the moment the scenario is about); none to check without
    automated vehicles. A crossing crosses the edges SUMO lists as its ``crossingEdges``."""
    if not routes:
        return
    crossing = next(e for e in path if net.getEdge(e).getFunction() == "crossing")
    crossed = [e.getID() for e in net.getEdge(crossing).getCrossingEdges()]
    if any(e in route for route in routes.values() for e in crossed):
        return
    field = f"pedestrians.{pid}"
    names = ", ".join(f"automated.{vid}" for vid in routes)
    on_route = route_crossings(net, routes.values())
    zebras = ", ".join(on_route[:NEAREST_EDGES]) + (", ..." if len(on_route) > NEAREST_EDGES
                                                     else "")
    fix = ("end the pedestrian on the far side of the route's street (an edge whose sidewalk "
           "is across the route from its start), so that its walk takes a zebra over the "
           f"route: {zebras}" if on_route else f"the route has no zebra: route {names} over "
           f"a street with one, or set {field}.present = false")
    raise UserError(source, f"{field}.end_edge", f"the walk from {ped.start_edge!r} to "
                    f"{ped.end_edge!r} crosses at {crossing} (over "
                    f"{', '.join(map(repr, crossed))}), on no automated vehicle's route "
                    f"({names}), so it never steps onto the route at "
                    f"{field}.steps_onto_crossing_s", fix)


def route_crossings(net: sumolib.net.Net, routes: Iterable[Sequence[str]]) -> list[str]:
    """The crossings over any of ``routes`` (each a list of edges), by id: those whose
    ``crossingEdges`` include an edge of a route."""
    routes = list(routes)
    return sorted(e.getID() for e in net.getEdges(withInternal=True)
                  if e.getFunction() == "crossing"
                  and any(c.getID() in route for route in routes for c in e.getCrossingEdges()))


def crossing_choices(scenario: Scenario, pid: str, net_path: Path, roadmap: RoadMap) -> list[str]:
    """The crossings over an automated vehicle's route that pedestrian ``pid`` of ``scenario``
    can take from its start to its end, the shortest walk first (ties by id): the crossings
    its ``crossing`` may name."""
    net = net_of(net_path, roadmap)
    ped = scenario.pedestrians[pid]
    graph = WalkGraph(net)
    routes = [av.route_edges for av in present(scenario.automated).values()]
    walks = []
    for crossing in route_crossings(net, routes):
        path = pedestrian_path(net, (ped.start_edge, ped.start_pos_m),
                               (ped.end_edge, ped.end_pos_m), [crossing], graph)
        if path is not None:
            walks.append((walk_length(net, path, ped.start_pos_m, ped.end_pos_m), crossing))
    return [crossing for _, crossing in sorted(walks)]


def pedestrian_path(net: sumolib.net.Net, start: tuple[str, float], end: tuple[str, float],
                    crossings: Sequence[str],
                    graph: WalkGraph | None = None) -> list[str] | None:
    """The shortest walk from ``start`` to ``end`` (each an edge and a position on it, m) over
    exactly one of ``crossings``, as a list of edges; None if there is none.

    Walking areas and crossings can be walked either way, so the pedestrian graph
    (:class:`~sse_cosim.world.walkgraph.WalkGraph`, built once; pass ``graph`` to share it)
    is undirected; for each crossing and direction, the walk reaches one of the crossing's
    walking areas without using any crossing, crosses, and goes on from the other one.

    Two searches price every crossing: one from the start gives the first half of each walk
    (the walk a search from the start to that walking area finds), one towards the end the
    cost of each second half. Only the crossings whose walk can still be the shortest (the
    position on the end edge left open) get a search for their second half; of those, the
    first in ``crossings`` order whose walk is shortest wins, as when every crossing is tried.
    """
    graph = WalkGraph(net) if graph is None else graph
    avoid = frozenset(graph.crossings)  # no other zebra before or after it: one crossing only
    firsts = graph.tree(start[0], avoid)
    to_end = graph.costs_to(end[0], avoid)
    end_length = graph.length[end[0]]
    priced: list[tuple[float, str, str, str]] = []  # (lower bound of the walk, crossing, a, b)
    for crossing in crossings:
        ends = graph.walking_areas_of(crossing)
        for a, b in ((ends[0], ends[1]), (ends[1], ends[0])) if len(ends) == 2 else ():
            if a not in firsts or b not in to_end:
                continue
            first = firsts[a]
            forward = _walks_forward(net, first)
            head = graph.length[start[0]] - start[1] if forward else start[1]
            low = (head + sum(graph.length[e] for e in first[1:]) + graph.length[crossing]
                   + graph.length[b] + to_end[b] - end_length)
            priced.append((low, crossing, a, b))
    if not priced:
        return None
    # the walk's length lies between its lower bound and that plus the end edge's length
    # (where on it the walk ends); the tolerance covers the backward search's rounding
    bound = min(low for low, *_ in priced) + end_length
    bound += 1e-6 * (1.0 + abs(bound))
    best: tuple[float, list[str]] | None = None
    for low, crossing, a, b in priced:
        if low > bound:
            continue
        second = graph.shortest(b, end[0], avoid)
        if second is None:
            continue
        path = [*firsts[a], crossing, *second[1]]
        length = walk_length(net, path, start[1], end[1])
        if best is None or length < best[0]:
            best = (length, path)
    return None if best is None else best[1]


def walk_length(net: sumolib.net.Net, path: Sequence[str], start_pos: float,
                end_pos: float) -> float:
    """Length (m) of a walk along ``path`` from ``start_pos`` on its first edge to ``end_pos``
    on its last (at least three edges: a sidewalk, ..., a sidewalk)."""
    first, last = net.getEdge(path[0]), net.getEdge(path[-1])
    head = first.getLength() - start_pos if _walks_forward(net, path) else start_pos
    tail = last.getLength() - end_pos if _walks_forward(net, path[::-1]) else end_pos
    return head + sum(net.getEdge(e).getLength() for e in path[1:-1]) + tail


def standing_point(net: sumolib.net.Net, path: list[str] | tuple[str, ...], start_pos: float,
                   radius: float) -> tuple[float, float]:
    """Centre (x, y) of a pedestrian of ``radius`` where its walk along ``path`` begins.

    SUMO's striping model lays stripes of :data:`STRIPE_WIDTH_M` across the sidewalk from
    its left edge and starts a walk on the stripe at the walker's right hand, with the
    walker's front at ``start_pos``; the centre lies ``radius`` behind, against the walking
    direction.
    """
    lane = next(lane for lane in net.getEdge(path[0]).getLanes() if lane.allows("pedestrian"))
    forward = _walks_forward(net, path)
    width = lane.getWidth()
    stripes = max(1, math.floor(width / STRIPE_WIDTH_M))
    stripe = stripes - 1 if forward else 0
    right = (stripe + 0.5) * STRIPE_WIDTH_M - 0.5 * width  # lateral offset, to the lane's right
    along = start_pos - radius if forward else start_pos + radius
    shape = lane.getShape()
    along *= sumolib.geomhelper.polyLength(shape) / lane.getLength()  # SUMO's geometry factor
    x, y = sumolib.geomhelper.positionAtShapeOffset(shape, along)
    angle = sumolib.geomhelper.rotationAtShapeOffset(shape, along)
    return float(x + right * math.sin(angle)), float(y - right * math.cos(angle))


def distance_to_crossing(net: sumolib.net.Net, path: list[str] | tuple[str, ...],
                         start_pos: float) -> float:
    """Walking distance (m) from ``start_pos`` on ``path[0]`` to the start of the crossing."""
    first = net.getEdge(path[0])
    distance = (first.getLength() - start_pos) if _walks_forward(net, path) else start_pos
    for edge_id in path[1:]:
        edge = net.getEdge(edge_id)
        if edge.getFunction() == "crossing":
            return distance
        distance += edge.getLength()
    raise ValueError("the path has no crossing")


def _walks_forward(net: sumolib.net.Net, path: Sequence[str]) -> bool:
    """Whether the walk leaves ``path[0]`` at its end (along the edge's direction)."""
    nxt = net.getEdge(path[1])
    return net.getEdge(path[0]).getToNode() in (nxt.getFromNode(), nxt.getToNode())


# --- XML ----------------------------------------------------------------------------------


def _num(value: float) -> str:
    if not math.isfinite(value):
        raise ValueError(f"not a finite number: {value}")
    return f"{value:.10g}"


def _element(tag: str, **attrs: object) -> str:
    parts = " ".join(
        f"{k}={quoteattr(_num(v) if isinstance(v, float | int) else str(v))}"
        for k, v in attrs.items())
    return f"    <{tag} {parts}/>"

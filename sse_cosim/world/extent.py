"""The part of a network a scene can use: the road map of a whole town is built for the edges
near the scene only.

A scene's extent is a set of boxes (network coordinates) around what it places on the
network: every automated and other vehicle's route edges, every parked vehicle's edge, every
pedestrian's start and end edges and every road-side unit, each widened by a margin of

    max_pedestrian_speed_mps * duration_s   (how far any pedestrian walks in the run)
  + interest_radius_m                       (the controller's tracked window)
  + the longest sensor range                (what any sensor can see beyond the route)
  + 2 * position_jitter_m + SLACK_M

with the jitter as the scenario sets it, or :data:`MAX_MEASURED_JITTER_M` where it is left to
the measurement (:mod:`sse_cosim.world.walker_jitter`, which refuses more).

Every pedestrian of the scenario starts on an edge of the extent and stays within its margin
for the whole run, so no pedestrian outside the extent can reach the bus's route, a crossing
on it or a sensor's field of view before the run ends: the walkable ground, crossings and
lanes of the rest of the town change nothing a run computes before then. A scenario with
route files (``network.route_files``) may put persons and sensor-carrying vehicles anywhere:
its extent is the whole network (:func:`scene_extent` returns None).

An edge belongs to the extent when the bounding box of its lanes meets one of the boxes; on a
network that lies within them all (the paper's road, the junction) every edge does, and the
road map is the same as the whole network's, built in the same order.

The jitter's scope (:class:`JitterScope`). Of the extent's junctions, the walkers' jitter is
measured (:mod:`sse_cosim.world.walker_jitter`) at those a run's assumption is about:

- every junction at an end of an edge a walker of the scene walks or stands on (a scenario
  pedestrian's planned path, a route file's walk given edge by edge): the scene's true walkers
  pass no other, and the world checks every step that each keeps the assumption;
- every junction with a walking area within reach of an automated vehicle's route: its
  controller tracks hidden ground within ``interest_radius_m`` of the crossings and walkable
  ground its body sweeps (docs/controller.md), so the walkers it reasons about are assumed to
  keep the jitter measured there, whether or not the scene puts a true walker there (a scene
  with its pedestrian and one without assume the same).

A junction that is neither decides nothing (a city's junction 115 m from the route that no
walker uses no longer refuses a run). Where some person's walk is left to SUMO's router (a
route file's ``from``/``to``), the scope is every junction of the extent.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import shapely
import sumolib

from sse_cosim.scenario.model import present

if TYPE_CHECKING:
    from sse_cosim.scenario.model import Scenario
    from sse_cosim.world.roadmap import RoadMap

MAX_MEASURED_JITTER_M = 2.0  # the most a measured jitter may be (m): the extent reaches that far
SLACK_M = 10.0  # beyond the margin's terms: lane widths, a pedestrian's radius, rounding

Box = tuple[float, float, float, float]  # (x_min, y_min, x_max, y_max), m


@dataclass(frozen=True)
class SceneExtent:
    """Boxes around what a scene places on the network (see module docstring)."""

    boxes: tuple[Box, ...]

    def meets(self, box: Box) -> bool:
        """Whether ``box`` meets one of the extent's boxes (touching counts)."""
        x0, y0, x1, y1 = box
        return any(x0 <= b[2] and b[0] <= x1 and y0 <= b[3] and b[1] <= y1
                   for b in self.boxes)

    def holds(self, edge: sumolib.net.edge.Edge) -> bool:
        """Whether ``edge`` (any function) belongs to the extent."""
        return self.meets(edge_box(edge))


def edge_box(edge: sumolib.net.edge.Edge) -> Box:
    """The bounding box of an edge's lanes' shapes (m)."""
    xs: list[float] = []
    ys: list[float] = []
    for lane in edge.getLanes():
        for point in lane.getShape():
            xs.append(point[0])
            ys.append(point[1])
    return (min(xs), min(ys), max(xs), max(ys))


def scene_margin(scenario: Scenario) -> float:
    """How far (m) around what the scene places its extent reaches (module docstring)."""
    ranges = [sensor.range_m for sensor in scenario.sensors.values()]
    estimator = scenario.estimator
    return (estimator.max_pedestrian_speed_mps * scenario.simulation.duration_s
            + scenario.controller.interest_radius_m + max(ranges, default=0.0)
            + 2.0 * scene_jitter(scenario) + SLACK_M)


def scene_jitter(scenario: Scenario) -> float:
    """The jitter (m) the extent allows for: the scenario's, or the most a measured one may be."""
    jitter = scenario.estimator.position_jitter_m
    return MAX_MEASURED_JITTER_M if jitter is None else jitter


def scene_edges(scenario: Scenario) -> list[str]:
    """The edges the scenario's actors name (routes, parking edges, pedestrians' ends)."""
    edges = [e for av in present(scenario.automated).values() for e in av.route_edges]
    edges += [e for vehicle in present(scenario.vehicles).values() for e in vehicle.route_edges]
    edges += [parked.edge for parked in present(scenario.parked).values()]
    for ped in present(scenario.pedestrians).values():
        edges += [ped.start_edge, ped.end_edge]
    return edges


def scene_extent(scenario: Scenario, net: sumolib.net.Net) -> SceneExtent | None:
    """The extent of ``scenario``'s scene on ``net``; None for the whole network (route files,
    or an edge the network lacks: the checks that follow name it)."""
    if scenario.network.route_files:
        return None
    margin = scene_margin(scenario)
    boxes: list[Box] = []
    for edge_id in scene_edges(scenario):
        if not net.hasEdge(edge_id):
            return None
        boxes.append(_widened(edge_box(net.getEdge(edge_id)), margin))
    boxes += [_widened((rsu.x_m, rsu.y_m, rsu.x_m, rsu.y_m), margin)
              for rsu in scenario.rsus.values()]
    return SceneExtent(tuple(_merged(boxes)))


def _widened(box: Box, margin: float) -> Box:
    return (box[0] - margin, box[1] - margin, box[2] + margin, box[3] + margin)


def _merged(boxes: Iterable[Box]) -> list[Box]:
    """The boxes without duplicates, in first-seen order."""
    return list(dict.fromkeys(boxes))


@dataclass(frozen=True)
class JitterScope:
    """The junctions whose walkers' jitter a run assumes (module docstring, "The jitter's
    scope"): those at an end of one of ``walked_edges`` and those with a walking area within
    ``reach_m`` of ``seeds`` (the ground the automated vehicles' controllers track hidden
    ground around: their bodies' sweeps and the crossings these meet)."""

    seeds: shapely.Geometry
    reach_m: float
    walked_edges: frozenset[str]

    def junctions(self, net: sumolib.net.Net,
                  areas: Sequence[sumolib.net.edge.Edge]) -> frozenset[str]:
        """Of the junctions of the walking areas ``areas`` of ``net``, the scope's: a walking
        area counts as near the seeds when the convex hull of its outline is."""
        walked = {node.getID() for edge in self.walked_edges if net.hasEdge(edge)
                  for node in (net.getEdge(edge).getFromNode(), net.getEdge(edge).getToNode())}
        if self.seeds.is_empty or not areas:
            return frozenset(walked)
        hulls = shapely.convex_hull([shapely.MultiPoint(area.getLanes()[0].getShape())
                                     for area in areas])
        near = shapely.dwithin(hulls, self.seeds, self.reach_m)
        return frozenset(walked | {area.getFromNode().getID()
                                   for area, close in zip(areas, near, strict=True) if close})


def jitter_scope(scenario: Scenario, roadmap: RoadMap,
                 walked_edges: frozenset[str] | None) -> JitterScope | None:
    """The jitter's scope of ``scenario`` on ``roadmap``, its walkers walking or standing on
    ``walked_edges`` (None: some walk is left to SUMO's router, so every junction of the
    extent: returns None). The seeds are each automated vehicle's route line widened by its
    body's length and width (its sweep, turning included) and the crossings that meets; the
    reach is the tracked window's radius, twice the jitter the extent allows for, and
    :data:`SLACK_M`."""
    if walked_edges is None:
        return None
    sweeps = [roadmap.route_line(av.route_edges).buffer(av.length_m + av.width_m)
              for av in present(scenario.automated).values()]
    swept = shapely.union_all(sweeps)
    met = set(roadmap.crossings_meeting(swept))
    crossings = [c.area for c in roadmap.crossings if c.id in met]
    reach = scenario.controller.interest_radius_m + 2.0 * scene_jitter(scenario) + SLACK_M
    return JitterScope(shapely.union_all([swept, *crossings]), reach, walked_edges)

"""The bus's situational picture: where the crossing is, what is hidden, where pedestrians may be.

Pure geometry on the road map (no SUMO). Distances are measured along the bus's route
centre line from its front bumper; the *path ahead* is that line widened to half the bus
width plus ``path_margin_m``.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
import shapely
from shapely.ops import substring

from sse_cosim.scenario.model import Bus, Controller
from sse_cosim.world.roadmap import RoadMap


@dataclass(frozen=True)
class SceneContext:
    """What does not change during a run: the route line, walkable and interesting areas."""

    route_line: shapely.LineString
    walkable: shapely.Geometry  # sidewalks, walking areas and the crossing
    area_of_interest: shapely.Geometry  # walkable within interest_radius_m of the crossing
    crossing_span: tuple[float, float]  # (start, end) of the crossing along the route (m)
    bus: Bus
    config: Controller

    @classmethod
    def build(cls, roadmap: RoadMap, route_edges: Sequence[str], bus: Bus, config: Controller):
        """Prepare the static geometry for a bus driving ``route_edges``."""
        route_line = roadmap.route_line(route_edges)
        walkable = shapely.union(roadmap.sidewalks, roadmap.crossing)
        near_crossing = roadmap.crossing.buffer(config.interest_radius_m)
        interest = shapely.intersection(walkable, near_crossing)
        along = [route_line.project(shapely.Point(p)) for p in _boundary_points(roadmap.crossing)]
        shapely.prepare(walkable)
        return cls(route_line, walkable, interest, (min(along), max(along)), bus, config)

    def path_ahead(self, front_s: float, length: float, margin: float) -> shapely.Geometry:
        """The corridor the bus sweeps over the next ``length`` metres, widened by ``margin``."""
        start = min(max(front_s, 0.0), self.route_line.length)
        end = min(front_s + max(length, 0.0), self.route_line.length)
        if end <= start:
            return shapely.Polygon()
        centre = substring(self.route_line, start, end)
        return centre.buffer(0.5 * self.bus.width_m + margin, cap_style="flat")

    def stopping_distance(self, speed: float) -> float:
        """Reaction distance plus comfortable braking distance plus the stopping margin (m)."""
        cfg = self.config
        braking = speed**2 / (2.0 * self.bus.comfortable_decel_mps2)
        return speed * cfg.reaction_time_s + braking + cfg.stopping_margin_m


@dataclass(frozen=True)
class Picture:
    """Everything the speed controller decides on, for one step."""

    front_s: float  # bus front along its route (m)
    distance_to_crossing: float  # front to the crossing's near edge (m); negative once on it
    crossing_ahead: bool
    own_occluded_m2: float  # hidden in the bus's own view and possibly holding a pedestrian
    unresolved_occluded_m2: float  # the same within the area of interest near the crossing
    pedestrian_near_crossing: bool
    pedestrian_near_path: bool
    pedestrian_in_stopping_distance: bool


def assess(
    context: SceneContext,
    front_xy: np.ndarray,
    speed: float,
    own_occluded: shapely.Geometry,
    unobserved: shapely.Geometry,
    pedestrian_regions: Iterable[shapely.Geometry],
) -> Picture:
    """The picture at one step.

    ``front_xy`` (2,) is the bus's front bumper; ``own_occluded`` what its sensors' shadows
    hide inside their fields of view; ``unobserved`` the walkable area where a pedestrian
    nobody detected may be (every node's views, shared ones included);
    ``pedestrian_regions`` where each known pedestrian may be.
    """
    cfg = context.config
    front_s = context.route_line.project(shapely.Point(front_xy))
    to_crossing = context.crossing_span[0] - front_s
    crossing_ahead = context.crossing_span[1] > front_s and to_crossing <= cfg.crossing_horizon_m
    own_hidden = shapely.intersection(own_occluded, unobserved)
    near_crossing_hidden = shapely.intersection(own_hidden, context.area_of_interest)
    near_path = context.path_ahead(front_s, cfg.crossing_horizon_m, cfg.path_margin_m)
    stopping = context.path_ahead(front_s, context.stopping_distance(speed), 0.0)
    sets = [s for s in pedestrian_regions if not s.is_empty]
    return Picture(
        front_s=float(front_s),
        distance_to_crossing=float(to_crossing),
        crossing_ahead=bool(crossing_ahead),
        own_occluded_m2=float(own_hidden.area),
        unresolved_occluded_m2=float(near_crossing_hidden.area),
        pedestrian_near_crossing=any(s.intersects(context.area_of_interest) for s in sets),
        pedestrian_near_path=any(s.intersects(near_path) for s in sets),
        pedestrian_in_stopping_distance=any(s.intersects(stopping) for s in sets),
    )


def _boundary_points(polygon: shapely.Geometry) -> np.ndarray:
    """Vertices of a polygon's exterior, shape (k, 2)."""
    return np.asarray(shapely.get_coordinates(polygon.convex_hull.exterior))

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
    crossing: shapely.Polygon
    crossing_span: tuple[float, float]  # (start, end) of the crossing along the route (m)
    bus: Bus
    config: Controller
    pedestrian_speed: float  # the estimator's speed bound (m/s)

    @classmethod
    def build(
        cls, roadmap: RoadMap, route_edges: Sequence[str], bus: Bus, config: Controller,
        pedestrian_speed: float,
    ) -> SceneContext:
        """Prepare the static geometry for a bus driving ``route_edges``."""
        route_line = roadmap.route_line(route_edges)
        walkable = shapely.union(roadmap.sidewalks, roadmap.crossing)
        along = [route_line.project(shapely.Point(p)) for p in _boundary_points(roadmap.crossing)]
        return cls(route_line, walkable, roadmap.crossing, (min(along), max(along)), bus, config,
                   pedestrian_speed)

    def reach_radius(self, front_s: float) -> float:
        """How far from the crossing an unseen pedestrian can be and still reach it before the
        bus, keeping its nominal speed, has cleared it; capped by ``interest_radius_m``.

        Farther away, a pedestrian cannot meet a bus at nominal speed on the crossing, so
        hidden area there is no reason to slow down; nearer, the bus slows so that it can
        stop for a pedestrian who steps out.
        """
        to_clear = self.crossing_span[1] - front_s + self.bus.length_m
        if to_clear <= 0:
            return 0.0
        radius = self.pedestrian_speed * to_clear / self.bus.nominal_speed_mps
        return min(radius, self.config.interest_radius_m)

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
    reach_radius_m: float  # how far from the crossing a pedestrian still matters
    own_occluded_m2: float  # hidden in the bus's own view and possibly holding a pedestrian
    unresolved_occluded_m2: float  # the part of it within the reach radius of the crossing
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
    reach = context.reach_radius(front_s)
    relevant = context.crossing.buffer(reach) if reach > 0 else shapely.Polygon()
    hidden_in_reach = shapely.intersection(own_hidden, relevant)
    near_path = context.path_ahead(front_s, cfg.crossing_horizon_m, cfg.path_margin_m)
    stopping = context.path_ahead(front_s, context.stopping_distance(speed), 0.0)
    sets = [s for s in pedestrian_regions if not s.is_empty]
    return Picture(
        front_s=float(front_s),
        distance_to_crossing=float(to_crossing),
        crossing_ahead=bool(crossing_ahead),
        reach_radius_m=float(reach),
        own_occluded_m2=float(own_hidden.area),
        unresolved_occluded_m2=float(hidden_in_reach.area),
        pedestrian_near_crossing=any(s.intersects(relevant) for s in sets),
        pedestrian_near_path=any(s.intersects(near_path) for s in sets),
        pedestrian_in_stopping_distance=any(s.intersects(stopping) for s in sets),
    )


def _boundary_points(polygon: shapely.Geometry) -> np.ndarray:
    """Vertices of a polygon's exterior, shape (k, 2)."""
    return np.asarray(shapely.get_coordinates(polygon.convex_hull.exterior))

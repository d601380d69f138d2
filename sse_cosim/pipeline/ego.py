"""One automated vehicle's estimation and control: from what every node sees to its speed.

Each automated vehicle is a fusing node (paper Fig. 3): it receives over its own V2X link what
every other node sends it, screens and fuses its own and the received estimates
(:class:`~sse_cosim.estimation.fusion_centre.FusionCentre`; anonymous tracks:
:class:`~sse_cosim.estimation.anonymous_fusion.AnonymousFusionCentre`), refines where each known
pedestrian can be and where an undetected one may be (negative information), builds its
situational picture and decides its speed level. :class:`Ego` owns all of that state; the
co-simulation holds one per automated vehicle.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from functools import partial
from typing import Protocol

import numpy as np

from sse_cosim.control.picture import (
    ArrivalMemory,
    LightClaims,
    Picture,
    SceneContext,
    Source,
    assess,
)
from sse_cosim.control.speed import Decision, fallback_floor, make_policy
from sse_cosim.estimation.fusion_centre import BusEstimate
from sse_cosim.estimation.motion import MotionModel
from sse_cosim.estimation.occupancy import UnobservedArea
from sse_cosim.estimation.settings import EstimatorSettings, coast
from sse_cosim.estimation.v2x import SharedPicture, V2XLink
from sse_cosim.pipeline.stages import (
    NodeView,
    Observations,
    Sharing,
    Tracks,
    known_regions,
    second_level,
    views_of,
)
from sse_cosim.regions import Region, RegionKind
from sse_cosim.scenario.model import Scenario
from sse_cosim.sensors import SensorSpec
from sse_cosim.world.roadmap import RoadMap
from sse_cosim.world.snapshot import Snapshot


class Laps(Protocol):
    """Charges the time since the previous lap to a stage (:mod:`sse_cosim.runner.timing`)."""

    def lap(self, stage: str) -> None: ...


@dataclass(frozen=True)
class EgoStep:
    """What one automated vehicle made of one step.

    ``shared``: the senders' newest messages brought to this step; ``estimate``: its screen,
    fused sets and flags; ``possible``: pedestrian id -> where that pedestrian can be (the
    fused set refined with negative information); ``unobserved``: walkable ground where an
    undetected pedestrian may be; ``window``: where hidden ground is tracked; ``sources``:
    what the picture's earliest arrivals came from, the unobserved area first, then each
    known pedestrian (its region, state set and path region).
    """

    vehicle: str
    shared: SharedPicture
    estimate: BusEstimate
    possible: dict[str, Region]
    unobserved: Region
    window: Region
    picture: Picture
    decision: Decision
    sources: tuple[Source, ...]


class Ego:
    """Automated vehicle ``vehicle_id``'s link, fusion centre, regions, picture and policy."""

    def __init__(self, vehicle_id: str, scenario: Scenario, roadmap: RoadMap, model: MotionModel,
                 settings: EstimatorSettings, specs: Mapping[str, SensorSpec],
                 link_rng: np.random.Generator, kind: RegionKind, scenario_name: str) -> None:
        config, dt = scenario.estimator, scenario.simulation.step_length_s
        vehicle = scenario.automated[vehicle_id]
        self.id = vehicle_id
        self.scenario_name = scenario_name  # what its run is called (the scenario file)
        self.controller = scenario.controller
        link = V2XLink(scenario.v2x, link_rng, partial(coast, model, settings))
        self.sharing = Sharing(link, model, vehicle_id)
        self.fusion = second_level(config.association, model, settings, config.fusion_method,
                                   specs, vehicle_id, kind)
        self.context = SceneContext.build(
            roadmap, vehicle.route_edges, vehicle, scenario.controller, model,
            scenario.pedestrian_radius_m(), dt, kind,
        )
        self.policy = make_policy(self.context)
        self.arrivals = ArrivalMemory(dt)  # the last consistent picture, for the floors
        # who a red light keeps off its crossing: a key is one pedestrian in labelled runs only
        self.claims = LightClaims(self.context) if config.association == "labelled" else None
        self.known = known_regions(config.filter, model, kind, self.context.walkable,
                                   self.context.window, history=config.association == "labelled")
        # hidden ground is tracked near the crossings on its route; outside it counts as occupied
        self.unobserved = UnobservedArea(
            self.context.walkable, model, scenario.v2x.latency_steps, kind,
            window=self.context.window,
        )
        self.kind = kind
        # where SUMO inserts it (its front): its V2X link's position until then
        self.departure_xy = self.context.path.point_at(vehicle.depart_pos_m)[0]

    def front(self, snapshot: Snapshot) -> np.ndarray:
        """Its front bumper (2,) in ``snapshot``; before SUMO has inserted it, where SUMO
        will (:attr:`departure_xy`)."""
        me = snapshot.vehicles.get(self.id)
        return self.departure_xy if me is None else me.footprint.front.position

    def step(self, step: int, snapshot: Snapshot, observations: Observations,
             node_views: Mapping[str, NodeView], tracks: Tracks, timer: Laps) -> EgoStep:
        """Receive, screen and fuse, refine, picture and decide (the vehicle is in
        ``snapshot``; every node's messages of ``step`` are already sent to it)."""
        me = snapshot.vehicles[self.id]
        received = self.sharing.receive(step)
        shared = received.picture
        views = views_of(self.id, observations)
        mine = node_views.get(self.id, NodeView(self.kind.empty(), self.kind.empty()))
        estimate, clear = self.fusion.step(tracks, shared, views, mine.visible)
        timer.lap("sharing_fusion")
        possible = self.known.update(step, observations, estimate, clear)
        own = tracks.get(self.id)
        unknown = self.unobserved.update(
            step, mine.visible, received.fresh_views,
            [*received.ended, *(own.ended_at(step) if own is not None else ())])
        timer.lap("occupancy")
        paths = self.known.paths
        releases = self.context.releases(snapshot.signals)
        offs = {} if self.claims is None else self.claims.update(
            snapshot.time, possible, releases, estimate.flags.inconsistent)
        sources = {key: Source(region, estimate.fused.get(key) if self.known.with_states
                               else None, paths.get(key), offs.get(key, ()))
                   for key, region in possible.items()}
        unobserved = Source(unknown, path=self.unobserved.path)
        picture = assess(
            self.context, me.footprint.front.position, me.speed,
            mine.occluded, unobserved, list(sources.values()),
            [source for key, source in sources.items() if key in estimate.in_view],
            in_view_beyond=not self.known.beyond.isdisjoint(estimate.in_view),
            floors=self.arrivals.floors(step, estimate.flags.inconsistent),
            signals=snapshot.signals,
            releases=releases,
            route_m=me.route_m,
        )
        self.arrivals.keep(step, picture, estimate.flags.inconsistent)
        decision = self.policy.decide(
            picture, fallback_floor(estimate.flags.inconsistent, self.controller))
        return EgoStep(self.id, shared, estimate, possible, unknown, self.context.window,
                       picture, decision, (unobserved, *sources.values()))

"""The stages of a simulation step between the world's snapshot and the controller's picture.

Each stage takes what the previous ones produced and returns its own output; none reaches back
into another's state. Sets are zonotopes (:mod:`sse_cosim.sets`), regions of one
:class:`~sse_cosim.regions.RegionKind` in network coordinates (m).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Generic, Protocol

import numpy as np

from sse_cosim.estimation.anonymous_fusion import AnonymousFusionCentre
from sse_cosim.estimation.association import AnonymousDetection
from sse_cosim.estimation.flags import disagrees
from sse_cosim.estimation.fusion_centre import BusEstimate, FusionCentre
from sse_cosim.estimation.kalman import KalmanTracker, all_detections
from sse_cosim.estimation.motion import MotionModel
from sse_cosim.estimation.observer import (
    LocalObservers,
    LocalTracks,
    NodeInput,
    NodeScan,
    Track,
)
from sse_cosim.estimation.occupancy import ClearRegion, EndedTrack, OccupancyTracker
from sse_cosim.estimation.settings import EstimatorSettings
from sse_cosim.estimation.v2x import Message, SharedPicture, V2XLink
from sse_cosim.regions import Region, RegionKind
from sse_cosim.sensors import SensorObservation, SensorSpec, observe
from sse_cosim.sensors.faults import FaultInjector
from sse_cosim.sets import Strips, portable
from sse_cosim.world.snapshot import Snapshot

Observations = dict[str, SensorObservation]  # sensor name -> its observation at this step
Tracks = Mapping[str, LocalTracks]  # node -> pedestrian id (or track key) -> track


def sense(snapshot: Snapshot, specs: Mapping[str, SensorSpec], faults: FaultInjector,
          rng: np.random.Generator, kind: RegionKind) -> Observations:
    """Every sensor's observation (visibility as regions of ``kind``, detections, strips
    |H x - y| <= r, paper eqs. senmodel and strip), as the scenario's injected faults distort
    it."""
    faults.begin_step(snapshot.time)
    return faults.corrupt_observations(snapshot, observe(snapshot, specs, rng, regions=kind),
                                       kind)


@dataclass(frozen=True)
class NodeView:
    """What one node's sensors see now, together: the union of their visible regions and of
    their occluded ones."""

    visible: Region
    occluded: Region


def views_by_node(observations: Observations, kind: RegionKind) -> dict[str, NodeView]:
    """Node -> the union of its present sensors' views, for every node with a sensor in the
    scene (each union made once a step: the node's message and its own picture use it)."""
    present: dict[str, list[SensorObservation]] = {}
    for obs in observations.values():
        if obs.pose is not None:
            present.setdefault(obs.node, []).append(obs)
    return {node: NodeView(kind.union_all(o.visible for o in found),
                           kind.union_all(o.occluded for o in found))
            for node, found in present.items()}


def detections_by_node(observations: Observations) -> dict[str, dict[str, dict[str, Strips]]]:
    """Node -> pedestrian id -> sensor name -> the strips of that node's sensors that see it;
    every node with a sensor in the scene is a key (with no pedestrian if it sees nobody)."""
    result: dict[str, dict[str, dict[str, Strips]]] = {}
    for obs in observations.values():
        if obs.pose is not None:
            result.setdefault(obs.node, {})
        for person_id, detection in obs.detections.items():
            result.setdefault(obs.node, {}).setdefault(person_id, {})[obs.sensor] = \
                detection.strips
    return result


def scans_by_node(observations: Observations) -> dict[str, NodeScan]:
    """Node -> its sensors' detections without ids (sensor by sensor, each in the snapshot's
    order of persons) and their visible regions; every node with a sensor in the scene is a
    key. The person ids of the observations stay here: they never reach the estimation."""
    detections: dict[str, list[AnonymousDetection]] = {}
    visible: dict[str, dict[str, Region]] = {}
    for obs in observations.values():
        if obs.pose is not None:
            visible.setdefault(obs.node, {})[obs.sensor] = obs.visible
        detections.setdefault(obs.node, []).extend(
            AnonymousDetection(obs.sensor, d.strips) for d in obs.detections.values())
    return {node: NodeScan(tuple(detections[node]), regions)
            for node, regions in visible.items()}


class FirstLevel(Generic[NodeInput]):
    """Every node's observer fed from the observations (``inputs``: by id or anonymous)."""

    def __init__(self, observers: LocalObservers[NodeInput],
                 inputs: Callable[[Observations], Mapping[str, NodeInput]]) -> None:
        self.observers = observers
        self.inputs = inputs

    def step(self, step: int, observations: Observations) -> dict[str, LocalTracks]:
        """Node -> track key -> its local track at ``step`` (and those it ended lately)."""
        return self.observers.step(step, self.inputs(observations))


def first_level(association: str, nodes: Iterable[str], model: MotionModel,
                settings: EstimatorSettings, kind: RegionKind) -> FirstLevel:
    """The first fusion level of ``estimator.association``: ``labelled`` (tracks by person
    id) or ``anonymous`` (node-local tracks from anonymous detections)."""
    if association == "anonymous":
        return FirstLevel(LocalObservers.anonymous(nodes, model, settings, kind), scans_by_node)
    return FirstLevel(LocalObservers.labelled(nodes, model, settings), detections_by_node)


def views_of(node: str, observations: Observations) -> list[SensorObservation]:
    """The observations of ``node``'s sensors."""
    return [o for o in observations.values() if o.node == node]


@dataclass(frozen=True)
class Received:
    """What reached the bus over V2X by this step.

    ``picture``: every sender's newest message brought to this step; ``fresh_views``: the
    visible regions of the messages delivered now that were seen exactly the link's latency
    ago (the unobserved area places them at that step; a view delayed longer by a link fault
    is left out rather than placed at the wrong step); ``ended``: the tracks the messages
    delivered now hand over to the unobserved area (:class:`~sse_cosim.estimation.v2x.V2XLink`).
    """

    picture: SharedPicture
    fresh_views: list[Region]
    ended: list[EndedTrack]


@dataclass(frozen=True)
class Outgoing:
    """A node's message of one step, the sender's position (m, shape (2,)) and the steps its
    injected link faults add to the delivery."""

    message: Message
    position: np.ndarray
    extra_latency_steps: int


def outgoing(step: int, snapshot: Snapshot, observations: Observations,
             views: Mapping[str, NodeView], tracks: Tracks, faults: FaultInjector,
             model: MotionModel) -> list[Outgoing]:
    """Every node's message of ``step``, built once for all receivers: each node in the scene
    whose message no loss burst takes sends its estimates (as its injected faults distort
    them), visible region, the keys of the tracks its sensors detect now (by id, those
    are the pedestrians it sees) and the tracks it ended lately."""
    result = []
    for node, node_tracks in tracks.items():
        node_obs = [o for o in views_of(node, observations) if o.pose is not None]
        if not node_obs or faults.link_lost(node):
            continue
        estimates = faults.corrupt_estimates(
            node, {pid: t.estimate for pid, t in node_tracks.items()}, snapshot, model)
        message = Message(
            node, step, estimates, views[node].visible,
            frozenset(key for key, t in node_tracks.items() if t.detected),
            disagrees(node_tracks.values()), node_tracks.ended, node_tracks.ended_since,
        )
        result.append(Outgoing(message, node_obs[0].pose.position, faults.extra_latency(node)))
    return result


class Sharing:
    """V2X to one automated vehicle (``receiver``, its id): every other node's message
    (:func:`outgoing`) over a link with the scenario's (and the injected) range, latency and
    losses."""

    def __init__(self, link: V2XLink, model: MotionModel, receiver: str) -> None:
        self.receiver = receiver
        self.link = link
        self.model = model

    def send(self, receiver_xy: np.ndarray, messages: Sequence[Outgoing]) -> None:
        """Queue the messages of the other nodes, at their distance to the receiver, its front
        at ``receiver_xy`` (2,) now."""
        for out in messages:
            if out.message.sender != self.receiver:
                self.link.send(out.message, float(portable.hypot(*(out.position - receiver_xy))),
                               out.extra_latency_steps)

    def receive(self, step: int) -> Received:
        """Deliver what is due by ``step``."""
        delivered = self.link.deliver(step)
        latency = self.link.config.latency_steps
        return Received(self.link.picture(step, self.model),
                        [m.visible_region for m in delivered if step - m.sent_step == latency],
                        self.link.take_ended())


def clear_regions(
    bus_views: Sequence[SensorObservation], own: Mapping[str, Track], shared: SharedPicture
) -> dict[str, list[ClearRegion]]:
    """Pedestrian id -> the regions seen without it: by the bus's sensors now, and by every
    sender that did not detect it (negative information), for every pedestrian the bus or a
    sender knows of."""
    return {
        pid: [ClearRegion(o.visible, 0) for o in bus_views if pid not in o.detections]
        + shared.clear_of(pid)
        for pid in own.keys() | shared.estimates.keys()
    }


def detected_now(own: Mapping[str, Track], shared: SharedPicture) -> frozenset[str]:
    """Pedestrians the bus detects now or a sender detected in its newest message."""
    return frozenset(pid for pid, t in own.items() if t.detected).union(
        *shared.detected.values())


Clear = dict[str, list[ClearRegion]]  # fused key -> the regions seen without its pedestrians


class SecondLevel(Protocol):
    """An automated vehicle's fusion of its own and the received tracks, and the regions seen
    without the pedestrians of each fused set (negative information)."""

    def step(self, tracks: Tracks, shared: SharedPicture, views: Sequence[SensorObservation],
             seen: Region) -> tuple[BusEstimate, Clear]:
        """``views``: the vehicle's sensors' observations now; ``seen``: their visible
        regions' union."""
        ...


class LabelledFusion:
    """By person id: the screen (vote, probation), Proposition 2 per pedestrian, flags."""

    def __init__(self, centre: FusionCentre) -> None:
        self.centre = centre

    def step(self, tracks: Tracks, shared: SharedPicture, views: Sequence[SensorObservation],
             seen: Region) -> tuple[BusEstimate, Clear]:
        own = tracks[self.centre.node]
        clear = clear_regions(views, own, shared)
        return self.centre.step(tracks, shared, clear, detected_now(own, shared)), clear


class AnonymousFusion:
    """Anonymous tracks, fused only where they certainly hold the same pedestrians."""

    def __init__(self, centre: AnonymousFusionCentre) -> None:
        self.centre = centre

    def step(self, tracks: Tracks, shared: SharedPicture, views: Sequence[SensorObservation],
             seen: Region) -> tuple[BusEstimate, Clear]:
        own = tracks.get(self.centre.node, {})
        return self.centre.step(tracks, shared, seen, detected_now(own, shared))


def second_level(association: str, model: MotionModel, settings: EstimatorSettings,
                 fusion_method: str, sensors: Iterable[str], node: str,
                 kind: RegionKind) -> SecondLevel:
    """Automated vehicle ``node``'s second fusion level of ``estimator.association``."""
    if association == "anonymous":
        return AnonymousFusion(AnonymousFusionCentre(model, settings, fusion_method, sensors,
                                                     node, kind))
    return LabelledFusion(FusionCentre(model, settings, fusion_method, sensors, node, kind))


class KnownRegions(Protocol):
    """Where each known pedestrian can be (pedestrian id -> region), for the controller;
    ``beyond``: the keys whose pedestrian may instead be outside the tracked window."""

    beyond: frozenset[str]
    with_states: bool  # whether each region is about the fused state set of the same key

    @property
    def paths(self) -> Mapping[str, Region]:
        """Pedestrian id -> its path region at the last update, where one is known (the
        region the motion assumption bounds; the returned region is grown from it)."""
        ...

    def update(self, step: int, observations: Observations, estimate: BusEstimate,
               clear: Mapping[str, Sequence[ClearRegion]]) -> dict[str, Region]: ...


class RefinedRegions:
    """The fused sets refined with negative information
    (:class:`~sse_cosim.estimation.occupancy.OccupancyTracker`). When the bus's picture turns
    inconsistent the refinement's history is forgotten: it may hold a faulty source. Without
    ``history`` it is forgotten every step: a fused track of anonymous tracks names no
    pedestrian, and may hold another one at the next step (a merge, or a newcomer inside its
    set), whom the previous step's region need not hold."""

    with_states = True  # each region refines the fused set of its key

    def __init__(self, tracker: OccupancyTracker, history: bool = True) -> None:
        self.tracker = tracker
        self.history = history
        self._was_inconsistent = False

    def update(self, step: int, observations: Observations, estimate: BusEstimate,
               clear: Mapping[str, Sequence[ClearRegion]]) -> dict[str, Region]:
        inconsistent = estimate.flags.inconsistent
        if not self.history or (inconsistent and not self._was_inconsistent):
            self.tracker.forget()
        self._was_inconsistent = inconsistent
        return self.tracker.update(step, estimate.fused, clear)

    @property
    def beyond(self) -> frozenset[str]:
        return self.tracker.beyond

    @property
    def paths(self) -> Mapping[str, Region]:
        return self.tracker.paths


class KalmanRegions:
    """The baseline: each pedestrian's 3-sigma ellipse of a Kalman filter over every node's
    detections (:mod:`sse_cosim.estimation.kalman`), in place of the refined sets."""

    beyond: frozenset[str] = frozenset()  # its ellipses are not kept in a window
    with_states = False  # its ellipses are not the fused sets' (baseline, not guaranteed)
    paths: Mapping[str, Region] = {}  # an ellipse is of positions: no path region

    def __init__(self, tracker: KalmanTracker, kind: RegionKind) -> None:
        self.tracker = tracker
        self.kind = kind

    def update(self, step: int, observations: Observations, estimate: BusEstimate,
               clear: Mapping[str, Sequence[ClearRegion]]) -> dict[str, Region]:
        self.tracker.step(step, all_detections(observations.values()))
        return self.tracker.regions(self.kind)


def known_regions(filter_name: str, model: MotionModel, kind: RegionKind, walkable: Region,
                  window: Region, history: bool = True) -> KnownRegions:
    """The region stage of ``estimator.filter``: ``zonotope`` or ``kalman``; refined regions
    are kept in the tracked ``window``; ``history``: whether they carry a fused set's key from
    one step to the next (false for anonymous tracks, :class:`RefinedRegions`)."""
    if filter_name == "kalman":
        return KalmanRegions(KalmanTracker(model), kind)
    return RefinedRegions(OccupancyTracker(model, kind, walkable, window), history)

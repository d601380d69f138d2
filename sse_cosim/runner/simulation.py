"""One co-simulation run: SUMO, sensors, local observers, V2X, fusion, control, in that order.

Data flows one way through a step:

1. the SUMO snapshot (footprints, speeds, the pedestrian's true position);
2. sensors: visibility, detections, strips -- as the scenario's injected faults distort them;
3. every node's observer: predict, leave out strips inconsistent with the prediction and the
   other sensors, correct with the rest (Proposition 1), reduce;
4. V2X: every other node sends the bus its estimates and visible region;
5. the bus screens its own and the received estimates (a consistent majority, negative
   information; :mod:`sse_cosim.estimation.bus_screen`), fuses those it keeps
   (Proposition 2), refines where each known pedestrian can be and where an undetected one
   may be (negative information);
6. the situational picture; 7. the speed level (no faster than the fallback level while the
   picture is inconsistent), set back into SUMO.

The true position is checked against every node's set and the fused set at every step.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

import numpy as np
import shapely

from sse_cosim.control.picture import Picture, SceneContext, assess
from sse_cosim.control.speed import SpeedLevel, fallback_floor, make_policy
from sse_cosim.estimation.bus_fusion import fuse_at_bus
from sse_cosim.estimation.bus_screen import BusScreen, BusScreener
from sse_cosim.estimation.flags import StepFlags, step_flags
from sse_cosim.estimation.kalman import KalmanTracker, all_detections
from sse_cosim.estimation.motion import MotionModel
from sse_cosim.estimation.observer import EstimatorSettings, NodeObserver, Track
from sse_cosim.estimation.occupancy import (
    ClearRegion,
    OccupancyTracker,
    UnobservedArea,
)
from sse_cosim.estimation.v2x import Message, SharedPicture, V2XLink
from sse_cosim.runner.timing import NoTimer, StageTimer
from sse_cosim.scenario.model import BUS_NODE, Scenario
from sse_cosim.sensors import SensorObservation, observe, specs_from_scenario
from sse_cosim.sensors.faults import FaultInjector, FaultStatus
from sse_cosim.sets import Strips, Zonotope
from sse_cosim.world.roadmap import RoadMap
from sse_cosim.world.snapshot import Snapshot
from sse_cosim.world.sumo import SumoWorld

CONTAINMENT_TOLERANCE = 1e-7


@dataclass(frozen=True)
class StepResult:
    """Everything one step produced, handed to the recorder."""

    step: int
    snapshot: Snapshot
    observations: dict[str, SensorObservation]
    tracks: dict[str, dict[str, Track]]  # node -> pedestrian id -> track
    shared: SharedPicture
    unobserved: shapely.Geometry  # walkable area where an undetected pedestrian may be
    window: shapely.Geometry  # where hidden ground is tracked; outside, all counts as occupied
    fused: dict[str, Zonotope]  # pedestrian id -> fused state set
    possible: dict[str, shapely.Geometry]  # pedestrian id -> fused position set minus clear areas
    picture: Picture
    level: SpeedLevel
    commanded_speed: float
    model: MotionModel
    screen: BusScreen = field(default_factory=BusScreen)  # what the bus fused, whom it flagged
    flags: StepFlags = field(default_factory=StepFlags)  # per sensor and node
    faults: dict[str, FaultStatus] = field(default_factory=dict)  # injected fault -> status


StepCallback = Callable[[StepResult], None]


@dataclass(frozen=True)
class SimulationInfo:
    """How a run ended and the road map it ran on."""

    steps: int
    bus_arrived: bool
    roadmap: RoadMap


def simulate(
    scenario: Scenario, run_dir: Path, scenario_name: str, on_step: StepCallback,
    timer: StageTimer | NoTimer | None = None,
) -> SimulationInfo:
    """Run ``scenario`` in SUMO, calling ``on_step`` after every step.

    SUMO's own files (routes, logs) go to ``run_dir``. The bus leaving the network (end of
    its route) or the scenario's duration ends the run. ``timer`` (optional) is charged the
    time of each stage of each step (:mod:`sse_cosim.runner.timing`).
    """
    timer = timer or NoTimer()
    dt = scenario.simulation.step_length_s
    noise_rng, v2x_rng, fault_rng = (
        np.random.default_rng(s) for s in np.random.SeedSequence(scenario.simulation.seed).spawn(3)
    )
    model = MotionModel.from_config(scenario.estimator, dt)
    settings = EstimatorSettings(
        scenario.estimator.gain_method,
        scenario.estimator.reduction_method,
        scenario.estimator.max_generators,
    )
    observers = {node: NodeObserver(node, model, settings) for node in scenario.node_ids()}
    link = V2XLink(scenario.v2x, v2x_rng)
    kalman = KalmanTracker(model) if scenario.estimator.filter == "kalman" else None
    specs = specs_from_scenario(scenario)
    faults = FaultInjector(scenario, specs, fault_rng)
    screener = BusScreener(model, model.max_speed * dt)
    was_inconsistent = False
    n_steps = round(scenario.simulation.duration_s / dt)
    with SumoWorld(scenario, run_dir, scenario_name) as world:
        context = SceneContext.build(
            world.roadmap, scenario.bus.route_edges, scenario.bus, scenario.controller,
            model.max_speed, model.jitter, scenario.pedestrian.radius_m, dt,
        )
        policy = make_policy(context)
        new_occupancy = partial(OccupancyTracker, model, dt, context.walkable)
        occupancy = new_occupancy()
        # hidden ground is tracked near the crossing; outside the window it counts as occupied
        unobserved = UnobservedArea(
            context.walkable, model, dt, scenario.v2x.latency_steps, window=context.window,
        )
        for step in range(n_steps):
            timer.start()
            snapshot = world.step()
            bus = snapshot.role(BUS_NODE)
            if bus is None:
                if world.bus_arrived:
                    return SimulationInfo(step, True, world.roadmap)
                continue  # not inserted yet: world.step() refuses a bus that never is
            timer.lap("sumo")
            faults.begin_step(snapshot.time)
            observations = faults.corrupt_observations(
                snapshot, observe(snapshot, specs, noise_rng, want_regions=True))
            timer.lap("geometry")
            tracks = {
                node: observer.step(step, _detections_of(node, observations))
                for node, observer in observers.items()
            }
            timer.lap("local_fusion")
            _share(step, snapshot, scenario, observations, tracks, link, faults, model)
            delivered = link.deliver(step)
            shared = link.picture(step, model)
            bus_views = [o for o in observations.values() if o.node == BUS_NODE]
            clear = {
                pid: [ClearRegion(o.visible, 0) for o in bus_views if pid not in o.detections]
                + shared.clear_of(pid)
                for pid in tracks[BUS_NODE].keys() | shared.estimates.keys()
            }
            detected = frozenset(pid for pid, t in tracks[BUS_NODE].items() if t.detected) \
                .union(*shared.detected.values())
            screen = screener.screen({pid: t.estimate for pid, t in tracks[BUS_NODE].items()},
                                     shared.estimates, clear, detected)
            fused = fuse_at_bus(
                {pid: tracks[BUS_NODE][pid] for pid in screen.own}, screen.received,
                scenario.estimator.fusion_method, settings, model,
            )
            flags = step_flags(specs, tracks, screen,
                               any(m.inconsistent for m in link.latest.values()))
            if flags.inconsistent and not was_inconsistent:
                occupancy = new_occupancy()  # its history may hold a faulty source
            was_inconsistent = flags.inconsistent
            timer.lap("sharing_fusion")
            possible = occupancy.update(step, fused, clear)
            if kalman is not None:  # the baseline: the controller gets the KF's 3-sigma ellipses
                kalman.step(step, all_detections(observations.values()))
                possible = kalman.regions()
            unknown = unobserved.update(
                step, _union(o.visible for o in bus_views),
                # views delayed beyond the latency (a link fault) are not placed at the wrong step
                [m.visible_region for m in delivered
                 if step - m.sent_step == scenario.v2x.latency_steps],
            )
            timer.lap("occupancy")
            picture = assess(
                context,
                bus.footprint.front.position,
                bus.speed,
                _union(o.occluded for o in bus_views),
                unknown,
                list(possible.values()),
            )
            decision = policy.decide(
                picture, fallback_floor(flags.inconsistent, scenario.controller))
            level, commanded = decision.level, decision.command_mps
            world.set_bus_speed(commanded, emergency=level is SpeedLevel.EMERGENCY)
            timer.lap("control")
            on_step(
                StepResult(
                    step, snapshot, observations, tracks, shared, unknown, context.window,
                    fused, possible,
                    picture, level, commanded, model, screen, flags, faults.statuses(),
                )
            )
            timer.end_step("output")
        return SimulationInfo(n_steps, world.bus_arrived, world.roadmap)


def _detections_of(
    node: str, observations: dict[str, SensorObservation]
) -> dict[str, dict[str, Strips]]:
    """Pedestrian id -> sensor name -> the strips of ``node``'s sensors that see it."""
    result: dict[str, dict[str, Strips]] = {}
    for obs in observations.values():
        if obs.node == node:
            for person_id, detection in obs.detections.items():
                result.setdefault(person_id, {})[obs.sensor] = detection.strips
    return result


def _share(
    step: int,
    snapshot: Snapshot,
    scenario: Scenario,
    observations: dict[str, SensorObservation],
    tracks: dict[str, dict[str, Track]],
    link: V2XLink,
    faults: FaultInjector,
    model: MotionModel,
) -> None:
    """Every node other than the bus that is in the scene sends its picture to the bus
    (as its injected faults distort it, over a link with the injected losses and delays)."""
    bus_xy = snapshot.role(BUS_NODE).footprint.front.position
    for node, node_tracks in tracks.items():
        if node == BUS_NODE:
            continue
        node_obs = [o for o in observations.values() if o.node == node and o.pose is not None]
        if not node_obs or faults.link_lost(node):
            continue
        position = node_obs[0].pose.position
        region = _union(o.visible for o in node_obs)
        estimates = faults.corrupt_estimates(
            node, {pid: t.estimate for pid, t in node_tracks.items()}, snapshot, model)
        seen = frozenset(pid for o in node_obs for pid in o.detections)
        inconsistent = any(t.conflict or t.flagged for t in node_tracks.values())
        message = Message(node, step, estimates, region, seen, inconsistent)
        link.send(message, float(np.hypot(*(position - bus_xy))), faults.extra_latency(node))


def _union(geometries) -> shapely.Geometry:
    parts = [g for g in geometries if g is not None and not g.is_empty]
    return shapely.union_all(parts) if parts else shapely.Polygon()


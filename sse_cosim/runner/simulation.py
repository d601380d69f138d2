"""One co-simulation run: SUMO, sensors, local observers, V2X, fusion, control, in that order.

Data flows one way through a step (:mod:`sse_cosim.pipeline`):

1. the SUMO snapshot (footprints, speeds, the pedestrians' true positions);
2. sensors: visibility, detections, strips -- as the scenario's injected faults distort them;
3. every node's observer: predict, leave out strips inconsistent with the prediction and the
   other sensors, correct with the rest (Proposition 1), reduce;
4. V2X: every other node sends the bus its estimates and visible region;
5. the bus screens its own and the received estimates (a consistent majority, negative
   information), fuses those it keeps (Proposition 2) and flags the rest
   (:class:`~sse_cosim.estimation.fusion_centre.FusionCentre`);
6. it refines where each known pedestrian can be and where an undetected one may be
   (negative information);
7. the situational picture; 8. the speed level (no faster than the fallback level while the
   picture is inconsistent), set back into SUMO; 9. the step's record, to ``on_step``.

SUMO is touched through :class:`~sse_cosim.world.sumo.SumoWorld` only.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sse_cosim.control.picture import SceneContext, assess
from sse_cosim.control.speed import SpeedLevel, fallback_floor, make_policy
from sse_cosim.estimation.fusion_centre import FusionCentre
from sse_cosim.estimation.motion import MotionModel
from sse_cosim.estimation.observer import EstimatorSettings, LocalObservers
from sse_cosim.estimation.occupancy import UnobservedArea
from sse_cosim.estimation.v2x import V2XLink
from sse_cosim.pipeline.result import StepCallback, StepResult
from sse_cosim.pipeline.stages import (
    Sharing,
    clear_regions,
    detected_now,
    detections_by_node,
    known_regions,
    sense,
    union_or_empty,
    views_of,
)
from sse_cosim.runner.timing import NoTimer, StageTimer
from sse_cosim.scenario.model import Scenario, present
from sse_cosim.sensors import specs_from_scenario
from sse_cosim.sensors.faults import FaultInjector
from sse_cosim.world.roadmap import RoadMap
from sse_cosim.world.sumo import SumoWorld


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
    config = scenario.estimator
    model = MotionModel.from_config(config, dt)
    settings = EstimatorSettings(config.gain_method, config.reduction_method,
                                 config.max_generators)
    specs = specs_from_scenario(scenario)
    faults = FaultInjector(scenario, specs, fault_rng)
    observers = LocalObservers(scenario.node_ids(), model, settings)
    ego, vehicle = next(iter(present(scenario.automated).items()))
    sharing = Sharing(V2XLink(scenario.v2x, v2x_rng), faults, model, ego)
    centre = FusionCentre(model, settings, config.fusion_method, specs, dt, ego)
    n_steps = round(scenario.simulation.duration_s / dt)
    with SumoWorld(scenario, run_dir, scenario_name) as world:
        context = SceneContext.build(
            world.roadmap, vehicle.route_edges, vehicle, scenario.controller,
            model.max_speed, model.jitter, scenario.pedestrian_radius_m(), dt,
        )
        policy = make_policy(context)
        known = known_regions(config.filter, model, dt, context.walkable)
        # hidden ground is tracked near the crossings on the route; outside it counts as occupied
        unobserved = UnobservedArea(
            context.walkable, model, dt, scenario.v2x.latency_steps, window=context.window,
        )
        for step in range(n_steps):
            timer.start()
            snapshot = world.step()
            bus = snapshot.vehicles.get(ego)
            if bus is None:  # arrived (world.step() refuses a bus missing at its departure)
                return SimulationInfo(step, world.all_arrived, world.roadmap)
            timer.lap("sumo")
            observations = sense(snapshot, specs, faults, noise_rng)
            timer.lap("geometry")
            tracks = observers.step(step, detections_by_node(observations))
            timer.lap("local_fusion")
            sharing.send(step, snapshot, observations, tracks)
            received = sharing.receive(step)
            shared = received.picture
            bus_views = views_of(ego, observations)
            clear = clear_regions(bus_views, tracks[ego], shared)
            estimate = centre.step(tracks, shared, clear, detected_now(tracks[ego], shared))
            timer.lap("sharing_fusion")
            possible = known.update(step, observations, estimate, clear)
            unknown = unobserved.update(
                step, union_or_empty(o.visible for o in bus_views), received.fresh_views)
            timer.lap("occupancy")
            picture = assess(
                context, bus.footprint.front.position, bus.speed,
                union_or_empty(o.occluded for o in bus_views), unknown, list(possible.values()),
            )
            decision = policy.decide(
                picture, fallback_floor(estimate.flags.inconsistent, scenario.controller))
            world.set_speed(ego, decision.command_mps,
                                emergency=decision.level is SpeedLevel.EMERGENCY)
            timer.lap("control")
            on_step(StepResult(
                step, snapshot, observations, tracks, shared, unknown, context.window,
                estimate.fused, possible, picture, decision.level, decision.command_mps, model,
                estimate.screen, estimate.flags, faults.statuses(),
            ))
            timer.end_step("output")
        return SimulationInfo(n_steps, world.all_arrived, world.roadmap)

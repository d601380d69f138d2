"""One co-simulation run: SUMO, sensors, local observers, V2X, fusion, control, in that order.

Data flows one way through a step (:mod:`sse_cosim.pipeline`):

1. the SUMO snapshot (footprints, speeds, the pedestrians' true positions);
2. sensors: visibility, detections, strips -- as the scenario's injected faults distort them;
3. every node's observer: predict, leave out strips inconsistent with the prediction and the
   other sensors, correct with the rest (Proposition 1), reduce -- or, with
   ``estimator.association = "anonymous"``, associate the node's detections without ids
   with its tracks (:mod:`sse_cosim.estimation.association`);
4. V2X: every node sends every automated vehicle other than itself its estimates and visible
   region, over that vehicle's own link;
5. each automated vehicle (:class:`~sse_cosim.pipeline.ego.Ego`) screens its own and the
   received estimates (a consistent majority, negative information), fuses those it keeps
   (Proposition 2) and flags the rest (anonymous: fuses the tracks that certainly hold the
   same pedestrians, :mod:`sse_cosim.estimation.anonymous_fusion`); 6. it refines where each
   known pedestrian can be and where an undetected one may be (negative information); 7. its
   situational picture; 8. its speed level (no faster than the fallback level while its
   picture is inconsistent), set back into SUMO; 9. the step's record, to ``on_step``.

Random draws: the sensor noise, the first automated vehicle's link and the faults draw from
the seed's first three streams (so a run with one automated vehicle draws as it always did);
the links of further automated vehicles from the next ones. SUMO is touched through
:class:`~sse_cosim.world.sumo.SumoWorld` only.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from sse_cosim import regions
from sse_cosim.control.speed import SpeedLevel
from sse_cosim.estimation.motion import motion_model
from sse_cosim.estimation.settings import EstimatorSettings
from sse_cosim.pipeline.ego import Ego
from sse_cosim.pipeline.result import StepCallback, StepResult
from sse_cosim.pipeline.stages import first_level, outgoing, sense, views_by_node
from sse_cosim.runner.timing import NoTimer, StageTimer
from sse_cosim.scenario.model import Scenario, present
from sse_cosim.sensors import specs_from_scenario
from sse_cosim.sensors.faults import FaultInjector
from sse_cosim.world.roadmap import RoadMap
from sse_cosim.world.sumo import SumoWorld


@dataclass(frozen=True)
class SimulationInfo:
    """How a run ended (steps recorded; per automated vehicle whether it reached the end of
    its route), the road map and the scenario it ran with, and the breaks of the assumptions
    its study lists in ``breaks_assumptions``, by summary key (``SumoWorld.breaks``)."""

    steps: int
    arrived: dict[str, bool]
    roadmap: RoadMap
    scenario: Scenario  # as run: with what the world resolved (the measured jitter)
    breaks: dict[str, Any] = field(default_factory=dict)


def simulate(
    scenario: Scenario, run_dir: Path, scenario_name: str, on_step: StepCallback,
    timer: StageTimer | NoTimer | None = None,
    on_start: Callable[[Scenario], None] | None = None,
) -> SimulationInfo:
    """Run ``scenario`` in SUMO, calling ``on_step`` after every step.

    SUMO's own files (routes, logs) go to ``run_dir``. Every automated vehicle having left
    the network (end of its route) or the scenario's duration ends the run. ``timer``
    (optional) is charged the time of each stage of each step (:mod:`sse_cosim.runner.timing`).
    The world resolves what the scenario leaves to the network (the position jitter its
    walkers need, :mod:`sse_cosim.world.walker_jitter`); the estimator runs with that
    scenario, which ``on_start`` (optional) receives before the first step and
    :class:`SimulationInfo` returns. A pedestrian that leaves the estimator's motion model
    stops the run (:class:`~sse_cosim.errors.AssumptionBroken`, raised by ``world.step()``
    before the step's snapshot reaches the estimator) unless the scenario lists
    ``pedestrian_speed``; so does any other checked assumption (:mod:`sse_cosim.world.checks`).
    """
    timer = timer or NoTimer()
    with SumoWorld(scenario, run_dir, scenario_name) as world:
        scenario = world.scenario
        if on_start is not None:
            on_start(scenario)
        dt = scenario.simulation.step_length_s
        automated = list(present(scenario.automated))
        streams = np.random.SeedSequence(scenario.simulation.seed).spawn(2 + len(automated))
        noise_rng, first_link_rng, fault_rng, *link_rngs = map(np.random.default_rng, streams)
        config = scenario.estimator
        model = motion_model(config, dt)
        settings = EstimatorSettings(config.gain_method, config.reduction_method,
                                     config.max_generators)
        specs = specs_from_scenario(scenario)
        faults = FaultInjector(scenario, specs, fault_rng)
        kind = regions.kind(config.regions)
        observers = first_level(config.association, scenario.node_ids(), model, settings, kind)
        n_steps = round(scenario.simulation.duration_s / dt)
        egos = [Ego(vid, scenario, world.roadmap, model, settings, specs, rng, kind,
                    scenario_name)
                for vid, rng in zip(automated, [first_link_rng, *link_rngs], strict=True)]
        for step in range(n_steps):
            timer.start()
            snapshot = world.step()
            if world.all_arrived:  # (world.step() refuses a vehicle missing at its departure)
                return SimulationInfo(step, _arrivals(world, automated), world.roadmap,
                                      scenario, world.breaks)
            active = [ego for ego in egos if ego.id in snapshot.vehicles]
            timer.lap("sumo")
            observations = sense(snapshot, specs, faults, noise_rng, kind)
            views = views_by_node(observations, kind)
            timer.lap("geometry")
            tracks = observers.step(step, observations)
            timer.lap("local_fusion")
            # every vehicle still to drive listens, one not yet inserted from where SUMO will
            # insert it: inserted at speed, it starts from the messages in the air
            listening = [ego for ego in egos if not world.arrived(ego.id)]
            if listening:  # building a message marks its faults (docs/faults.md): when sent
                messages = outgoing(step, snapshot, observations, views, tracks, faults, model)
                for ego in listening:
                    ego.sharing.send(ego.front(snapshot), messages)
            results = {ego.id: ego.step(step, snapshot, observations, views, tracks, timer)
                       for ego in active}
            for vid, result in results.items():
                world.set_speed(vid, result.decision.command_mps,
                                emergency=result.decision.level is SpeedLevel.EMERGENCY)
            timer.lap("control")
            on_step(StepResult(step, snapshot, observations, tracks, model, faults.statuses(),
                               results))
            timer.end_step("output")
        return SimulationInfo(n_steps, _arrivals(world, automated), world.roadmap, scenario,
                              world.breaks)


def _arrivals(world: SumoWorld, automated: list[str]) -> dict[str, bool]:
    return {vid: world.arrived(vid) for vid in automated}

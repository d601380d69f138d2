"""Item 3: cost per step in a synthetic scene (no SUMO) against pedestrians × sensors.

Snapshots are built by hand on the real road map: the bus drives at 10 m/s towards the
crossing past the parked truck, P pedestrians walk on the sidewalks near the crossing, and
S sensors watch: the bus's front sensor plus S - 1 road-side units (one node each) spread
around the crossing. Every step runs the loop's stages with the library's functions:
sensors with regions, one plain observer per node (predict, Prop. 1, reduce), every unit's
message (estimates, visible region) to the bus with one step of latency, fusion at the bus,
negative information (occupancy, unobserved area) and the picture.
"""

from __future__ import annotations

import math
import time

import numpy as np

from benchmarks.common import PlainObserver, fuse_inputs, median
from benchmarks.loop_cost import profile_call
from sse_cosim.control.picture import SceneContext, Source, assess
from sse_cosim.estimation.motion import motion_model
from sse_cosim.estimation.occupancy import ClearRegion, OccupancyTracker, UnobservedArea
from sse_cosim.pipeline.stages import views_by_node
from sse_cosim.regions import Region
from sse_cosim.regions import kind as regions_kind
from sse_cosim.scenario.model import AutomatedVehicle, Controller, Estimator
from sse_cosim.sensors import Camera, SensorSpec, observe
from sse_cosim.world.network import build_network
from sse_cosim.world.roadmap import load_roadmap
from sse_cosim.world.snapshot import Footprint, PersonState, Pose, Snapshot, VehicleState

PEDESTRIANS = (1, 4, 16, 64)
SENSORS = (1, 2, 4, 8, 16)
DT = 0.1
JITTER_M = 0.65  # about the paper road's measured jitter; the cost does not depend on it


def _specs(count: int) -> dict[str, SensorSpec]:
    specs = {"bus_front": SensorSpec("bus_front", "bus", Camera(range_m=60.0))}
    for i in range(count - 1):
        angle = 2 * math.pi * i / max(count - 1, 1)
        x, y = 200 + 16 * math.cos(angle), 11 * math.sin(angle)
        heading = math.atan2(-y, 200 - x)  # looking at the crossing
        camera = Camera(range_m=40.0, noise_bound_m=(1.0, 1.0))
        specs[f"rsu{i}"] = SensorSpec(f"rsu{i}", f"rsu{i}", camera, static_pose=Pose(x, y, heading))
    return specs


def _pedestrians(count: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Start positions on both sidewalks near the crossing, and walking velocities."""
    x = rng.uniform(175, 225, count)
    y = np.where(rng.random(count) < 0.5, -7.0, 7.0) + rng.uniform(-0.6, 0.6, count)
    v = np.stack([rng.choice([-1.2, 1.2], count), np.zeros(count)], axis=1)
    return np.stack([x, y], axis=1), v


def _snapshot(step: int, bus_x: float, people: np.ndarray) -> Snapshot:
    bus = VehicleState("bus", "automated", Footprint(Pose(bus_x, -1.6, 0.0), 12.0, 2.55), 10.0)
    truck = VehicleState("truck", "parked", Footprint(Pose(186.0, -4.8, 0.0), 10.0, 2.5), 0.0)
    persons = {f"p{i}": PersonState(f"p{i}", (float(x), float(y)), 1.2)
               for i, (x, y) in enumerate(people)}
    return Snapshot(step * DT, {"bus": bus, "truck": truck}, persons)


def measure(pedestrians: int, sensors: int, steps: int, warmup: int, roadmap) -> float:
    """Median seconds per step (after ``warmup`` steps) of one configuration."""
    rng = np.random.default_rng(pedestrians * 100 + sensors)
    config = Estimator(position_jitter_m=JITTER_M)
    model = motion_model(config, DT)
    specs = _specs(sensors)
    nodes = sorted({s.node for s in specs.values()})
    observers = {n: PlainObserver(model, config.gain_method) for n in nodes}
    kind = regions_kind()
    context = SceneContext.build(roadmap, ["WC", "CE"], AutomatedVehicle(), Controller(), model,
                                 0.3, DT, kind)
    occupancy = OccupancyTracker(model, kind, context.walkable, context.window)  # as in the loop
    unobserved = UnobservedArea(context.walkable, model, 1, kind, window=context.window)
    people, velocity = _pedestrians(pedestrians, rng)
    inbox: dict[str, tuple[int, dict, Region]] = {}
    samples = []
    for step in range(warmup + steps):
        start = time.perf_counter()
        bus_x = 120.0 + 10.0 * DT * step
        snapshot = _snapshot(step, bus_x, people)
        observations = observe(snapshot, specs, rng, regions=kind)
        views = views_by_node(observations, kind)
        by_node: dict[str, dict[str, list]] = {n: {} for n in nodes}
        for obs in observations.values():
            for pid, det in obs.detections.items():
                by_node[obs.node].setdefault(pid, []).append(det.strips)
        estimates = {n: observers[n].step(step, by_node[n]) for n in nodes}
        delivered = [(n, *inbox[n]) for n in sorted(inbox)]  # sent last step
        fused = {}
        for pid in set(estimates["bus"]) | {p for _, _, est, _ in delivered for p in est}:
            inputs = [estimates["bus"][pid]] if pid in estimates["bus"] else []
            inputs += [model.predict(est[pid], step - sent) for _, sent, est, _ in delivered
                       if pid in est]
            fused[pid] = fuse_inputs(inputs, config.fusion_method, model)
        bus_views = [o for o in observations.values() if o.node == "bus"]
        clear = {pid: [ClearRegion(o.visible, 0) for o in bus_views if pid not in o.detections]
                 + [ClearRegion(region, step - sent) for _, sent, est, region in delivered
                    if pid not in est] for pid in fused}
        possible = occupancy.update(step, fused, clear)
        unknown = unobserved.update(step, views["bus"].visible, [r for _, _, _, r in delivered])
        paths = occupancy.paths
        assess(context, np.array([bus_x, -1.6]), 10.0, views["bus"].occluded,
               Source(unknown, path=unobserved.path),
               [Source(region, fused.get(pid), paths.get(pid))
                for pid, region in possible.items()])
        inbox = {n: (step, estimates[n], views[n].visible) for n in nodes if n != "bus"}
        people = people + velocity * DT
        if step >= warmup:
            samples.append(time.perf_counter() - start)
    return median(samples)


def run(pedestrians=PEDESTRIANS, sensors=SENSORS, steps: int = 8, warmup: int = 3,
        profile: bool = True) -> dict:
    roadmap = load_roadmap(build_network("sumo_net"))
    grid = []
    for p in pedestrians:
        for s in sensors:
            grid.append({"pedestrians": p, "sensors": s,
                         "us_per_step": 1e6 * measure(p, s, steps, warmup, roadmap)})
    largest = max(grid, key=lambda g: (g["pedestrians"] * g["sensors"], g["pedestrians"]))
    # where the largest configuration's time goes: its steps (warm-up included) profiled
    text = profile_call(lambda: measure(largest["pedestrians"], largest["sensors"], steps,
                                        warmup, roadmap), "tottime", 20) if profile else ""
    x = np.log([g["pedestrians"] * g["sensors"] for g in grid])
    y = np.log([g["us_per_step"] for g in grid])
    design = np.column_stack([np.ones_like(x), x])
    exponent = float(np.linalg.lstsq(design, y, rcond=None)[0][1])
    px = np.column_stack([np.ones(len(grid)), np.log([g["pedestrians"] for g in grid]),
                          np.log([g["sensors"] for g in grid])])
    per_axis = np.linalg.lstsq(px, y, rcond=None)[0]
    # marginal cost: the fixed part of a step (1 x 1) removed before the fit
    base = min(g["us_per_step"] for g in grid)
    marginal = [(g["pedestrians"] * g["sensors"], g["us_per_step"] - base) for g in grid
                if g["us_per_step"] - base > 0 and g["pedestrians"] * g["sensors"] > 1]
    marginal_exponent = None
    if len(marginal) >= 2:
        mx = np.log([m[0] for m in marginal])
        my = np.log([m[1] for m in marginal])
        marginal_exponent = float(np.polyfit(mx, my, 1)[0])
    return {"grid": grid, "largest": largest, "profile_largest": text,
            "exponent_in_pedestrians_x_sensors": exponent,
            "exponent_pedestrians": float(per_axis[1]), "exponent_sensors": float(per_axis[2]),
            "marginal_exponent": marginal_exponent, "steps": steps, "warmup": warmup}

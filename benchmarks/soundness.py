"""Item 6: the soundness campaign. Zero containment violations over >= 100,000 node-steps.

Synthetic measurement streams (no SUMO, so that many fit in the time budget): a pedestrian's
path s moves by at most v_max·dt per axis and step (often exactly on the bound), its measured
position is p = s + e with |e| <= the jitter (often on the bound), and three sensors at random
poses measure p with bounded noise, uniform or worst case (every component on its bound),
with bounds from 0.1 to 2 m, seeing the pedestrian in random on/off stretches. Each of the
three nodes runs the paper's observer (predict, Prop. 1, reduce) and the bus fuses its own set
with the others' sets of the previous step (one step of V2X latency). A *node-step* is one
set at one step: each node's local set, and the bus's fused set. Every one is re-checked by an
LP of its own (scipy HiGHS on G and c, not ``Zonotope.contains``): the path set must hold s
and the position set (C Z ⊕ box(eps)) must hold p.
"""

from __future__ import annotations

import itertools
import math
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context

import numpy as np

from benchmarks.common import PlainObserver, contains_lp_batch, fuse_inputs
from sse_cosim.estimation.motion import motion_model
from sse_cosim.scenario.model import Estimator
from sse_cosim.sensors.measurement import measure
from sse_cosim.world.snapshot import Pose

DT = 0.1
BOUNDS = (0.1, 0.5, 1.0, 2.0)
KINDS = ("uniform", "worst-case")
GAINS = ("volume", "frobenius", "enclose")
FUSIONS = ("strips", "frobenius", "volume", "enclose")
NODES = ("bus", "n1", "n2")
JITTER_M = 0.3  # the synthetic walker's jitter (a SUMO run measures its network's)


def stream(seed: int, bound: float, kind: str, gain: str, fusion: str, steps: int) -> dict:
    """One synthetic stream; counts of node-steps checked and of violations."""
    rng = np.random.default_rng(seed)
    config = Estimator(gain_method=gain, fusion_method=fusion, position_jitter_m=JITTER_M)
    model = motion_model(config, DT)
    step_bound = config.max_pedestrian_speed_mps * DT
    eps = config.position_jitter_m
    poses = {n: Pose(*rng.uniform(-20, 20, 2), rng.uniform(-math.pi, math.pi)) for n in NODES}
    ratio = rng.uniform(0.5, 1.0)
    bounds = {n: np.array([bound, bound * ratio])[rng.permutation(2)] for n in NODES}
    observers = {n: PlainObserver(model, gain) for n in NODES}
    visible = dict.fromkeys(NODES, True)
    s = np.zeros(2)
    previous: dict[str, object] = {}
    checks: list[tuple] = []
    labels: list[tuple[int, str]] = []
    for k in range(steps):
        if k:
            u = rng.uniform(-1, 1, 2)
            if rng.random() < 0.4:
                u = np.sign(u)  # on the speed bound (a corner of the box)
            s = s + step_bound * u
        e = rng.normal(size=2)
        e *= eps * (1.0 if rng.random() < 0.4 else rng.random()) / np.linalg.norm(e)
        p = s + e
        for n in NODES:
            if rng.random() < 0.08:
                visible[n] = not visible[n]
        if k == 0:
            visible["bus"] = True
        sets = {}
        for n in NODES:
            detections = {}
            if visible[n]:
                detections["ped"] = measure(poses[n], p[None, :], bounds[n], kind, rng)
            sets[n] = observers[n].step(k, detections).get("ped")
        inputs = [sets["bus"]] + [model.predict(previous[n], 1) for n in NODES[1:]
                                  if previous.get(n) is not None]
        fused = fuse_inputs([z for z in inputs if z is not None], fusion, model) \
            if any(z is not None for z in inputs) else None
        for name, z in [*sets.items(), ("fused", fused)]:
            if z is None:
                continue
            position = model.position(z)
            checks.append((z.center, z.generators, s.copy()))
            checks.append((position.center, position.generators, p.copy()))
            labels.append((k, name))
        previous = {n: sets[n] for n in NODES[1:]}
    answers = contains_lp_batch(checks)
    examples = []
    violations = 0
    for i, (k, name) in enumerate(labels):
        if not (answers[2 * i] and answers[2 * i + 1]):
            violations += 1
            if len(examples) < 5:
                examples.append({"seed": seed, "step": k, "set": name})
    return {"node_steps": len(labels), "violations": violations, "examples": examples}


def _job(args: tuple) -> dict:
    return stream(*args)


def run(node_steps: int = 100_000, steps: int = 200, workers: int = 2) -> dict:
    per_stream = steps * (len(NODES) + 1) * 0.85  # roughly: most nodes hold a set most steps
    count = max(1, math.ceil(node_steps / per_stream))
    combos = list(itertools.product(BOUNDS, KINDS, GAINS, FUSIONS))
    jobs = [(1000 + i, *combos[i % len(combos)], steps) for i in range(count)]
    if workers <= 1:
        results = [_job(job) for job in jobs]
    else:
        with ProcessPoolExecutor(max_workers=workers, mp_context=get_context("spawn")) as pool:
            results = list(pool.map(_job, jobs, chunksize=max(1, count // (4 * workers))))
    while sum(r["node_steps"] for r in results) < node_steps:  # top up to the target
        i = len(results)
        results.append(stream(1000 + i, *combos[i % len(combos)], steps))
    by_kind = {kind: sum(r["node_steps"] for r, j in zip(results, jobs, strict=False)
                         if j[2] == kind) for kind in KINDS}
    return {
        "node_steps": sum(r["node_steps"] for r in results),
        "violations": sum(r["violations"] for r in results),
        "streams": len(results),
        "steps_per_stream": steps,
        "noise_bounds_m": list(BOUNDS),
        "noise_kinds": list(KINDS),
        "gain_methods": list(GAINS),
        "fusion_methods": list(FUSIONS),
        "node_steps_by_noise_kind": by_kind,
        "examples": [x for r in results for x in r["examples"]][:10],
    }

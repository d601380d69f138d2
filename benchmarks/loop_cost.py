"""Item 1: cost per step of the co-simulation against libsumo alone and against bare SUMO through
the project's world, stage by stage; anonymous detections against labelled ones.

All configurations run in this process, one after another and interleaved over the repeats
(libsumo allows one open simulation at a time; closing it allows the next), so each ratio
is measured side by side on the same machine state.
"""

from __future__ import annotations

import cProfile
import io
import pstats
import sysconfig
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from benchmarks.common import median
from sse_cosim.reporting.recorder import RunRecorder
from sse_cosim.runner.simulation import simulate
from sse_cosim.runner.timing import STAGES, StageTimer
from sse_cosim.scenario.loader import load_scenario
from sse_cosim.scenario.model import Estimator, Scenario
from sse_cosim.world.sumo import CONFIG_FILE_NAME, SumoWorld
from sse_cosim.world.sumo_setup import libsumo

BUS = "bus"  # the automated vehicle's id (its node)

SCENARIO = "scenarios/s3_pedestrian.toml"
FUSION = Estimator().fusion_method  # the default fusion, the same in every configuration
ACTOR_VARS = (libsumo.VAR_POSITION, libsumo.VAR_ANGLE, libsumo.VAR_SPEED)
"""What libsumo alone reads of every vehicle and person each step."""


@dataclass(frozen=True)
class Config:
    """One configuration of the loop: the nodes' gain and how detections find their tracks
    (``estimator.association``)."""

    gain: str
    association: str = "labelled"

    def overrides(self) -> dict[str, str]:
        return {"estimator.gain_method": self.gain, "estimator.association": self.association}


DEFAULT = "default_enclose"  # the default methods, labelled detections
ANONYMOUS = "anonymous"  # the same with anonymous detections
CONFIGS = {
    "a_frobenius": Config("frobenius"),
    "b_cvxpy_frobenius": Config("cvxpy-frobenius"),
    "b_cvxpy_volume": Config("cvxpy-volume"),
    "volume": Config("volume"),
    DEFAULT: Config(Estimator().gain_method),
    ANONYMOUS: Config(Estimator().gain_method, "anonymous"),
}


def libsumo_alone(config: Path, steps: int) -> tuple[float, int, int]:
    """Seconds per step of libsumo by itself on a run's SUMO configuration ``config`` (its
    ``sumo.sumocfg``), ``steps`` steps, each reading every vehicle's and person's position,
    angle and speed: each actor subscribed once when it departs, every result of a domain in
    one call. Also how many vehicles and persons were read."""
    libsumo.start(["sumo", "-c", str(config)])
    vehicles: set[str] = set()
    persons: set[str] = set()
    try:
        start = time.perf_counter()
        for _ in range(steps):
            libsumo.simulationStep()
            for vid in libsumo.simulation.getDepartedIDList():
                libsumo.vehicle.subscribe(vid, ACTOR_VARS)
                vehicles.add(vid)
            for pid in libsumo.simulation.getDepartedPersonIDList():
                libsumo.person.subscribe(pid, ACTOR_VARS)
                persons.add(pid)
            libsumo.vehicle.getAllSubscriptionResults()
            libsumo.person.getAllSubscriptionResults()
        elapsed = time.perf_counter() - start
    finally:
        libsumo.close()
    return elapsed / steps, len(vehicles), len(persons)


def bare_sumo(scenario: Scenario, steps: int, folder: Path) -> float:
    """Seconds per step of SUMO through the project's world (``SumoWorld.step``): same network,
    routes and steps, the bus at its nominal speed, the snapshot built every step, no sensor
    layer."""
    with SumoWorld(scenario, folder, "bare") as world:
        elapsed, counted = 0.0, 0
        for _ in range(steps):
            start = time.perf_counter()
            snapshot = world.step()
            bus = snapshot.vehicles.get(BUS)
            if bus is not None:
                world.set_speed(BUS, scenario.automated[BUS].nominal_speed_mps)
            if bus is None and world.arrived(BUS):
                break
            elapsed += time.perf_counter() - start
            counted += bus is not None
    return elapsed / max(counted, 1)


def cosim(scenario: Scenario, folder: Path) -> tuple[float, dict[str, float], int]:
    """Seconds per step of the full loop (recorder included), µs per stage, steps. SUMO's
    configuration of the run is ``folder / CONFIG_FILE_NAME``."""
    timer = StageTimer()
    recorder = RunRecorder(scenario)
    simulate(scenario, folder, "bench", recorder, timer=timer, on_start=recorder.start)
    return sum(timer.totals.values()) / timer.steps, timer.per_step_us(), timer.steps


def profile_run(scenario: Scenario, folder: Path, top: int = 15) -> str:
    """cProfile of one full run: the functions with the largest cumulative time."""
    recorder = RunRecorder(scenario)
    return profile_call(lambda: simulate(scenario, folder, "profile", recorder,
                                         on_start=recorder.start), "cumulative", top)


def profile_call(call: Callable[[], object], order: str, top: int) -> str:
    """cProfile of ``call()``: the ``top`` functions by ``order`` (file paths relative to the
    Python environment or the current folder: no machine path)."""
    profiler = cProfile.Profile()
    profiler.enable()
    call()
    profiler.disable()
    out = io.StringIO()
    pstats.Stats(profiler, stream=out).sort_stats(order).print_stats(top)
    text = out.getvalue()
    for prefix in sorted({sysconfig.get_paths()["purelib"], str(Path.cwd())}, key=len,
                         reverse=True):
        text = text.replace(prefix + "/", "")
    lines = [line for line in text.splitlines() if line.strip()]
    start = next(i for i, line in enumerate(lines) if "ncalls" in line)
    return "\n".join(lines[start:])


def run(repeats: int = 3, configs: dict[str, Config] | None = None,
        duration_s: float | None = None, profile: bool = True) -> dict:
    """Every configuration of ``configs`` (at least :data:`DEFAULT`), bare SUMO through the
    world and libsumo alone on :data:`DEFAULT`'s SUMO configuration, ``repeats`` times
    interleaved; medians."""
    configs = CONFIGS if configs is None else configs
    overrides: dict[str, object] = {"estimator.fusion_method": FUSION}
    if duration_s is not None:
        overrides["simulation.duration_s"] = duration_s
    base = load_scenario(Path(SCENARIO), overrides)
    samples: dict[str, list[float]] = {"bare": [], "libsumo": [],
                                       **{name: [] for name in configs}}
    stages: dict[str, list[dict[str, float]]] = {name: [] for name in configs}
    steps: dict[str, int] = {}
    vehicles = persons = 0
    with tempfile.TemporaryDirectory(prefix="sse-bench-loop-") as tmp:
        folder = Path(tmp)
        for _ in range(repeats):
            for name, config in configs.items():
                scenario = load_scenario(Path(SCENARIO), {**overrides, **config.overrides()})
                per_step, per_stage, steps[name] = cosim(scenario, folder / name)
                samples[name].append(per_step)
                stages[name].append(per_stage)
            samples["bare"].append(bare_sumo(base, steps[DEFAULT], folder / "bare"))
            alone, vehicles, persons = libsumo_alone(folder / DEFAULT / CONFIG_FILE_NAME,
                                                     steps[DEFAULT])
            samples["libsumo"].append(alone)
        profiles = {name: profile_run(load_scenario(Path(SCENARIO), {
            **overrides, **configs[name].overrides()}), folder / f"profile_{name}")
            for name in (DEFAULT, ANONYMOUS) if profile and name in configs}
    dt = base.simulation.step_length_s
    bare, alone = median(samples["bare"]), median(samples["libsumo"])
    result = {
        "scenario": SCENARIO,
        "fusion_method": FUSION,
        "steps": steps[DEFAULT],
        "repeats": repeats,
        "libsumo_us_per_step": 1e6 * alone,
        "libsumo_actors_read": {"vehicles": vehicles, "persons": persons},
        "bare_us_per_step": 1e6 * bare,
        "bare_ratio_to_libsumo": bare / alone,
        "bare_real_time_factor": dt / bare,
        "configs": {},
        "profile_default_gain": profiles.get(DEFAULT, ""),
        "profile_anonymous": profiles.get(ANONYMOUS, ""),
    }
    for name, config in configs.items():
        per_step = median(samples[name])
        result["configs"][name] = {
            "gain_method": config.gain,
            "association": config.association,
            "steps": steps[name],
            "us_per_step": 1e6 * per_step,
            "ratio_to_libsumo": per_step / alone,
            "ratio_to_bare": per_step / bare,
            "real_time_factor": dt / per_step,
            "stages_us": {s: median([d.get(s, 0.0) for d in stages[name]]) for s in STAGES},
            "samples_us": [1e6 * v for v in samples[name]],
        }
    if "a_frobenius" in configs:
        a = result["configs"]["a_frobenius"]["us_per_step"]
        for name in configs:
            if name.startswith("b_"):
                result["configs"][name]["ratio_to_a"] = result["configs"][name]["us_per_step"] / a
    if ANONYMOUS in configs:
        anonymous = result["configs"][ANONYMOUS]
        anonymous["ratio_to_labelled"] = \
            anonymous["us_per_step"] / result["configs"][DEFAULT]["us_per_step"]
    return result

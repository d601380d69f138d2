"""Item 8: the safety campaign (``make safety``, ``sweeps/safety.toml``), projected.

The whole campaign takes hours on two cores, longer than a bench run may. This item plans it
as ``sse-cosim safety`` does (the same campaign file, the same planner, the same list of
runs; the planning is timed, as it is part of ``make safety``'s wall time), then times one
run of each scenario in one worker process, after a warm-up run that pays the worker's
start-up: the run in the middle of the scenario's list, at its full length, summary only, as
the campaign runs it. Each sample includes loading its scenario's network into the worker,
which the campaign pays once per worker, so the projection errs long.

The projection, in minutes on two cores: planning + (runs of each scenario x its sample run's
time) / the speed-up of two local workers over one, measured in item 4 of the same bench run
(without item 4: two workers counted as twice one, said so in the report).
"""

from __future__ import annotations

import tempfile
import time
from collections import Counter
from dataclasses import replace
from pathlib import Path

from sse_cosim.runner.safety import CampaignPlan, load_campaign, plan_campaign
from sse_cosim.runner.sweep import PlannedRun
from sse_cosim.runner.tasks import WorkerProcess

CAMPAIGN = Path("sweeps/safety.toml")
DURATION_PATH = "simulation.duration_s"


def samples(plan: CampaignPlan) -> dict[str, tuple[int, PlannedRun]]:
    """Per scenario (file stem, in plan order): its number of runs and the run in the middle
    of its list."""
    by_scenario: dict[str, list[PlannedRun]] = {}
    for run in plan.runs:
        by_scenario.setdefault(Path(run.scenario).stem, []).append(run)
    return {stem: (len(runs), runs[len(runs) // 2]) for stem, runs in by_scenario.items()}


def _cut(run: PlannedRun, duration_s: float | None) -> PlannedRun:
    """``run`` ending at ``duration_s`` (None: as planned)."""
    if duration_s is None:
        return run
    return replace(run, overrides={**run.overrides, DURATION_PATH: duration_s})


def run(quick: bool = False, duration_s: float | None = None) -> dict:
    """Plan the campaign (its ``[quick]`` subset with ``quick``), time one run per scenario
    (cut to ``duration_s`` if given) and return the figures the projection needs."""
    start = time.perf_counter()
    plan = plan_campaign(load_campaign(CAMPAIGN, quick=quick))
    planning_s = time.perf_counter() - start
    chosen = samples(plan)
    worker, scenarios = WorkerProcess(), {}
    with tempfile.TemporaryDirectory(prefix="sse-bench-campaign-") as tmp:
        folder = Path(tmp)
        try:
            first = next(iter(chosen.values()))[1]
            warm_up = _cut(first, 1.0).task(folder / "warm_up", True)
            if not worker.run(warm_up).ok:
                raise RuntimeError(f"campaign benchmark warm-up {first.key} failed")
            for stem, (count, sample) in chosen.items():
                t0 = time.perf_counter()
                outcome = worker.run(_cut(sample, duration_s).task(folder, True))
                seconds = time.perf_counter() - t0
                if not outcome.ok:
                    raise RuntimeError(f"campaign benchmark run {sample.key} failed: "
                                       f"{outcome.error}")
                scenarios[stem] = {"runs": count, "sample": sample.key,
                                   "run_seconds": seconds, "serial_minutes": count * seconds / 60}
        finally:
            worker.close()
    return {"campaign": str(CAMPAIGN), "quick": quick, "duration_s": duration_s,
            "planning_seconds": planning_s, "runs": len(plan.runs),
            "not_feasible": len(plan.not_feasible),
            "scenarios": scenarios,
            "not_feasible_by_scenario": dict(Counter(Path(n.run.scenario).stem
                                                     for n in plan.not_feasible))}


def projected_minutes(campaign: dict, speedup: float) -> float:
    """``make safety``'s wall time on two cores (minutes): planning, then every run on two
    workers that together go ``speedup`` times as fast as one."""
    serial = sum(s["serial_minutes"] for s in campaign["scenarios"].values())
    return campaign["planning_seconds"] / 60 + serial / speedup

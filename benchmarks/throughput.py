"""Item 4: sweep throughput, runs per minute, with 1 and 2 local workers and a Dask
LocalCluster of 2 workers. Runs are what a sweep runs: S3 with the pedestrian at its full
length (or cut with ``duration_s``), seeds 1..n, summary only, in worker processes
(``runner.tasks``) that start once per worker and take run after run."""

from __future__ import annotations

import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from sse_cosim.runner.executors import Execution, execute
from sse_cosim.runner.tasks import RunTask, WorkerProcess

SCENARIO = "scenarios/s3_pedestrian.toml"


def _tasks(folder: Path, runs: int, duration_s: float | None) -> list[RunTask]:
    cut = {} if duration_s is None else {"simulation.duration_s": duration_s}
    return [
        RunTask(key=f"r{i}", scenario=SCENARIO, out_dir=str(folder / f"r{i}"),
                overrides={**cut, "simulation.seed": i + 1}, plots=False, summary_only=True)
        for i in range(runs)
    ]


def _timed(runs: int, duration_s: float | None, workers: int, executor: str) -> dict:
    with tempfile.TemporaryDirectory(prefix="sse-bench-sweep-") as tmp:
        tasks = _tasks(Path(tmp), runs, duration_s)
        start = time.perf_counter()
        outcomes = execute(tasks, Execution(workers, executor, progress=False))
        elapsed = time.perf_counter() - start
    failed = [o.error for o in outcomes if not o.ok]
    if failed:
        raise RuntimeError(f"sweep benchmark runs failed: {failed[:2]}")
    return {"workers": workers, "executor": executor, "runs": runs, "seconds": elapsed,
            "runs_per_minute": 60.0 * runs / elapsed}


IMPORT_TIMER = ("import time; start = time.perf_counter(); import sse_cosim.runner.worker; "
                "print(time.perf_counter() - start)")


def _worker_startup(duration_s: float | None, runs: int = 3) -> dict:
    """Where a worker's start-up goes: its imports (timed in a fresh interpreter), and its
    first run against the later ones (numba loading its cached kernels, lazy imports, SUMO's
    first start), in one worker process."""
    imports = float(subprocess.run([sys.executable, "-c", IMPORT_TIMER], capture_output=True,
                                   text=True, check=True).stdout)
    worker, seconds = WorkerProcess(), []
    with tempfile.TemporaryDirectory(prefix="sse-bench-startup-") as tmp:
        try:
            for task in _tasks(Path(tmp), runs, duration_s):
                start = time.perf_counter()
                if not worker.run(task).ok:
                    raise RuntimeError(f"start-up benchmark run {task.key} failed")
                seconds.append(time.perf_counter() - start)
        finally:
            worker.close()
    later = statistics.median_high(seconds[1:])  # a run that took place
    return {"imports_seconds": imports, "first_run_seconds": seconds[0],
            "later_run_seconds": later, "first_run_extra_seconds": seconds[0] - later}


def run(runs: int = 16, duration_s: float | None = None, dask: bool = True) -> dict:
    configs = {"local_1": (1, "local"), "local_2": (2, "local")}
    if dask:
        configs["dask_2"] = (2, "dask")
    results = {name: _timed(runs, duration_s, w, ex) for name, (w, ex) in configs.items()}
    base = results["local_1"]["runs_per_minute"]
    for result in results.values():
        result["speedup_vs_1_worker"] = result["runs_per_minute"] / base
    return {"scenario": SCENARIO, "duration_s": duration_s, "configs": results,
            "worker_startup": _worker_startup(duration_s),
            "note": "wall time of execute() for the whole batch, worker start-up included; "
                    "the Dask figure includes starting and stopping the LocalCluster"}

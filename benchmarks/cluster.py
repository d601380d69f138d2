"""Item 3 (distributed): a sweep of many short runs on a Dask cluster started the way a user
starts one -- ``dask scheduler`` and two ``dask worker`` processes (one thread each) on
localhost -- against the local pool with two workers, in one process, one after the other.
Both execute the same tasks (S3 with the pedestrian, seeds 1..n, cut to ``duration_s``,
summary only); the figure is runs per minute (wall time of ``execute()``, the cluster's
start-up excluded: a user starts it once), and every run's summary must be identical on both.

The machine's load drifts over minutes, so the runs go in two halves, in the order local,
Dask, Dask, local (each executor's two halves straddle the other's): a load that rises or
falls steadily slows both alike. The local pool starts its workers in each half (as each
sweep does); a worker is replaced every ``TASKS_PER_WORKER`` runs anyway.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path

from sse_cosim.reporting.outputs import SUMMARY
from sse_cosim.runner.executors import Execution, execute
from sse_cosim.runner.tasks import RunTask

SCENARIO = Path("scenarios/s3_pedestrian.toml")
START_TIMEOUT_S = 60.0


def _tasks(folder: Path, runs: int, duration_s: float) -> list[RunTask]:
    scenario = str(SCENARIO.resolve())  # the workers' own working folder may differ
    return [RunTask(key=f"r{i}", scenario=scenario, out_dir=str(folder / f"r{i}"),
                    overrides={"simulation.duration_s": duration_s, "simulation.seed": i + 1},
                    plots=False, summary_only=True)
            for i in range(runs)]


def _dask_command() -> str:
    """The ``dask`` command beside this Python (a virtual environment's), else on PATH."""
    beside = Path(sys.executable).with_name("dask")
    found = str(beside) if beside.exists() else shutil.which("dask")
    if found is None:
        raise RuntimeError("the dask command is missing: pip install -e '.[dask]'")
    return found


@contextmanager
def dask_cluster(folder: Path, workers: int = 2):
    """``dask scheduler`` and ``workers`` ``dask worker`` processes on localhost; yields the
    scheduler's address once every worker has joined; stops them all on exit."""
    from dask.distributed import Client

    dask = _dask_command()
    address_file = folder / "scheduler.json"
    logs = (folder / "cluster.log").open("w")
    processes = [subprocess.Popen(
        [dask, "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
         "--scheduler-file", str(address_file)], stdout=logs, stderr=subprocess.STDOUT)]
    try:
        deadline = time.monotonic() + START_TIMEOUT_S
        while not address_file.exists():
            if time.monotonic() > deadline or processes[0].poll() is not None:
                raise RuntimeError(f"dask scheduler did not start (see {folder}/cluster.log)")
            time.sleep(0.1)
        for _ in range(workers):
            processes.append(subprocess.Popen(
                [dask, "worker", "--scheduler-file", str(address_file), "--nthreads", "1",
                 "--no-dashboard", "--host", "127.0.0.1"], stdout=logs,
                stderr=subprocess.STDOUT))
        address = json.loads(address_file.read_text(encoding="utf-8"))["address"]
        with Client(address, timeout=START_TIMEOUT_S) as client:
            client.wait_for_workers(workers, timeout=START_TIMEOUT_S)
        yield address
    finally:
        for process in reversed(processes):
            process.terminate()
        for process in processes:
            try:
                process.wait(timeout=30)
            except subprocess.TimeoutExpired:
                process.kill()
        logs.close()


def _timed(tasks: list[RunTask], execution: Execution) -> tuple[float, dict[str, dict]]:
    start = time.perf_counter()
    outcomes = execute(tasks, execution)
    elapsed = time.perf_counter() - start
    failed = [o.error for o in outcomes if not o.ok]
    if failed:
        raise RuntimeError(f"cluster benchmark runs failed: {failed[:2]}")
    rows = {t.key: json.loads((Path(t.out_dir) / SUMMARY).read_text(encoding="utf-8"))
            for t in tasks}
    return elapsed, rows


def run(runs: int = 1000, duration_s: float = 3.0, workers: int = 2) -> dict:
    with tempfile.TemporaryDirectory(prefix="sse-bench-cluster-") as tmp:
        root = Path(tmp)
        tasks = {name: _tasks(root / name, runs, duration_s) for name in ("local", "dask")}
        halves = {name: (t[:runs // 2], t[runs // 2:]) for name, t in tasks.items()}
        seconds = {"local": 0.0, "dask": 0.0}
        rows: dict[str, dict[str, dict]] = {"local": {}, "dask": {}}
        with dask_cluster(root, workers) as address:
            executions = {"local": Execution(workers, "local", progress=False),
                          "dask": Execution(workers, "dask", scheduler=address,
                                            progress=False)}
            for name, half in (("local", 0), ("dask", 0), ("dask", 1), ("local", 1)):
                elapsed, found = _timed(halves[name][half], executions[name])
                seconds[name] += elapsed
                rows[name].update(found)
    local_rate, dask_rate = 60.0 * runs / seconds["local"], 60.0 * runs / seconds["dask"]
    different = sorted(k for k in rows["local"] if rows["local"][k] != rows["dask"][k])
    return {"scenario": str(SCENARIO), "runs": runs, "duration_s": duration_s,
            "workers": workers,
            "local": {"seconds": seconds["local"], "runs_per_minute": local_rate},
            "dask_cluster": {"seconds": seconds["dask"], "runs_per_minute": dask_rate},
            "dask_over_local": dask_rate / local_rate,
            "rows_identical": not different, "rows_different": different[:10],
            "note": "dask scheduler + 2 dask worker processes on localhost (one thread "
                    "each), started before the timing; the runs in two halves, in the order "
                    "local, Dask, Dask, local (a steady drift in the machine's load slows "
                    "both alike); the local pool starts its workers inside each half's "
                    "timing; Dask tasks carry batches of runs"}

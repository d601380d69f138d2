"""Item 3 (distributed): a sweep of many short runs on a Dask cluster started the way a user
starts one -- ``dask scheduler`` and two ``dask worker`` processes (one thread each) on
localhost -- against the local pool with two workers, in one process, one after the other.
Both execute the same tasks (S3 with the pedestrian, seeds 1..n, cut to ``duration_s``,
summary only); the figure is runs per minute (wall time of ``execute()``, the cluster's
start-up excluded: a user starts it once), and every run's summary must be identical on both.

Where the time goes: each half also records the CPU time (user + system, psutil) of the run
workers (``sse_cosim.runner.worker`` processes, ended ones included), of the cluster's own
processes (scheduler, nannies, Dask workers) and of this process (the local pool's threads,
the Dask client); what the cores could have given beyond that went to other jobs or idled.

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
from contextlib import contextmanager, suppress
from pathlib import Path

import psutil

from sse_cosim.reporting.outputs import SUMMARY
from sse_cosim.runner.executors import Execution, default_workers, execute
from sse_cosim.runner.tasks import RunTask

SCENARIO = Path("scenarios/s3_pedestrian.toml")
START_TIMEOUT_S = 60.0
RUN_WORKER = "sse_cosim.runner.worker"  # in the command line of every run worker process
# a process that ended (or cannot be read) between listing and reading it counts for nothing
GONE = (psutil.NoSuchProcess, psutil.AccessDenied, psutil.ZombieProcess)


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
        yield address, [p.pid for p in processes]
    finally:
        for process in reversed(processes):
            process.terminate()
        for process in processes:
            try:
                process.wait(timeout=30)
            except subprocess.TimeoutExpired:
                process.kill()
        logs.close()


def cpu_seconds(cluster_pids: list[int]) -> dict[str, float]:
    """CPU seconds (user + system) used so far by the run workers, the cluster's own processes
    (``cluster_pids`` and their descendants but the run workers) and this process.

    A run worker that has ended and been waited for is in its parent's ``children_*`` times
    (this process for the local pool, a Dask worker process for the cluster): those count as
    runs, since run workers are the only children either waits for while runs go on.
    """
    me = psutil.Process()
    cluster = []
    for pid in cluster_pids:
        with suppress(*GONE):
            root = psutil.Process(pid)
            cluster += [root, *root.children(recursive=True)]
    # the cluster's processes are this process's children too: each process counted once
    every = {p.pid: p for p in [*me.children(recursive=True), *cluster]}.values()
    workers = [p for p in every if _is_run_worker(p)]
    own = [p for p in cluster if not _is_run_worker(p)]
    totals = {"runs": 0.0, "cluster": 0.0, "this_process": 0.0}
    for process in workers:
        totals["runs"] += _times(process, children=False)
    for process in own:
        totals["cluster"] += _times(process, children=False)
        totals["runs"] += _times(process, children=True)  # ended run workers it waited for
    totals["this_process"] = _times(me, children=False)
    totals["runs"] += _times(me, children=True)
    return totals


def _is_run_worker(process: psutil.Process) -> bool:
    with suppress(*GONE):
        return RUN_WORKER in " ".join(process.cmdline())
    return False


def _times(process: psutil.Process, children: bool) -> float:
    """A process's own CPU seconds, or those of its ended children it waited for (0 if it has
    ended meanwhile)."""
    with suppress(*GONE):
        t = process.cpu_times()
        return t.children_user + t.children_system if children else t.user + t.system
    return 0.0


def _timed(tasks: list[RunTask], execution: Execution,
           cluster_pids: list[int]) -> tuple[float, dict[str, float], dict[str, dict]]:
    before = cpu_seconds(cluster_pids)
    start = time.perf_counter()
    outcomes = execute(tasks, execution)
    elapsed = time.perf_counter() - start
    after = cpu_seconds(cluster_pids)
    failed = [o.error for o in outcomes if not o.ok]
    if failed:
        raise RuntimeError(f"cluster benchmark runs failed: {failed[:2]}")
    rows = {t.key: json.loads((Path(t.out_dir) / SUMMARY).read_text(encoding="utf-8"))
            for t in tasks}
    return elapsed, {k: after[k] - before[k] for k in after}, rows


def run(runs: int = 1000, duration_s: float = 3.0, workers: int = 2) -> dict:
    cores = default_workers()  # the cores this process may use
    with tempfile.TemporaryDirectory(prefix="sse-bench-cluster-") as tmp:
        root = Path(tmp)
        tasks = {name: _tasks(root / name, runs, duration_s) for name in ("local", "dask")}
        halves = {name: (t[:runs // 2], t[runs // 2:]) for name, t in tasks.items()}
        seconds = {"local": 0.0, "dask": 0.0}
        cpu = {name: {"runs": 0.0, "cluster": 0.0, "this_process": 0.0} for name in seconds}
        rows: dict[str, dict[str, dict]] = {"local": {}, "dask": {}}
        with dask_cluster(root, workers) as (address, cluster_pids):
            executions = {"local": Execution(workers, "local", progress=False),
                          "dask": Execution(workers, "dask", scheduler=address,
                                            progress=False)}
            for name, half in (("local", 0), ("dask", 0), ("dask", 1), ("local", 1)):
                elapsed, used, found = _timed(halves[name][half], executions[name],
                                              cluster_pids)
                seconds[name] += elapsed
                cpu[name] = {k: cpu[name][k] + used[k] for k in cpu[name]}
                rows[name].update(found)
    local_rate, dask_rate = 60.0 * runs / seconds["local"], 60.0 * runs / seconds["dask"]
    different = sorted(k for k in rows["local"] if rows["local"][k] != rows["dask"][k])
    for name in cpu:
        cpu[name]["cores_wall"] = cores * seconds[name]
        cpu[name]["other_or_idle"] = cpu[name]["cores_wall"] - sum(
            cpu[name][k] for k in ("runs", "cluster", "this_process"))
    return {"scenario": str(SCENARIO), "runs": runs, "duration_s": duration_s,
            "workers": workers, "cores": cores,
            "local": {"seconds": seconds["local"], "runs_per_minute": local_rate,
                      "cpu_seconds": cpu["local"]},
            "dask_cluster": {"seconds": seconds["dask"], "runs_per_minute": dask_rate,
                             "cpu_seconds": cpu["dask"]},
            "dask_over_local": dask_rate / local_rate,
            "rows_identical": not different, "rows_different": different[:10],
            "note": "dask scheduler + 2 dask worker processes on localhost (one thread "
                    "each), started before the timing; the runs in two halves, in the order "
                    "local, Dask, Dask, local (a steady drift in the machine's load slows "
                    "both alike); the local pool starts its workers inside each half's "
                    "timing; Dask tasks carry batches of runs"}

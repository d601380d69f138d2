"""Where tasks run: a local pool of worker processes, or Dask distributed.

Either way each task runs in a worker process (:mod:`sse_cosim.runner.tasks`) and is seeded
by its scenario alone, so the outcomes do not depend on the executor, the number of workers
or the order in which tasks finish. Outcomes come back in the tasks' order.
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor, as_completed
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Literal

from tqdm import tqdm

from sse_cosim.reporting.outputs import TaskOutcome
from sse_cosim.runner.tasks import (
    RunTask,
    WorkerPool,
    finished_outcome,
    ran_as_planned,
    run_batch_in_worker,
)

ExecutorName = Literal["local", "dask"]
BATCHES_PER_THREAD = 4  # Dask: at least this many batches per worker thread, to balance load
MAX_BATCH_RUNS = 16  # Dask: at most this many runs per task


@dataclass(frozen=True)
class Execution:
    """Where and how runs execute: ``workers`` processes (None: one per core) on
    ``executor``, with a Dask ``scheduler`` address (None: a local cluster); ``resume`` skips
    runs that already finished; ``progress`` shows a progress bar."""

    workers: int | None = None
    executor: ExecutorName = "local"
    scheduler: str | None = None
    resume: bool = False
    progress: bool = True


def default_workers() -> int:
    """The number of cores this process may use."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def execute(
    tasks: Sequence[RunTask], execution: Execution, description: str = "runs"
) -> list[TaskOutcome]:
    """Run every task (skipping finished ones with ``execution.resume``) and return outcomes
    in order."""
    done: dict[str, TaskOutcome] = {}
    if execution.resume:
        stale = 0
        for task in tasks:
            outcome = finished_outcome(task)
            if outcome is not None and outcome.ok:
                if ran_as_planned(task):
                    done[task.key] = outcome
                else:
                    stale += 1
        if stale:
            tqdm.write(f"{description}: {stale} finished run(s) recorded another scenario "
                       "than their file and overrides give today (the file edited, or the "
                       "schema grown since): made again")
    todo = [t for t in tasks if t.key not in done]
    workers = execution.workers or default_workers()
    bar = tqdm(total=len(tasks), initial=len(done), desc=description, unit="run",
               disable=not execution.progress, dynamic_ncols=True)
    failures = 0
    with bar, _runner(execution.executor, workers, execution.scheduler) as submit_all:
        for outcome in submit_all(todo):
            done[outcome.key] = outcome
            failures += not outcome.ok
            bar.set_postfix(failed=failures)
            bar.update(1)
    return [done[t.key] for t in tasks]


@contextmanager
def _runner(executor: ExecutorName, workers: int, scheduler: str | None):
    if executor == "local":
        yield lambda todo: _local(todo, workers)
    elif executor == "dask":
        with _dask_client(workers, scheduler) as client:
            yield lambda todo: _dask(client, todo)
    else:
        raise ValueError(f"unknown executor {executor!r}")


def _local(todo: Sequence[RunTask], workers: int) -> Iterator[TaskOutcome]:
    """Threads that each keep one worker process busy.

    If the caller stops early (Ctrl-C), tasks not yet started are cancelled rather than
    run to the end of the queue; only the runs in flight finish.
    """
    processes = WorkerPool()
    try:
        with ThreadPoolExecutor(max_workers=workers) as pool:
            futures = [pool.submit(processes.run, task) for task in todo]
            try:
                for future in as_completed(futures):
                    yield future.result()
            finally:
                pool.shutdown(wait=False, cancel_futures=True)
    finally:
        processes.close()


@contextmanager
def _dask_client(workers: int, scheduler: str | None):
    from dask.distributed import Client, LocalCluster

    if scheduler:
        with Client(scheduler) as client:
            yield client
        return
    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        yield client


def dask_batches(todo: Sequence[RunTask], threads: int) -> list[list[RunTask]]:
    """``todo`` cut, in order, into batches (one Dask task each): as many runs per batch as
    leaves every worker thread :data:`BATCHES_PER_THREAD` batches, between 1 and
    :data:`MAX_BATCH_RUNS`.

    A run of a few seconds is short next to a scheduler's round trip and the worker's
    bookkeeping per task; batches pay them once per several runs.
    """
    size = max(1, min(MAX_BATCH_RUNS, len(todo) // (BATCHES_PER_THREAD * max(threads, 1))))
    return [list(todo[i:i + size]) for i in range(0, len(todo), size)]


def _dask(client, todo: Sequence[RunTask]) -> Iterator[TaskOutcome]:
    from dask.distributed import as_completed as dask_as_completed

    threads = sum(client.nthreads().values())
    futures = [client.submit(run_batch_in_worker, batch, key=f"runs-{batch[0].key}", pure=False)
               for batch in dask_batches(todo, threads)]
    for future in dask_as_completed(futures):
        yield from future.result()

"""Dask tasks carry batches of runs: every run once, in order, batches balanced over the
worker threads and bounded in size."""

from __future__ import annotations

import pytest

from sse_cosim.runner.executors import BATCHES_PER_THREAD, MAX_BATCH_RUNS, dask_batches
from sse_cosim.runner.tasks import RunTask


def tasks(count: int) -> list[RunTask]:
    return [RunTask(key=f"r{i}", scenario="s.toml", out_dir=f"out/r{i}") for i in range(count)]


@pytest.mark.parametrize(("runs", "threads"), [(0, 2), (1, 2), (7, 2), (16, 2), (33, 3),
                                               (1000, 2), (1000, 64), (5, 0)])
def test_every_run_once_in_order(runs, threads):
    batches = dask_batches(tasks(runs), threads)
    assert [t.key for batch in batches for t in batch] == [f"r{i}" for i in range(runs)]
    assert all(1 <= len(batch) <= MAX_BATCH_RUNS for batch in batches)


def test_few_runs_go_one_per_task_so_every_thread_stays_busy():
    assert [len(b) for b in dask_batches(tasks(16), threads=2)] == [2] * 8
    assert [len(b) for b in dask_batches(tasks(7), threads=2)] == [1] * 7


def test_many_runs_go_in_bounded_batches_with_enough_per_thread():
    batches = dask_batches(tasks(1000), threads=2)
    assert len(batches[0]) == MAX_BATCH_RUNS
    assert len(batches) >= BATCHES_PER_THREAD * 2
    assert len(dask_batches(tasks(1000), threads=64)) >= BATCHES_PER_THREAD * 64

"""Worker processes: runs do not depend on what ran before in the same worker; a worker that
dies or whose run fails costs only that run."""

from __future__ import annotations

import json
import os
import signal
import threading
import time
from pathlib import Path

import pytest

from sse_cosim.runner import tasks
from sse_cosim.runner.tasks import RunTask, WorkerProcess

pytestmark = pytest.mark.sumo

ROOT = Path(__file__).resolve().parents[2]
S3 = str(ROOT / "scenarios" / "s3_pedestrian.toml")


def task(folder: Path, name: str, seed: int, duration_s: float = 2.0, **overrides) -> RunTask:
    return RunTask(key=name, scenario=S3, out_dir=str(folder / name), plots=False,
                   summary_only=True,
                   overrides={"simulation.duration_s": duration_s, "simulation.seed": seed,
                              **overrides})


def summary(folder: Path, name: str) -> dict:
    return json.loads((folder / name / "summary.json").read_text())


def test_a_run_gives_the_same_summary_after_other_runs_in_the_same_worker(tmp_path):
    fresh, warm = WorkerProcess(), WorkerProcess()
    try:
        assert fresh.run(task(tmp_path, "alone", seed=1)).ok
        for name, seed in (("other1", 5), ("other2", 9), ("again", 1)):
            assert warm.run(task(tmp_path, name, seed=seed)).ok
    finally:
        fresh.close()
        warm.close()
    assert summary(tmp_path, "again") == summary(tmp_path, "alone")
    assert summary(tmp_path, "other1") != summary(tmp_path, "alone")  # seeds do matter


def test_a_failed_run_is_recorded_and_the_next_one_runs(tmp_path):
    worker = WorkerProcess()
    try:
        bad = worker.run(task(tmp_path, "bad", seed=1, **{"automated.bus.nominal_speed_mps": -3.0}))
        good = worker.run(task(tmp_path, "good", seed=1))
    finally:
        worker.close()
    assert not bad.ok and "nominal_speed_mps" in bad.error
    assert good.ok and good.summary["containment_violations"] == 0


def test_a_killed_worker_costs_only_its_run(tmp_path):
    worker = WorkerProcess()
    outcomes = {}
    try:
        assert worker.run(task(tmp_path, "first", seed=1)).ok  # the worker is up
        pid = worker._proc.pid
        thread = threading.Thread(
            target=lambda: outcomes.update(long=worker.run(task(tmp_path, "long", 2, 60.0))))
        thread.start()
        staging = tmp_path / ".long.tmp" / "sumo"
        deadline = time.monotonic() + 60
        while not staging.exists():  # the run has started
            assert time.monotonic() < deadline
            time.sleep(0.02)
        os.kill(pid, signal.SIGKILL)
        thread.join(timeout=60)
        after = worker.run(task(tmp_path, "after", seed=3))
    finally:
        worker.close()
    assert not outcomes["long"].ok
    assert outcomes["long"].error.startswith("worker died (signal 9)")
    assert not (tmp_path / ".long.tmp").exists() and (tmp_path / "long" / "error.json").is_file()
    assert after.ok


def test_a_worker_is_replaced_after_its_quota_of_runs(tmp_path, monkeypatch):
    monkeypatch.setattr(tasks, "TASKS_PER_WORKER", 2)
    worker = WorkerProcess()
    pids = []
    try:
        for i in range(3):
            assert worker.run(task(tmp_path, f"r{i}", seed=1, duration_s=0.5)).ok
            pids.append(None if worker._proc is None else worker._proc.pid)
    finally:
        worker.close()
    assert pids[0] is not None and pids[1] is None  # ended after its second run
    assert pids[2] is not None and pids[2] != pids[0]  # a fresh process took the third

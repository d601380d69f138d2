"""Runs as tasks: one scenario file, its overrides, one output folder, run in a worker process.

libsumo runs one simulation per process at a time, and a crash (even by a signal) must lose
only the run it happened in, so tasks never run in the caller's process: each runs in a
*worker process* (``python -m sse_cosim.runner.worker``) that stays up and takes the next
task, which spares every run after the first the ~1 s of imports and start-up (most of a
short run's cost). Runs do not depend on what ran before them in the same worker: each is
seeded by its scenario alone, SUMO starts and closes per run, and a worker whose run failed
exits, so the next task gets a fresh process. A worker is also replaced after
:data:`TASKS_PER_WORKER` runs. Executors (:mod:`sse_cosim.runner.executors`) only decide
*where* the worker processes run.

A task writes into a hidden staging folder beside its run folder (``.<name>.tmp``) that
replaces the run folder only once it holds ``summary.json`` or ``error.json``: a run folder
is always a finished run, and a run killed half-way leaves only its staging folder, which
the next attempt clears.
"""

from __future__ import annotations

import atexit
import contextlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import IO, Any

from sse_cosim.files import write_json_atomic
from sse_cosim.reporting.outputs import (
    ERROR,
    SUMMARY,
    TaskOutcome,
    portable_scenario,
    read_outcome,
    read_scenario_record,
)

TASKS_PER_WORKER = 100  # then a fresh process: no slow build-up over long sweeps


@dataclass(frozen=True)
class RunTask:
    """One simulation to run: ``scenario`` with dotted ``overrides`` into ``out_dir``."""

    key: str
    scenario: str
    out_dir: str
    overrides: dict[str, Any] = field(default_factory=dict)
    plots: bool = True
    scene_times: tuple[float, ...] = ()
    summary_only: bool = False  # write summary.json and scenario.json only (large sweeps)
    margins: tuple[str, ...] = ()  # margins (reporting.margins) the summary gets besides

    def to_json(self) -> str:
        return json.dumps(asdict(self))

    @classmethod
    def from_json(cls, text: str) -> RunTask:
        data = json.loads(text)
        data["scene_times"] = tuple(data.get("scene_times", ()))
        data["margins"] = tuple(data.get("margins", ()))
        return cls(**data)


def finished_outcome(task: RunTask) -> TaskOutcome | None:
    """The outcome recorded in the task's folder, if the task already ran to its end."""
    return read_outcome(task.key, Path(task.out_dir))


def ran_as_planned(task: RunTask) -> bool:
    """Whether the task's folder records the scenario the task would run now.

    A run key names a scenario file, its overrides and its seed, not the file's content: a
    finished run of a scenario file edited since, or written before a field was added to
    the schema, has the same key. ``--resume`` keeps a run only if its ``scenario.json`` is
    what the task resolves to today.
    """
    from sse_cosim.errors import UserError
    from sse_cosim.scenario.loader import load_scenario

    folder = Path(task.out_dir)
    recorded = read_scenario_record(folder)
    if recorded is None:
        return False
    try:
        scenario = load_scenario(task.scenario, task.overrides)
    except UserError:  # the file no longer loads: the run is made again and says why
        return False
    recorded.pop("source", None)  # where the file was read from, not what it says
    return _agrees(recorded, portable_scenario(scenario, folder))


def _agrees(recorded: Any, planned: Any) -> bool:
    """Whether a recorded scenario (or a part of it) is the planned one. A field the plan
    leaves None is the run's to fill (``estimator.position_jitter_m``: measured on the
    network), so any recorded value agrees with it."""
    if planned is None:
        return True
    if isinstance(planned, dict):
        return (isinstance(recorded, dict) and recorded.keys() == planned.keys()
                and all(_agrees(recorded[k], v) for k, v in planned.items()))
    if isinstance(planned, list):
        return (isinstance(recorded, list) and len(recorded) == len(planned)
                and all(_agrees(r, v) for r, v in zip(recorded, planned, strict=True)))
    return recorded == planned


class WorkerProcess:
    """One worker process, started on first use, that runs tasks one after another."""

    def __init__(self) -> None:
        self._proc: subprocess.Popen[str] | None = None
        self._stderr: IO[bytes] | None = None
        self._served = 0

    def run(self, task: RunTask) -> TaskOutcome:
        """Run ``task`` in the worker and read its outcome from its folder."""
        staged = _staged(task)
        proc = self._started()
        try:
            proc.stdin.write(staged.to_json() + "\n")
            proc.stdin.flush()
            answer = proc.stdout.readline().strip()
        except (BrokenPipeError, OSError):
            answer = ""
        self._served += 1
        if answer != task.key:
            self._record_death(staged, task)
        outcome = _publish(staged, task)
        if not outcome.ok or answer != task.key or self._served >= TASKS_PER_WORKER:
            self.close()  # the worker exits after a failure; start afresh either way
        return outcome

    def close(self) -> None:
        """End the worker (it finishes its current task first) and forget it."""
        proc, self._proc = self._proc, None
        if proc is not None:
            with contextlib.suppress(OSError):  # already gone
                proc.stdin.close()
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
            proc.stdout.close()
        if self._stderr is not None:
            self._stderr.close()
            self._stderr = None

    def _started(self) -> subprocess.Popen[str]:
        if self._proc is None:
            self._stderr = tempfile.TemporaryFile()  # noqa: SIM115 -- closed in close()
            env = {**os.environ, "PYTHONHASHSEED": "0", "MPLBACKEND": "Agg"}
            self._proc = subprocess.Popen(
                [sys.executable, "-m", "sse_cosim.runner.worker"], stdin=subprocess.PIPE,
                stdout=subprocess.PIPE, stderr=self._stderr, text=True, encoding="utf-8",
                env=env,
            )
            self._served = 0
        return self._proc

    def _record_death(self, staged: RunTask, task: RunTask) -> None:
        """The worker died during ``task``: record why in its folder, unless the task did."""
        try:
            code = self._proc.wait(timeout=30)
        except subprocess.TimeoutExpired:  # alive but answering out of turn: stop it
            self._proc.kill()
            code = self._proc.wait()
        self._stderr.seek(0)
        lines = self._stderr.read().decode("utf-8", "replace").strip().splitlines()
        if finished_outcome(staged) is None:
            last = lines[-1] if lines else f"exit status {code}"
            error = f"worker died ({_exit_reason(code)}): {last}"
            write_json_atomic(Path(staged.out_dir) / ERROR, {"key": task.key, "error": error})


class WorkerPool:
    """One :class:`WorkerProcess` per calling thread (threads run tasks in parallel)."""

    def __init__(self) -> None:
        self._local = threading.local()
        self._workers: list[WorkerProcess] = []
        self._lock = threading.Lock()

    def run(self, task: RunTask) -> TaskOutcome:
        worker = getattr(self._local, "worker", None)
        if worker is None:
            worker = self._local.worker = WorkerProcess()
            with self._lock:
                self._workers.append(worker)
        return worker.run(task)

    def close(self) -> None:
        with self._lock:
            workers, self._workers = self._workers, []
        for worker in workers:
            worker.close()


_PROCESS_POOL = WorkerPool()
atexit.register(_PROCESS_POOL.close)


def run_batch_in_worker(tasks: Sequence[RunTask]) -> list[TaskOutcome]:
    """Run ``tasks`` one after another in this thread's worker, of a pool that lives as long
    as this process (for executors such as Dask whose own workers call it): one remote call
    for several runs, so a scheduler's round trip is paid once per batch. Each run publishes
    its folder as it ends, so an interrupted batch loses only the run in flight."""
    return [_PROCESS_POOL.run(task) for task in tasks]


def record_failure(task: RunTask, error: str) -> TaskOutcome:
    """Record ``task`` as failed without running it (e.g. its overrides do not validate)."""
    staged = _staged(task)
    write_json_atomic(Path(staged.out_dir) / ERROR, {"key": task.key, "error": error})
    return _publish(staged, task)


def _staged(task: RunTask) -> RunTask:
    """``task`` writing into a fresh staging folder ``.<name>.tmp`` beside its run folder."""
    final = Path(task.out_dir)
    staging = final.with_name(f".{final.name}.tmp")
    shutil.rmtree(staging, ignore_errors=True)
    staging.mkdir(parents=True)
    return replace(task, out_dir=str(staging))


def _publish(staged: RunTask, task: RunTask) -> TaskOutcome:
    """Replace the task's run folder by its finished staging folder; the outcome it holds."""
    final = Path(task.out_dir)
    shutil.rmtree(final, ignore_errors=True)
    os.replace(staged.out_dir, final)
    outcome = finished_outcome(task)
    assert outcome is not None, f"{final} holds neither {SUMMARY} nor {ERROR}"
    return outcome


def _exit_reason(code: int) -> str:
    return f"signal {-code}" if code < 0 else f"exit status {code}"

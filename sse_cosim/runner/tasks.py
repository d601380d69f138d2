"""Runs as tasks: one scenario file, its overrides, one output folder, one process each.

libsumo runs one simulation per process, so every task runs in a fresh Python process
(``python -m sse_cosim.runner.worker``). A task that crashes, even by a signal, loses only
itself; its folder then holds ``error.json`` instead of ``summary.json``. Executors
(:mod:`sse_cosim.runner.executors`) only decide *where* those processes run.

A task writes into a hidden staging folder beside its run folder (``.<name>.tmp``) that
replaces the run folder only once it holds ``summary.json`` or ``error.json``: a run folder
is always a finished run, and a run killed half-way leaves only its staging folder, which
the next attempt clears.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

from sse_cosim.files import write_json_atomic
from sse_cosim.reporting.outputs import SUMMARY

ERROR = "error.json"


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

    def to_json(self) -> str:
        return json.dumps(asdict(self))

    @classmethod
    def from_json(cls, text: str) -> RunTask:
        data = json.loads(text)
        data["scene_times"] = tuple(data.get("scene_times", ()))
        return cls(**data)


@dataclass(frozen=True)
class TaskOutcome:
    """A finished task: its summary, or the one-line error that stopped it."""

    key: str
    summary: dict[str, Any] | None
    error: str | None

    @property
    def ok(self) -> bool:
        return self.error is None


def finished_outcome(task: RunTask) -> TaskOutcome | None:
    """The outcome recorded in the task's folder, if the task already ran to its end."""
    folder = Path(task.out_dir)
    for name, is_summary in ((SUMMARY, True), (ERROR, False)):
        path = folder / name
        if path.is_file():
            try:
                data = json.loads(path.read_text(encoding="utf-8"))
            except (OSError, json.JSONDecodeError):
                return None
            if is_summary:
                return TaskOutcome(task.key, data, None)
            return TaskOutcome(task.key, None, str(data.get("error", "unknown error")))
    return None


def run_in_subprocess(task: RunTask) -> TaskOutcome:
    """Run ``task`` in a fresh Python process and read its outcome from its folder."""
    staged = _staged(task)
    env = {**os.environ, "PYTHONHASHSEED": "0", "MPLBACKEND": "Agg"}
    proc = subprocess.run(
        [sys.executable, "-m", "sse_cosim.runner.worker", staged.to_json()],
        capture_output=True, text=True, env=env, check=False,
    )
    if finished_outcome(staged) is None:
        last = (proc.stderr.strip().splitlines() or [f"exit status {proc.returncode}"])[-1]
        error = f"worker died ({_exit_reason(proc.returncode)}): {last}"
        write_json_atomic(Path(staged.out_dir) / ERROR, {"key": task.key, "error": error})
    return _publish(staged, task)


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

"""A worker process: runs :class:`RunTask`\\ s, one JSON line each on stdin, one after another.

After each task it answers the task's key on its reply channel (the original stdout; anything
else written to stdout, such as SUMO's messages, goes to stderr). A task's folder ends with
``summary.json`` (success) or ``error.json`` (a one-line reason; a run the world's check
stopped also names the broken assumption, ``"assumption": "pedestrian_speed"``). After a
failed task the worker exits, so the next task starts in a fresh process with nothing left behind.
"""

from __future__ import annotations

import os
import sys
import traceback
from collections.abc import Iterable
from pathlib import Path
from typing import TextIO

from sse_cosim.errors import AssumptionBroken, SimulationError, UserError
from sse_cosim.files import write_json_atomic
from sse_cosim.reporting.outputs import ERROR
from sse_cosim.runner.run import run_scenario_file
from sse_cosim.runner.tasks import RunTask


def run_task(task: RunTask) -> int:
    """Run one task into its folder; 0 on success, 2 for a bad input, 1 for a bug."""
    try:
        run_scenario_file(
            Path(task.scenario), Path(task.out_dir), task.overrides,
            scene_times=task.scene_times, plots=task.plots, summary_only=task.summary_only,
            margins=task.margins,
        )
    except (UserError, SimulationError) as exc:
        record = {"key": task.key, "error": str(exc)}
        if isinstance(exc, AssumptionBroken):  # stopped by the world's check: say which
            record["assumption"] = exc.assumption
        write_json_atomic(Path(task.out_dir) / ERROR, record)
        return 2
    except Exception as exc:  # a bug: keep the traceback in the folder, one line for the table
        write_json_atomic(
            Path(task.out_dir) / ERROR,
            {"key": task.key, "error": f"{type(exc).__name__}: {exc}",
             "traceback": traceback.format_exc()},
        )
        return 1
    return 0


def serve(lines: Iterable[str], reply: TextIO) -> int:
    """Run the task of every line, answering each key; stop after the first failure."""
    for line in lines:
        task = RunTask.from_json(line)
        code = run_task(task)
        reply.write(task.key + "\n")
        reply.flush()
        if code:
            return code
    return 0


def main() -> int:
    reply = os.fdopen(os.dup(sys.stdout.fileno()), "w", encoding="utf-8")
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())  # stray output must not mix with replies
    return serve(sys.stdin, reply)


if __name__ == "__main__":
    sys.exit(main())

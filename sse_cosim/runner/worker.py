"""A worker process: runs one :class:`RunTask` given as JSON on the command line.

Its folder ends with ``summary.json`` (success) or ``error.json`` (a one-line reason).
"""

from __future__ import annotations

import sys
import traceback
from pathlib import Path

from sse_cosim.errors import SimulationError, UserError
from sse_cosim.files import write_json_atomic
from sse_cosim.runner.run import run_scenario_file
from sse_cosim.runner.tasks import ERROR, RunTask


def main(argv: list[str]) -> int:
    task = RunTask.from_json(argv[0])
    try:
        run_scenario_file(
            Path(task.scenario), Path(task.out_dir), task.overrides,
            scene_times=task.scene_times, plots=task.plots, summary_only=task.summary_only,
        )
    except (UserError, SimulationError) as exc:
        write_json_atomic(Path(task.out_dir) / ERROR, {"key": task.key, "error": str(exc)})
        return 2
    except Exception as exc:  # a bug: keep the traceback in the folder, one line for the table
        write_json_atomic(
            Path(task.out_dir) / ERROR,
            {"key": task.key, "error": f"{type(exc).__name__}: {exc}",
             "traceback": traceback.format_exc()},
        )
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

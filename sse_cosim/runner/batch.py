"""All scenarios of a folder, run in worker processes, then the paper's tables and figures."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from sse_cosim.errors import UserError
from sse_cosim.reporting.outputs import RUNS_FOLDER, TaskOutcome
from sse_cosim.runner.executors import Execution, execute
from sse_cosim.runner.tasks import RunTask


def scenario_files(paths: Sequence[Path]) -> list[Path]:
    """Scenario files named by ``paths`` (files, or folders searched recursively).

    Files whose name starts with ``_`` are bases for ``extends``, not scenarios.
    """
    found: list[Path] = []
    for path in paths:
        if path.is_dir():
            found += sorted(p for p in path.rglob("*.toml") if not p.name.startswith("_"))
        elif path.is_file():
            found.append(path)
        else:
            raise UserError(str(path), "", "no such file or folder",
                            "name a scenario file or folder")
    if not found:
        raise UserError(", ".join(map(str, paths)), "", "no scenario files (*.toml) found",
                        "name a folder that holds scenario files")
    return found


def batch_tasks(
    files: Sequence[Path], out_dir: Path, scene_times: Sequence[float]
) -> list[RunTask]:
    """One task per scenario file, its folder named after the file under ``out_dir/runs``."""
    stems = [f.stem for f in files]
    duplicates = {s for s in stems if stems.count(s) > 1}
    if duplicates:
        raise UserError(", ".join(sorted(duplicates)), "", "two scenario files share a name",
                        "rename one: run folders are named after the files")
    return [
        RunTask(key=f.stem, scenario=str(f.resolve()), out_dir=str(out_dir / RUNS_FOLDER / f.stem),
                scene_times=tuple(scene_times))
        for f in files
    ]


def run_batch(
    paths: Sequence[Path],
    out_dir: Path,
    execution: Execution,
    scene_times: Sequence[float] = (),
) -> list[TaskOutcome]:
    """Run every scenario under ``paths``; outcomes in file order."""
    tasks = batch_tasks(scenario_files(paths), out_dir, scene_times)
    return execute(tasks, execution, description="scenarios")

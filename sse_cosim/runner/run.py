"""One run in this process: load a scenario, simulate it, write its folder."""

from __future__ import annotations

import shutil
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from tqdm import tqdm

from sse_cosim.files import portable_path
from sse_cosim.pipeline.result import StepResult
from sse_cosim.reporting.margins import MARGINS, Margin, check_margins
from sse_cosim.reporting.outputs import REGIONS, RegionFile, write_run
from sse_cosim.reporting.recorder import RegionLog, RunRecorder
from sse_cosim.reporting.replay import ReplayLog
from sse_cosim.runner.simulation import simulate
from sse_cosim.scenario.loader import load_scenario
from sse_cosim.scenario.model import Scenario


def run_scenario_file(
    path: Path,
    out_dir: Path,
    overrides: Mapping[str, Any] | None = None,
    scene_times: Sequence[float] = (),
    plots: bool = True,
    summary_only: bool = False,
    margins: Sequence[str] = (),
) -> dict:
    """Load ``path`` (with dotted ``overrides``), run it and write ``out_dir``; the summary."""
    scenario = load_scenario(path, overrides)
    return run_scenario(scenario, str(path), out_dir, scene_times, plots, summary_only,
                        margins)


def run_scenario(
    scenario: Scenario,
    source: str,
    out_dir: Path,
    scene_times: Sequence[float] = (),
    plots: bool = True,
    summary_only: bool = False,
    margins: Sequence[str] = (),
    progress: bool = False,
) -> dict:
    """Simulate ``scenario`` (read from ``source``) and write its outputs to ``out_dir``.

    ``source`` is recorded (and named in messages) relative to the current folder where it
    lies below it, so that a results folder holds no machine path. ``margins``: the names of
    the margins (:data:`~sse_cosim.reporting.margins.MARGINS`) the summary gets under
    ``margins``; none, no such key. ``progress``: a bar of the simulated time on standard
    error while it runs, where that is a terminal."""
    source = portable_path(source)
    check_margins(margins, scenario, source)
    watchers = [MARGINS[name](scenario) for name in margins]
    region_file = None if summary_only else RegionFile(out_dir / REGIONS)
    recorder = RunRecorder(scenario, tuple(scene_times),
                           replay=None if summary_only else ReplayLog(),
                           regions=RegionLog(region_file,
                                             keep=any(w.reads_regions for w in watchers)))
    try:
        return _simulate_and_write(scenario, source, out_dir, recorder, watchers, plots,
                                   summary_only, progress)
    finally:  # a run that stopped leaves no regions file (one that finished put it in place)
        if region_file is not None:
            region_file.discard()


def _simulate_and_write(scenario: Scenario, source: str, out_dir: Path, recorder: RunRecorder,
                        watchers: Sequence[Margin], plots: bool, summary_only: bool,
                        progress: bool) -> dict:
    """:func:`run_scenario`'s run, its ``recorder`` and margin ``watchers`` fed every step."""
    bar = tqdm(total=scenario.simulation.duration_s, desc=scenario.name, unit="s",
               bar_format="{desc}: {percentage:3.0f}%|{bar}| {n:.1f}/{total:g} s simulated "
               "[{elapsed}<{remaining}]", disable=None if progress else True,
               dynamic_ncols=True, leave=False)
    step_s = scenario.simulation.step_length_s

    def on_step(result: StepResult) -> None:
        recorder(result)
        for watch in watchers:
            watch(result)
        bar.update(step_s)

    sumo_dir = out_dir / "sumo"
    with bar:
        info = simulate(scenario, sumo_dir, source, on_step, on_start=recorder.start)
    if summary_only:  # SUMO's files served the run; one that failed keeps them (its log)
        shutil.rmtree(sumo_dir)
    extra: dict[str, Any] = dict(info.breaks)
    if watchers:
        extra["margins"] = {watch.name: watch.value(recorder) for watch in watchers}
    return write_run(out_dir, info.scenario, recorder, info.roadmap, source, info.arrived,
                     plots, summary_only, extra or None)

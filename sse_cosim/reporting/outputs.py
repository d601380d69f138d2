"""A run's folder: ``trace.csv``, ``sets.jsonl``, ``summary.json``, ``scenario.json`` and plots.

Every file is written whole or not at all (:mod:`sse_cosim.files`); ``summary.json`` is
written last, so a folder with a summary is a finished run. With ``summary_only`` (large
sweeps) a run writes ``scenario.json`` and ``summary.json`` only.
"""

from __future__ import annotations

import json
from pathlib import Path

from sse_cosim.files import atomic_path, write_json_atomic, write_text_atomic
from sse_cosim.reporting.recorder import RunRecorder
from sse_cosim.scenario.model import Scenario
from sse_cosim.world.roadmap import RoadMap

TRACE = "trace.csv"
SETS = "sets.jsonl"
SUMMARY = "summary.json"
SCENARIO = "scenario.json"


def write_run(
    out_dir: Path, scenario: Scenario, recorder: RunRecorder, roadmap: RoadMap, source: str,
    plots_wanted: bool = True, summary_only: bool = False,
) -> dict:
    """Write every output of one run into ``out_dir``; returns the summary."""
    out_dir.mkdir(parents=True, exist_ok=True)
    write_json_atomic(out_dir / SCENARIO, {"source": source, **scenario.model_dump(mode="json")})
    if not summary_only:
        # pandas and matplotlib load only here: a sweep's summary-only runs skip ~1 s of imports
        import pandas as pd

        trace = pd.DataFrame(recorder.rows)
        with atomic_path(out_dir / TRACE) as tmp:
            trace.to_csv(tmp, index=False, float_format="%.6g")
        write_text_atomic(
            out_dir / SETS, "".join(json.dumps(line) + "\n" for line in recorder.set_lines)
        )
        if plots_wanted and not trace.empty:
            _write_plots(out_dir, scenario, recorder, trace, roadmap)
    summary = {"source": source, **recorder.summary()}
    write_json_atomic(out_dir / SUMMARY, summary)
    return summary


def label(scenario: Scenario) -> str:
    """``S1 with pedestrian`` / ``S1 without pedestrian``."""
    return f"{scenario.name} {'with' if scenario.pedestrian.present else 'without'} pedestrian"


def _write_plots(out_dir, scenario, recorder, trace, roadmap) -> None:
    from sse_cosim.reporting import plots

    nodes = scenario.node_ids()
    title = label(scenario)
    plots.save_figure(plots.speed_profile({title: trace}, f"Bus speed: {title}"),
                      out_dir / "speed.png")
    plots.save_figure(plots.set_areas(trace, nodes, f"Set areas: {title}"),
                      out_dir / "set_areas.png")
    for frame in recorder.scenes:
        plots.save_figure(plots.scene(frame, roadmap, nodes, title),
                          out_dir / f"scene_t{frame.time:06.2f}.png")

"""A run's folder: ``trace.csv``, ``truth.csv``, ``pedestrians.csv``, ``sets.jsonl.gz``,
``regions.jsonl.gz``, ``summary.json``, ``scenario.json``, ``replay.html`` and plots (among them
``key_moments.png``) -- or ``error.json`` if the run failed.

Every file is written whole or not at all (:mod:`sse_cosim.files`); ``summary.json`` is
written last, so a folder with a summary is a finished run. With ``summary_only`` (large
sweeps) a run writes ``scenario.json`` and ``summary.json`` only.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import shapely

from sse_cosim.files import AtomicGzip, atomic_path, write_json_atomic, write_text_atomic
from sse_cosim.reporting import replay
from sse_cosim.reporting.recorder import RegionRecord, RunRecorder
from sse_cosim.reporting.shapes import polygon_parts
from sse_cosim.scenario.model import Scenario, present
from sse_cosim.world.roadmap import RoadMap

if TYPE_CHECKING:
    import pandas as pd

TRACE = "trace.csv"
TRUTH = "truth.csv"  # every pedestrian in the scene at every step
TRUTH_COLUMNS = ["t", "pedestrian", "x", "y", "speed", "heading"]  # m, m/s, rad (or empty)
PEDESTRIANS = "pedestrians.csv"  # per step, vehicle and pedestrian: its checks and distance
SETS = "sets.jsonl.gz"  # gzipped, as REGIONS (files.write_text_atomic)
REGIONS = "regions.jsonl.gz"
SUMMARY = "summary.json"
SCENARIO = "scenario.json"
KEY_MOMENTS = "key_moments.png"  # the paper's Fig. 5: the scene at the run's key moments
ERROR = "error.json"  # instead of summary.json: {"key", "error"}, the one line that stopped it
RUNS_FOLDER = "runs"  # a batch, sweep or campaign keeps run <key> in <its folder>/runs/<key>/
DECIMALS = 6  # positions in trace.csv and regions.jsonl.gz: 1e-6 m (a re-check allows 1e-5 m)
POSITIONS = ("bus_x", "bus_y", "x", "y")


@dataclass(frozen=True)
class TaskOutcome:
    """A finished run: its summary, or the one-line error that stopped it."""

    key: str
    summary: dict[str, Any] | None
    error: str | None

    @property
    def ok(self) -> bool:
        return self.error is None


def read_outcome(key: str, folder: Path) -> TaskOutcome | None:
    """The outcome recorded in run ``key``'s ``folder``, if the run already ran to its end."""
    for name, is_summary in ((SUMMARY, True), (ERROR, False)):
        path = folder / name
        if path.is_file():
            try:
                data = json.loads(path.read_text(encoding="utf-8"))
            except (OSError, json.JSONDecodeError):
                return None
            if is_summary:
                return TaskOutcome(key, data, None)
            return TaskOutcome(key, None, str(data.get("error", "unknown error")))
    return None


def write_run(
    out_dir: Path, scenario: Scenario, recorder: RunRecorder, roadmap: RoadMap, source: str,
    route_completed: Mapping[str, bool], plots_wanted: bool = True, summary_only: bool = False,
    extra: Mapping[str, Any] | None = None,
) -> dict:
    """Write every output of one run into ``out_dir``; returns the summary.

    ``route_completed``: per automated vehicle whether it reached the end of its route (the
    simulation's outcome, which the recorder cannot see); ``extra``: more of the simulation's
    outcome for the summary (``assumption_breaks`` of a study that runs on with them).
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    write_json_atomic(out_dir / SCENARIO,
                      {"source": source, **portable_scenario(scenario, out_dir)})
    summary = {"source": source, **recorder.summary(route_completed), **(extra or {})}
    if not summary_only:
        # pandas and matplotlib load only here: a sweep's summary-only runs skip ~1 s of imports
        import pandas as pd

        trace = pd.DataFrame(recorder.rows)
        _write_trace(out_dir / TRACE, trace)
        _write_trace(out_dir / TRUTH,
                     pd.DataFrame(recorder.truth_rows, columns=TRUTH_COLUMNS))
        _write_trace(out_dir / PEDESTRIANS, pd.DataFrame(recorder.pedestrian_rows, columns=[
            "t", "vehicle", "pedestrian", "contained_fused", "contained_refined",
            "accounted_for", "distance"]))
        write_text_atomic(
            out_dir / SETS, "".join(json.dumps(line) + "\n" for line in recorder.set_lines)
        )
        regions = recorder.regions.sink
        if not isinstance(regions, RegionFile) or regions.path != out_dir / REGIONS:
            regions = RegionFile(out_dir / REGIONS)  # a recorder that kept its regions
            regions.add(recorder.regions.records)
        regions.finish()
        if recorder.replay is not None:
            page = replay.replay_page(recorder.replay, scenario, roadmap, label(scenario),
                                      replay.opening_s(summary))
            write_text_atomic(out_dir / replay.REPLAY, page)
        if plots_wanted and not trace.empty:
            _write_plots(out_dir, scenario, recorder, trace, roadmap)
    write_json_atomic(out_dir / SUMMARY, summary)  # last: a folder with it is complete
    return summary


def read_scenario_record(folder: Path) -> dict | None:
    """The run folder's ``scenario.json`` (None if missing or unreadable)."""
    try:
        return json.loads((folder / SCENARIO).read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError):
        return None


def portable_scenario(scenario: Scenario, out_dir: Path) -> dict:
    """The resolved scenario with its network's paths relative to the run folder, where the
    loader looks for them (the file that sets them), so that no machine path is recorded."""
    data = scenario.model_dump(mode="json")
    network = data["network"]
    for key in ("sources_dir", "net_file"):
        if network[key] is not None:
            network[key] = os.path.relpath(network[key], out_dir)
    network["route_files"] = [os.path.relpath(f, out_dir) for f in network["route_files"]]
    return data


REGIONS_LEVEL = 1
"""deflate's level for ``regions.jsonl.gz``: the regions are most of what a long run writes
(line 300 on the whole town: 354 kB of text a step), and deflate at level 1 packs them 17
times as fast as at 9, for 16% more bytes (22% on S3; docs/own_network.md)."""


class RegionFile:
    """``regions.jsonl.gz`` written step by step while the run goes (a
    :class:`~sse_cosim.reporting.recorder.RegionSink`): one :func:`region_line` per record,
    gzipped as it comes (:class:`~sse_cosim.files.AtomicGzip` at :data:`REGIONS_LEVEL`: the
    same bytes as the whole file at once), in place once :meth:`finish` is called (by
    :func:`write_run`, before ``summary.json``); :meth:`discard` drops it if the run stops
    first. A polygon written at the step before, the same to the bit (its WKB), is written
    as the text it had (a group of the unobserved area at rest is the same region step after
    step): the file's bytes do not change, only the work of writing them."""

    def __init__(self, path: Path) -> None:
        self._file = AtomicGzip(path, REGIONS_LEVEL)
        self._texts: dict[bytes, str] = {}  # the latest step's polygons' text, by their WKB

    @property
    def path(self) -> Path:
        """Where it is put in place."""
        return self._file.target

    def add(self, records: Sequence[RegionRecord]) -> None:
        before, self._texts = self._texts, {}
        lines = []
        for record in records:
            parts = polygon_parts(record.region)
            texts = []
            for key, polygon in zip(shapely.to_wkb(parts), parts, strict=True):
                text = self._texts.get(key) or before.get(key) or polygon_text(polygon)
                self._texts[key] = text
                texts.append(text)
            lines.append(region_line(record, texts))
        self._file.write("".join(lines))

    def finish(self) -> None:
        self._file.finish()

    def discard(self) -> None:
        self._file.discard()


def region_line(record: RegionRecord, texts: Sequence[str] | None = None) -> str:
    """One line of ``regions.jsonl.gz``: ``{"t", "vehicle", "kind", "track", "polygons"}``
    (compact JSON: the regions are most of the file). ``texts``: its polygons'
    :func:`polygon_text`, if known."""
    if texts is None:
        texts = [polygon_text(polygon) for polygon in polygon_parts(record.region)]
    head = json.dumps({"t": record.time, "vehicle": record.vehicle, "kind": record.kind,
                       "track": record.track}, separators=(",", ":"))
    return f'{head[:-1]},"polygons":[{",".join(texts)}]}}\n'


def polygon_text(polygon: shapely.Polygon) -> str:
    """One polygon of a ``polygons`` field as compact JSON: its rings (exterior first, then
    holes), each a list of [x, y] rounded to ``DECIMALS``. A region's polygons are its
    non-empty polygons at any depth of nesting (:func:`~sse_cosim.reporting.shapes.polygon_parts`:
    lines and points hold no area, and a region is where a pedestrian may be); ``[]`` if it
    has none."""
    return json.dumps(_rings(polygon), separators=(",", ":"))


def _rings(polygon: shapely.Polygon) -> list[list[list[float]]]:
    """``polygon``'s rings (exterior first, then holes), each a list of [x, y] rounded to
    ``DECIMALS``."""
    rings = [polygon.exterior, *polygon.interiors]
    coordinates = np.round(shapely.get_coordinates(rings), DECIMALS).tolist()  # (n, 2)
    ends = np.cumsum(shapely.get_num_coordinates(rings)).tolist()
    return [coordinates[start:end] for start, end in zip([0, *ends[:-1]], ends, strict=True)]


def _write_trace(path: Path, trace: pd.DataFrame) -> None:
    """A table (``trace.csv``, ``truth.csv``, ...): positions to 1e-6 m, so that the truth can
    be re-checked against ``regions.jsonl.gz`` near a boundary; every other figure to 6
    significant digits."""
    text = trace.copy()
    for column in (c for c in POSITIONS if c in trace):
        text[column] = trace[column].map(
            lambda v: "" if v is None or np.isnan(v) else repr(round(float(v), DECIMALS)))
    with atomic_path(path) as tmp:
        text.to_csv(tmp, index=False, float_format="%.6g")


def label(scenario: Scenario) -> str:
    """``S1 with pedestrian`` / ``S1 without pedestrian``."""
    with_ = "with" if present(scenario.pedestrians) else "without"
    return f"{scenario.name} {with_} pedestrian"


def _write_plots(out_dir, scenario, recorder, trace, roadmap) -> None:
    from sse_cosim.reporting import plots

    nodes = scenario.node_ids()
    title = label(scenario)
    by_vehicle = {vid: rows for vid, rows in trace.groupby("vehicle", sort=False)}
    plots.save_figure(plots.speed_profile(by_vehicle, f"Speed: {title}"), out_dir / "speed.png")
    first = next(iter(by_vehicle))
    plots.save_figure(plots.set_areas(by_vehicle[first], nodes,
                                      f"Set areas ({first}'s fused sets): {title}"),
                      out_dir / "set_areas.png")
    for frame in recorder.scenes:
        plots.save_figure(plots.scene(frame, roadmap, nodes, title),
                          out_dir / f"scene_t{frame.time:06.2f}.png")
    plots.save_figure(plots.key_moments(recorder.key_moments.scenes(), roadmap, nodes, title),
                      out_dir / KEY_MOMENTS)

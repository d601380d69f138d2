"""The paper's Table I and Fig. 7 figures, built from finished run folders.

Everything here reads run folders (``summary.json``, ``trace.csv``, ``scenario.json``), so
``sse-cosim batch`` and ``sse-cosim report`` produce the same tables from the same runs.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd

from sse_cosim.files import atomic_path, write_text_atomic
from sse_cosim.reporting import plots
from sse_cosim.reporting.outputs import SCENARIO, SUMMARY, TRACE
from sse_cosim.reporting.replay import replay_href

# Paper Table I: average speed of the ego vehicle (nominal 20).
PAPER_TABLE1 = {
    ("S1", True): 13.0, ("S1", False): 15.0,
    ("S2", True): 13.1, ("S2", False): 20.0,
    ("S3", True): 13.2, ("S3", False): 20.0,
}
PAPER_SCENARIOS = frozenset(name for name, _ in PAPER_TABLE1)
# Paper Fig. 7: zonotope areas when the shared estimates are first fused (with pedestrian).
PAPER_FIG7 = {
    "S2": {"bus": 50.3, "car": 123.1, "fused": 94.0},
    "S3": {"bus": 100.5, "rsu1": 227.5, "rsu2": 227.5, "fused": 170.0},
}
DIFFERENCE_NOTE = 0.10  # relative difference above which table1.md flags a figure
TABLE1_FILES = {"safe": "", "paper": "_paper"}  # policy -> suffix of its Table I files
POLICY_TITLES = {"safe": "safe policy (the default)", "paper": "the paper's rules"}


@dataclass(frozen=True)
class RunFolder:
    """A finished run read back from disk."""

    path: Path
    summary: dict[str, Any]
    scenario: dict[str, Any]

    @property
    def name(self) -> str:
        return str(self.summary["scenario"])

    @property
    def pedestrian(self) -> bool:
        return bool(self.summary["pedestrian"])

    @property
    def label(self) -> str:
        return f"{self.name} {'with' if self.pedestrian else 'without'} pedestrian"

    @property
    def policy(self) -> str:
        """The speed policy the run used (``controller.policy``)."""
        return str(self.scenario.get("controller", {}).get("policy", "safe"))

    @property
    def nominal_speed_mps(self) -> float:
        """The nominal speed of the run's first automated vehicle (the paper's bus)."""
        first = next(v for v in self.scenario["automated"].values() if v["present"])
        return float(first["nominal_speed_mps"])

    @property
    def faults(self) -> bool:
        """Whether the scenario injects any fault."""
        return any(self.scenario.get("faults", {}).values())

    def trace(self) -> pd.DataFrame:
        return pd.read_csv(self.path / TRACE)


def read_run_folders(folders: Sequence[Path]) -> list[RunFolder]:
    """Every folder among ``folders`` (searched recursively) that holds a finished run.

    Hidden folders (a run's ``.<name>.tmp`` staging folder) are not runs yet.
    """
    runs = []
    for root in folders:
        for summary_path in sorted(Path(root).rglob(SUMMARY)):
            folder = summary_path.parent
            hidden = any(p.startswith(".") for p in folder.relative_to(root).parts)
            if hidden or not (folder / SCENARIO).is_file():
                continue
            runs.append(RunFolder(
                folder,
                json.loads(summary_path.read_text(encoding="utf-8")),
                json.loads((folder / SCENARIO).read_text(encoding="utf-8")),
            ))
    return runs


def table1(runs: Sequence[RunFolder], policy: str = "safe") -> pd.DataFrame:
    """One row per paper scenario run under ``policy``: our average speed beside the
    paper's."""
    rows = []
    for run in _paper_runs(runs, policy):
        s = run.summary
        nodes = s["nodes"]
        paper = PAPER_TABLE1.get((run.name, run.pedestrian))
        first = s["first_detection"].get("fused", {})
        rows.append({
            "scenario": run.name,
            "shared_awareness": len(nodes) > 1,
            "pedestrian": run.pedestrian,
            "sensors": " + ".join(_node_label(n) for n in nodes),
            "average_speed_mps": round(s["average_speed_mps"], 2),
            "paper_average_speed": paper,
            "nominal_speed_mps": run.nominal_speed_mps,
            "first_detection_bus_to_crossing_m": _round(first.get("bus_distance_to_crossing_m")),
            "min_distance_bus_pedestrian_m": _round(s["min_distance_bus_pedestrian_m"]),
            "containment_violations": s["containment_violations"],
            "collisions": s["collisions"],
            "time_stopped_s": s.get("time_stopped_s"),
            "emergency_share": round(s["level_share"].get("emergency", 0.0), 4),
        })
    return pd.DataFrame(rows)


def fig7(runs: Sequence[RunFolder]) -> pd.DataFrame:
    """Set areas at the first shared fusion of the paper's scenarios (default policy), beside
    the paper's Fig. 7 values."""
    rows = []
    for run in runs:
        shared = run.summary.get("first_shared_fusion")
        if not run.pedestrian or not shared or run.faults or run.policy != "safe" \
                or run.name not in PAPER_FIG7:
            continue
        paper = PAPER_FIG7.get(run.name, {})
        areas = {**shared["input_areas_m2"], "fused": shared["fused_area_m2"]}
        for node, area in areas.items():
            rows.append({"scenario": run.name, "t": shared["t"], "set": node,
                         "area_m2": round(area, 2), "paper_area": paper.get(node)})
    return pd.DataFrame(rows)


def fault_table(runs: Sequence[RunFolder]) -> pd.DataFrame:
    """One row per injected fault: when it was noticed and whether the fused set held."""
    rows = []
    for run in sorted((r for r in runs if r.faults), key=lambda r: r.name):
        s = run.summary
        for fault in s.get("faults", []):
            rows.append({
                "scenario": run.name,
                "fault": fault["fault"],
                "kind": fault["kind"],
                "target": fault["target"],
                "detection_delay_steps": fault["detection_delay_steps"],
                "fused_violations_after_detection": fault["fused_violations_after_detection"],
                "containment_violations": s["containment_violations"],
                "average_speed_mps": round(s["average_speed_mps"], 2),
                "collisions": s["collisions"],
            })
    return pd.DataFrame(rows)


def _paper_runs(runs: Sequence[RunFolder], policy: str) -> list[RunFolder]:
    """The runs of Table I's rows under ``policy``, in its order."""
    chosen = [r for r in runs if (r.name, r.pedestrian) in PAPER_TABLE1 and not r.faults
              and r.policy == policy]
    return sorted(chosen, key=lambda r: (r.name, not r.pedestrian))


def replay_links(runs: Sequence[RunFolder], out_dir: Path) -> str:
    """A Markdown line linking each run's ``replay.html`` (relative to ``out_dir``; runs
    without one, e.g. summaries only, are left out); empty if none has one."""
    links = [f"[{run.label}]({href})" for run in runs
             if (href := replay_href(run.path, out_dir)) is not None]
    return f"\nEach run in the browser (`replay.html`): {', '.join(links)}.\n" if links else ""


def write_paper_report(out_dir: Path, runs: Sequence[RunFolder]) -> list[Path]:
    """``table1.csv``/``.md``, ``fig7_set_sizes.csv``, combined speed and set-size figures."""
    written = []
    for policy, suffix in TABLE1_FILES.items():
        table = table1(runs, policy)
        if table.empty:
            continue
        written.append(_csv(table, out_dir / f"table1{suffix}.csv"))
        written.append(write_text_atomic(
            out_dir / f"table1{suffix}.md",
            table1_markdown(table, policy) + replay_links(_paper_runs(runs, policy), out_dir)))
        chosen = [r for r in runs if r.policy == policy]
        written.append(plots.save_figure(_speed_panels(chosen),
                                         out_dir / f"speed_profiles{suffix}.png"))
    faults = fault_table(runs)
    if not faults.empty:
        written.append(_csv(faults, out_dir / "faults.csv"))
        written.append(write_text_atomic(out_dir / "faults.md", _faults_markdown(faults)))
    sizes = fig7(runs)
    if not sizes.empty:
        written.append(_csv(sizes, out_dir / "fig7_set_sizes.csv"))
        figure = plots.set_size_bars(sizes)
        written.append(plots.save_figure(figure, out_dir / "fig7_set_sizes.png"))
    return written


def table1_markdown(table: pd.DataFrame, policy: str = "safe") -> str:
    """Table I as Markdown, with a note wherever our figure differs from the paper's."""
    header = ("| Scenario | Shared awareness | Pedestrian | Sensors | Average speed (m/s) "
              "| Paper | First detection: bus to crossing (m) | Min. distance (m) "
              "| Stopped (s) | Violations | Collisions |\n"
              "|---|---|---|---|---|---|---|---|---|---|---|\n")
    lines, notes = [], []
    for row in table.itertuples(index=False):
        tick = lambda flag: "✓" if flag else "–"  # noqa: E731
        lines.append(
            f"| {row.scenario} | {tick(row.shared_awareness)} | {tick(row.pedestrian)} "
            f"| {row.sensors} | {row.average_speed_mps:.1f} | {_fmt(row.paper_average_speed)} "
            f"| {_fmt(row.first_detection_bus_to_crossing_m)} "
            f"| {_fmt(row.min_distance_bus_pedestrian_m)} | {_fmt(row.time_stopped_s)} "
            f"| {row.containment_violations} | {row.collisions} |"
        )
        paper = row.paper_average_speed
        if paper is not None and abs(row.average_speed_mps - paper) > DIFFERENCE_NOTE * paper:
            notes.append(
                f"- {row.scenario} {'with' if row.pedestrian else 'without'} pedestrian: "
                f"{row.average_speed_mps:.1f} m/s against the paper's {paper:.1f} m/s."
            )
    text = (f"# Table I: average bus speed, {POLICY_TITLES[policy]}\n\n" + header
            + "\n".join(lines) + "\n")
    if notes:
        text += ("\nWhere our figures differ from the paper's by more than "
                 f"{DIFFERENCE_NOTE:.0%} (see `docs/results.md` for why):\n\n"
                 + "\n".join(notes) + "\n")
    return text


def _faults_markdown(faults: pd.DataFrame) -> str:
    """The fault table as Markdown; 'never' where a fault was not (or cannot be) detected."""
    lines = ["# Injected faults\n",
             "| Scenario | Fault | Kind | Target | Detected after (steps) "
             "| Fused misses after detection | Violations (run) | Avg. speed (m/s) | Collisions |",
             "|---|---|---|---|---|---|---|---|---|"]
    for row in faults.itertuples(index=False):
        delay = "never" if pd.isna(row.detection_delay_steps) else int(row.detection_delay_steps)
        after = ("–" if pd.isna(row.fused_violations_after_detection)
                 else int(row.fused_violations_after_detection))
        lines.append(f"| {row.scenario} | {row.fault} | {row.kind} | {row.target} | {delay} "
                     f"| {after} | {row.containment_violations} | {row.average_speed_mps:.1f} "
                     f"| {row.collisions} |")
    return "\n".join(lines) + "\n\nWhat can and cannot be detected: `docs/faults.md`.\n"


def _speed_panels(runs: Sequence[RunFolder]):
    paper = sorted((r for r in runs if not r.faults and r.name in PAPER_SCENARIOS),
                   key=lambda r: r.name)
    with_ped = {r.label: r.trace() for r in paper if r.pedestrian}
    without = {r.label: r.trace() for r in paper if not r.pedestrian}
    return plots.speed_panels(with_ped, without)


def _csv(frame: pd.DataFrame, target: Path) -> Path:
    with atomic_path(target) as tmp:
        frame.to_csv(tmp, index=False)
    return target


def _node_label(node: str) -> str:
    return {"bus": "local sensor", "car": "connected vehicle"}.get(node, f"road-side unit {node}")


def _round(value) -> float | None:
    return None if value is None else round(float(value), 1)


def _fmt(value) -> str:
    return "–" if value is None or value != value else f"{value:.1f}"

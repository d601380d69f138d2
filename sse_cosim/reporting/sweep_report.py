"""A sweep's table and figures, rebuilt from its plan (``sweep.json``) and its run folders.

``sweep.csv`` (and ``sweep.parquet`` when pyarrow imports) has one row per planned run, in
plan order, read from the finished run folders: it never depends on the order in which
runs finished, on the executor or on the number of workers. ``sweep_<figure>.png`` shows
each figure against the swept parameters (see :func:`sweep_figure`).

Parameter values that are lists (a noise bound ``[0.5, 0.5]``) are JSON strings in the
table, and are plotted at their largest absolute component (the infinity norm: for a
noise box ``[r, r]`` that is ``r``), labelled in words (``0.5 × 0.5``).
``sweep_uncertainty.md`` says what the seeds leave uncertain (:mod:`.uncertainty`).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from matplotlib import pyplot as plt
from matplotlib.figure import Figure

from sse_cosim.files import atomic_path, read_plan, write_text_atomic
from sse_cosim.reporting import plots
from sse_cosim.reporting.outputs import RUNS_FOLDER, TaskOutcome, read_outcome
from sse_cosim.reporting.safety_report import markdown_table
from sse_cosim.reporting.uncertainty import (
    Difference,
    detectable,
    differences,
    intervals,
    pooled_std,
)

SWEEP_PLAN = "sweep.json"
SWEEP_TABLE = "sweep.csv"
SWEEP_PARQUET = "sweep.parquet"
SWEEP_UNCERTAINTY = "sweep_uncertainty.md"

# Table column -> where the figure sits in a run's summary.json.
FIGURES: dict[str, tuple[str, ...]] = {
    "average_speed_mps": ("average_speed_mps",),
    "travel_time_s": ("travel_time_s",),
    "distance_travelled_m": ("distance_travelled_m",),
    "min_distance_bus_pedestrian_m": ("min_distance_bus_pedestrian_m",),
    "first_detection_fused_t_s": ("first_detection", "fused", "t"),
    "first_detection_fused_bus_to_crossing_m":
        ("first_detection", "fused", "bus_distance_to_crossing_m"),
    "fused_area_mean_m2": ("set_area_m2", "fused", "mean"),
    "fused_area_max_m2": ("set_area_m2", "fused", "max"),
    "refined_area_mean_m2": ("set_area_m2", "possible", "mean"),
    "refined_area_max_m2": ("set_area_m2", "possible", "max"),
    "first_shared_fusion_t_s": ("first_shared_fusion", "t"),
    "first_shared_fusion_area_m2": ("first_shared_fusion", "fused_area_m2"),
    "containment_violations": ("containment_violations",),
    "fusion_larger_than_input": ("fusion_larger_than_input",),
    "collisions": ("collisions",),
    "contact_steps": ("contact_steps",),
    "time_stopped_s": ("time_stopped_s",),
    "first_stop_bus_to_crossing_m": ("first_stop", "bus_distance_to_crossing_m"),
    "longest_standstill_after_clear_s": ("longest_standstill_after_clear_s",),
    "longest_needless_hold_s": ("longest_needless_hold_s",),
    "route_completed": ("route_completed",),
    "steps": ("steps",),
}
COUNTS = ("containment_violations", "fusion_larger_than_input", "collisions", "contact_steps",
          "steps")
LEVEL_SHARE = "level_share"  # one column per speed level: level_share_<level>
PLOTTED = (
    "average_speed_mps", "time_stopped_s", "travel_time_s", "min_distance_bus_pedestrian_m",
    "first_detection_fused_bus_to_crossing_m", "fused_area_mean_m2", "fused_area_max_m2",
    "refined_area_mean_m2", "containment_violations", "collisions",
)
# The figures whose uncertainty over seeds is reported (sweep_uncertainty.md, report.html):
# the bus's speed, and the figures that respond where the average speed hardly does.
RESPONDING = ("average_speed_mps", "time_stopped_s", "first_stop_bus_to_crossing_m",
              "min_distance_bus_pedestrian_m", "first_detection_fused_bus_to_crossing_m",
              "longest_needless_hold_s")
# The short table (terminal, report): figure -> how runs of one combination are combined.
SUMMARY_COLUMNS = {
    "average_speed_mps": "mean", "time_stopped_s": "mean", "travel_time_s": "mean",
    "min_distance_bus_pedestrian_m": "min", "first_detection_fused_bus_to_crossing_m": "mean",
    "fused_area_mean_m2": "mean", "containment_violations": "sum", "collisions": "sum",
}


@dataclass(frozen=True)
class SweepFolder:
    """A sweep's output folder and its plan."""

    path: Path
    plan: dict[str, Any]

    @property
    def parameters(self) -> list[dict[str, Any]]:
        """``{"column", "path", "values"}`` per swept parameter, in order."""
        return self.plan["parameters"]

    @property
    def columns(self) -> list[str]:
        return [p["column"] for p in self.parameters]

    @property
    def runs(self) -> list[dict[str, Any]]:
        return self.plan["runs"]

    def run_folder(self, key: str) -> Path:
        return self.path / RUNS_FOLDER / key

    def outcome(self, run: Mapping[str, Any]) -> TaskOutcome | None:
        """The run's recorded outcome; ``None`` while it has not finished."""
        return read_outcome(run["key"], self.run_folder(run["key"]))


def read_sweep(folder: Path) -> SweepFolder:
    """The sweep in ``folder`` (its ``sweep.json``)."""
    return SweepFolder(folder, read_plan(folder / SWEEP_PLAN, "sse-cosim sweep"))


def find_sweeps(folders: Sequence[Path]) -> list[SweepFolder]:
    """Every sweep folder among ``folders`` (searched recursively, hidden folders skipped)."""
    found = {
        plan.parent.resolve(): plan.parent
        for root in folders for plan in sorted(Path(root).rglob(SWEEP_PLAN))
        if not any(part.startswith(".") for part in plan.parent.relative_to(root).parts)
    }
    return [read_sweep(path) for path in found.values()]


def summary_figures(summary: Mapping[str, Any] | None) -> dict[str, Any]:
    """A run's summary flattened into the table's figure columns (``None`` where absent)."""
    summary = summary or {}
    row: dict[str, Any] = {}
    for column, where in FIGURES.items():
        value: Any = summary
        for part in where:
            value = value.get(part) if isinstance(value, Mapping) else None
        row[column] = value
    for level, share in (summary.get(LEVEL_SHARE) or {}).items():
        row[f"{LEVEL_SHARE}_{level.replace(' ', '_')}"] = share
    return row


def sweep_table(sweep: SweepFolder) -> pd.DataFrame:
    """One row per planned run: scenario, seed, parameters, status, error, figures."""
    cells = {p["column"]: _cells(p["values"]) for p in sweep.parameters}
    rows = []
    for run in sweep.runs:
        outcome = sweep.outcome(run)
        status = "missing" if outcome is None else "ok" if outcome.ok else "failed"
        rows.append({
            "key": run["key"], "scenario": run["scenario"], "seed": run["seed"],
            **{col: cells[col][_identity(v)] for col, v in run["values"].items()},
            "status": status,
            "error": (outcome.error if outcome is not None else None) or "",
            **summary_figures(outcome.summary if outcome is not None else None),
        })
    table = pd.DataFrame(rows)
    for column in COUNTS:
        if column in table:
            table[column] = table[column].astype("Int64")
    return table


def summary_table(table: pd.DataFrame, columns: Sequence[str]) -> pd.DataFrame:
    """Runs of each scenario x parameter combination combined: counts and key figures."""
    keys = ["scenario", *columns]
    figures = {f: (f, _total if how == "sum" else how)
               for f, how in SUMMARY_COLUMNS.items() if f in table}
    grouped = table.groupby(keys, sort=False, dropna=False)
    return grouped.agg(
        runs=("key", "size"), failed=("status", lambda s: int((s != "ok").sum())), **figures
    ).reset_index()


def _total(values: pd.Series) -> float:
    """The sum of the finished runs' counts; NaN where none finished (a failed run counted
    nothing, which is not 0 collisions)."""
    return values.sum(min_count=1)


def write_sweep_report(folder: Path) -> list[Path]:
    """Rebuild ``sweep.csv``, ``sweep.parquet`` (if pyarrow imports) and the sweep figures."""
    sweep = read_sweep(folder)
    table = sweep_table(sweep)
    written = []
    with atomic_path(folder / SWEEP_TABLE) as tmp:
        table.to_csv(tmp, index=False)
    written.append(folder / SWEEP_TABLE)
    if _pyarrow_imports():
        with atomic_path(folder / SWEEP_PARQUET) as tmp:
            table.to_parquet(tmp, index=False)
        written.append(folder / SWEEP_PARQUET)
    for figure in PLOTTED:
        fig = sweep_figure(sweep, table, figure)
        if fig is not None:
            written.append(plots.save_figure(fig, folder / f"sweep_{figure}.png"))
    written.append(write_text_atomic(folder / SWEEP_UNCERTAINTY,
                                     uncertainty_markdown(uncertainty(sweep, table))))
    return written


@dataclass(frozen=True)
class FigureUncertainty:
    """One figure's uncertainty over seeds in a sweep (:mod:`.uncertainty`): per scenario and
    combination its runs, mean and 95 % interval (``table``, in words), the differences
    between neighbouring levels, and the seeds' pooled standard deviation ``sigma`` with the
    least difference the sweep's seeds tell apart (``detectable``)."""

    figure: str
    table: pd.DataFrame
    differences: list[Difference]
    sigma: float
    seeds: int
    detectable: float


def uncertainty(sweep: SweepFolder, table: pd.DataFrame,
                figures: Sequence[str] = RESPONDING) -> list[FigureUncertainty]:
    """:class:`FigureUncertainty` of each of ``figures`` that the finished runs give."""
    keys = ["scenario", *sweep.columns]
    finished = table[table["status"] == "ok"] if "status" in table else table
    found = []
    for figure in figures:
        if figure not in finished or finished[figure].dropna().empty:
            continue
        groups = intervals(finished.astype({figure: float}), keys, figure)
        steps: list[Difference] = []
        for parameter in sweep.parameters:
            column = parameter["column"]
            labels = _level_words(parameter["values"])  # in the order of the values
            others = [c for c in sweep.columns if c != column]
            steps += differences(groups, column, list(labels), others, figure, labels)
        sigma = pooled_std(groups)
        seeds = int(groups["n"].min())
        shown = groups[keys].assign(
            **{p["column"]: groups[p["column"]].map(_level_words(p["values"]))
               for p in sweep.parameters},
            runs=groups["n"], mean=groups["mean"].map(lambda v: f"{v:.4g}"),
            interval=[_interval(low, high) for low, high in zip(groups["low"], groups["high"],
                                                                 strict=True)])
        found.append(FigureUncertainty(figure, shown, steps, sigma, seeds,
                                       detectable(sigma, seeds)))
    return found


def _level_words(values: Sequence[Any]) -> dict[Any, str]:
    """A parameter's table cells, each by its value in words (:func:`value_label`)."""
    cells = _cells(values)
    return {cells[_identity(v)]: value_label(v) for v in values}


def _interval(low: float, high: float) -> str:
    return "–" if pd.isna(low) else f"{low:.4g} to {high:.4g}"


def uncertainty_markdown(items: Sequence[FigureUncertainty]) -> str:
    """``sweep_uncertainty.md``: each figure's table of intervals and its differences."""
    lines = ["# What the seeds leave uncertain", "",
             "Per scenario and combination of parameter values: the runs (one per seed), the "
             "mean and Student's 95 % confidence interval of the mean. Between neighbouring "
             "levels of a parameter: the difference of the means with Welch's 95 % interval; "
             "it exceeds the seeds' spread where that interval leaves out zero "
             "(sse_cosim/reporting/uncertainty.py).", ""]
    for item in items:
        label = figure_label(item.figure)
        lines += [f"## {label}", "", markdown_table(item.table.astype(str).to_dict("records")),
                  ""]
        if item.sigma == 0.0:
            lines += ["Every seed gives the same value at each combination: any difference "
                      "between levels is the parameter's.", ""]
        elif not math.isnan(item.detectable):
            lines += [f"The seeds spread by {item.sigma:.3g} (standard deviation pooled over "
                      f"the combinations); with {item.seeds} seeds per level, differences "
                      f"below {item.detectable:.3g} are not told apart (95 % confidence, 80 % "
                      "power; `sse-cosim sweep --detect` says how many seeds a difference "
                      "needs).", ""]
        exceed = [d for d in item.differences if d.exceeds]
        lines += [f"{len(exceed)} of {len(item.differences)} differences between neighbouring "
                  "levels exceed the seeds' spread:", ""]
        lines += [f"- {d.line(label)}" for d in item.differences] or ["- none (one level)"]
        lines.append("")
    return "\n".join(lines)


def sweep_figure(sweep: SweepFolder, table: pd.DataFrame, figure: str) -> Figure | None:
    """``figure`` against the swept parameters; ``None`` without parameters or data.

    Two parameters: one heat map per scenario (mean over seeds). Otherwise one panel per
    parameter, one line per scenario: the mean over the other runs (seeds and any other
    parameter) with a band from their minimum to their maximum.
    """
    if not sweep.parameters or figure not in table or table[figure].dropna().empty:
        return None
    axes = [_Axis.of(p, sweep.runs) for p in sweep.parameters]
    frame = table.assign(**{axis.x: axis.positions for axis in axes})
    if len(axes) == 2:
        return _heat_maps(frame, axes[0], axes[1], figure)
    return _lines(frame, axes, figure)


def parameter_scalar(value: Any) -> float | None:
    """Where a parameter value sits on a plot axis: numbers as they are, lists at their
    largest absolute component, anything else ``None`` (the axis is then categorical)."""
    if isinstance(value, bool | int | float):
        return float(value)
    if isinstance(value, list) and value and all(
            isinstance(v, int | float) and not isinstance(v, bool) for v in value):
        return float(max(abs(v) for v in value))
    return None


@dataclass(frozen=True)
class _Axis:
    """A parameter on a plot axis: each run's position, and tick labels by position."""

    column: str
    x: str
    positions: list[float]
    ticks: dict[float, str]

    @classmethod
    def of(cls, parameter: Mapping[str, Any], runs: Sequence[Mapping[str, Any]]) -> _Axis:
        values = parameter["values"]
        scalars = [parameter_scalar(v) for v in values]
        categorical = any(s is None for s in scalars) or len(set(scalars)) < len(scalars)
        place = {_identity(v): float(i) if categorical else scalars[i]
                 for i, v in enumerate(values)}
        ticks = {place[_identity(v)]: value_label(v) for v in values}
        column = parameter["column"]
        return cls(column, f"__x_{column}",
                   [place[_identity(run["values"][column])] for run in runs], ticks)

    def decorate(self, ax) -> None:
        """Label the x axis with the parameter in words and (up to 12) its values."""
        if len(self.ticks) <= 12:
            ax.set_xticks(list(self.ticks), list(self.ticks.values()), fontsize=8)
        ax.set_xlabel(parameter_label(self.column), fontsize=9)


def _lines(frame: pd.DataFrame, axes: Sequence[_Axis], figure: str) -> Figure:
    """One panel per parameter, one curve per scenario: the mean over the other runs with
    its 95 % interval as a band (:func:`~sse_cosim.reporting.uncertainty.intervals`). Curves
    that lie on one another are drawn in their own styles and marked as coinciding; a figure
    that is never negative is shown from zero, so that a flat result looks flat."""
    fig, grid = plt.subplots(1, len(axes), figsize=(5.5 * len(axes), 4), squeeze=False)
    values = frame[figure].dropna().astype(float)
    for ax, axis in zip(grid[0], axes, strict=True):
        groups = intervals(frame.astype({figure: float}), ["scenario", axis.x], figure)
        curves = [(str(scenario), rows[axis.x].to_numpy(), rows["mean"].to_numpy(), rows)
                  for scenario, rows in ((scenario, rows.sort_values(axis.x)) for scenario, rows
                                         in groups.groupby("scenario", sort=False))]
        labels = plots.coinciding_labels([(name, x, y) for name, x, y, _ in curves])
        for i, ((_, x, y, rows), label) in enumerate(zip(curves, labels, strict=True)):
            style = plots.curve_style(i, len(x))
            ax.plot(x, y, label=label, **style)
            ax.fill_between(x, rows["low"], rows["high"], color=style["color"], alpha=0.2)
        axis.decorate(ax)
        ax.set_ylabel(figure_label(figure))
        if (values >= 0.0).all():
            top = float(np.nanmax(groups[["mean", "high"]].to_numpy(dtype=float)))
            ax.set_ylim(0.0, 1.1 * top if top > 0.0 else 1.0)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"{figure_label(figure)}: mean over seeds, band: its 95 % interval",
                 fontsize=11)
    fig.tight_layout()
    return fig


def _heat_maps(frame: pd.DataFrame, across: _Axis, down: _Axis, figure: str) -> Figure:
    scenarios = list(dict.fromkeys(frame["scenario"]))
    fig, grid = plt.subplots(1, len(scenarios), figsize=(5.5 * len(scenarios), 4.2),
                             squeeze=False)
    for ax, scenario in zip(grid[0], scenarios, strict=True):
        runs = frame[frame["scenario"] == scenario]
        means = (runs.groupby([down.x, across.x])[figure].mean().astype(float)
                 .unstack().reindex(index=sorted(down.ticks), columns=sorted(across.ticks)))
        image = ax.imshow(means.to_numpy(), origin="lower", aspect="auto", cmap="viridis")
        for (row, col), value in pd.DataFrame(means.to_numpy()).stack().items():
            ax.text(col, row, f"{value:.3g}", ha="center", va="center", fontsize=8,
                    color="black" if image.norm(value) > 0.6 else "white")
        ax.set_xticks(range(len(across.ticks)), [across.ticks[x] for x in means.columns],
                      fontsize=8)
        ax.set_yticks(range(len(down.ticks)), [down.ticks[y] for y in means.index], fontsize=8)
        ax.set_xlabel(parameter_label(across.column), fontsize=9)
        ax.set_ylabel(parameter_label(down.column), fontsize=9)
        ax.set_title(scenario, fontsize=10)
        fig.colorbar(image, ax=ax, label=figure_label(figure))
    fig.suptitle(f"{figure_label(figure)}: mean over seeds", fontsize=11)
    fig.tight_layout()
    return fig


def _cells(values: Sequence[Any]) -> dict[str, Any]:
    """How a parameter's values appear in the table: numbers, strings or booleans as they
    are when all values are of one such kind, JSON text otherwise (lists, mixtures)."""
    kinds = {bool if isinstance(v, bool) else float if isinstance(v, int | float) else type(v)
             for v in values}
    plain = len(kinds) == 1 and kinds <= {bool, float, str}
    return {_identity(v): v if plain else json.dumps(v) for v in values}


def _identity(value: Any) -> str:
    return json.dumps(value, sort_keys=True)


def value_label(value: Any) -> str:
    """A parameter value in words: a list of numbers as ``0.5 × 0.5``, others as they are."""
    if isinstance(value, list) and all(isinstance(v, int | float) for v in value):
        return " × ".join(f"{v:g}" for v in value)
    return str(value)


_UNITS = {"_mps": "m/s", "_m2": "m²", "_m": "m", "_s": "s"}


def parameter_label(column: str) -> str:
    """A swept parameter in words: ``sensors.*[node!=bus].noise_bound_m`` -> ``noise bound
    (m) of sensors.*[node!=bus]``, ``shared_noise_bound_m`` -> ``shared noise bound (m)``."""
    where, _, field = column.rpartition(".")
    return figure_label(field) + (f" of {where}" if where else "")


def figure_label(figure: str) -> str:
    """``travel_time_s`` -> ``travel time (s)``."""
    for suffix, unit in _UNITS.items():
        if figure.endswith(suffix):
            return f"{figure.removesuffix(suffix).replace('_', ' ')} ({unit})"
    return figure.replace("_", " ")


def _pyarrow_imports() -> bool:
    """Parquet is optional (extra ``parquet``): write it only where pyarrow imports."""
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        return False
    return True

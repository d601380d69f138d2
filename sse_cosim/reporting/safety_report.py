"""The safety campaign's report, rebuilt from its plan (``safety.json.gz``) and its run folders.

Every figure comes from a run's ``summary.json``, read by its key (:data:`COLLISIONS` ...). A
key that a summary lacks is never given a value: the run is left out of that figure, the
report says in how many runs the key is missing, and a target that depends on it is not
shown (which is not met). Nothing here depends on the machine, the clock, the executor or
the order in which runs finished, so a rerun anywhere gives the same files.

Written into the campaign folder: ``safety.csv`` (one row per combination, in plan order,
the ones not run included) and two heat maps per scenario over step-out time x walking
speed. The report itself, ``<folder>.md``, is written beside the folder (``results/safety/``
-> ``results/safety.md``) and links to the heat maps inside it.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable, Mapping, Sequence
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

SAFETY_PLAN = "safety.json.gz"  # gzipped: it lists every run (files.write_text_atomic)
SAFETY_TABLE = "safety.csv"
STANDSTILL_LIMIT_S = 3.0

# Keys of a run's summary.json.
COLLISIONS = "collisions"
VIOLATIONS = "containment_violations"
VIOLATIONS_BY_SET = "containment_violations_by_set"
ROUTE_COMPLETED = "route_completed"
STANDSTILL = "longest_needless_hold_s"  # liveness measured from the truth
MIN_DISTANCE = "min_distance_bus_pedestrian_m"
SPEED = "average_speed_mps"
STOPPED = "time_stopped_s"
# The pedestrian the campaign moves (sse_cosim.runner.safety) and its own least distance to a
# bus, read from the summary's ``pedestrians.<id>.min_distance_m``: where other pedestrians
# walk nearer a bus (the crowd, the junction), MIN_DISTANCE is theirs, not the hard case's.
CAMPAIGN_PEDESTRIAN = "pedestrian"
OWN_DISTANCE = "min_distance_campaign_pedestrian_m"
KEYS = (COLLISIONS, VIOLATIONS, VIOLATIONS_BY_SET, ROUTE_COMPLETED, STANDSTILL, MIN_DISTANCE,
        OWN_DISTANCE, SPEED, STOPPED)
MISSING = "missing_keys"  # table column: the keys a run's summary lacks (or gives as null)

OK, FAILED, UNFINISHED, NOT_FEASIBLE = "ok", "failed", "missing", "not feasible"
LISTED_MAX = 5  # runs named per target, in the report and on the terminal


@dataclass(frozen=True)
class _HeatMap:
    name: str  # in the file name
    how: str  # how the runs of one cell combine
    label: str


HEAT_MAPS = {  # summary key -> its heat map
    SPEED: _HeatMap("average_speed", "mean", "average speed (m/s)"),
    MIN_DISTANCE: _HeatMap("min_distance", "min", "minimum distance bus-pedestrian (m)"),
}


# -- reading ---------------------------------------------------------------------------------

@dataclass(frozen=True)
class CampaignFolder:
    """A campaign's output folder and its plan."""

    path: Path
    plan: dict[str, Any]

    @property
    def columns(self) -> list[str]:
        """The axes' columns, in plan order."""
        return [axis["column"] for axis in self.plan["axes"]]

    def outcome(self, key: str) -> TaskOutcome | None:
        """The run's recorded outcome; ``None`` while it has not finished."""
        return read_outcome(key, self.path / RUNS_FOLDER / key)


def read_campaign(folder: Path) -> CampaignFolder:
    """The campaign in ``folder`` (its ``safety.json.gz``)."""
    return CampaignFolder(folder, read_plan(folder / SAFETY_PLAN, "sse-cosim safety"))


def run_figures(summary: Mapping[str, Any]) -> dict[str, Any]:
    """The campaign's figures of one summary: each key's value (``None`` where absent; the
    per-set violations as JSON text; :data:`OWN_DISTANCE` from the campaign pedestrian's
    entry) and, under :data:`MISSING`, the keys that are absent or null (either way the run
    has no value for that figure)."""
    row: dict[str, Any] = {key: summary.get(key) for key in KEYS}
    own = (summary.get("pedestrians") or {}).get(CAMPAIGN_PEDESTRIAN) or {}
    row[OWN_DISTANCE] = own.get("min_distance_m")
    if row[VIOLATIONS_BY_SET] is not None:
        row[VIOLATIONS_BY_SET] = json.dumps(row[VIOLATIONS_BY_SET], sort_keys=True)
    row[MISSING] = " ".join(key for key in KEYS if row[key] is None)
    return row


def campaign_table(campaign: CampaignFolder) -> pd.DataFrame:
    """One row per combination, in plan order (runs, then those not feasible): key,
    scenario, seed, one column per axis, status, error or reason, the figures."""
    rows = []
    for run in campaign.plan["runs"]:
        outcome = campaign.outcome(run["key"])
        status = UNFINISHED if outcome is None else OK if outcome.ok else FAILED
        figures = run_figures(outcome.summary) if outcome is not None and outcome.ok else {}
        rows.append({**_identity(campaign, run), "status": status,
                     "error": (outcome.error if outcome is not None else None) or "",
                     **figures})
    for run in campaign.plan["not_feasible"]:
        rows.append({**_identity(campaign, run), "status": NOT_FEASIBLE, "error": run["reason"]})
    table = pd.DataFrame(rows, columns=["key", "scenario", "seed", *campaign.columns, "status",
                                        "error", *KEYS, MISSING])
    for column in (COLLISIONS, VIOLATIONS):
        table[column] = table[column].astype("Int64")
    table[ROUTE_COMPLETED] = table[ROUTE_COMPLETED].astype("boolean")
    for column in (STANDSTILL, MIN_DISTANCE, OWN_DISTANCE, SPEED, STOPPED):
        table[column] = table[column].astype("Float64")
    table[MISSING] = table[MISSING].astype(object).fillna("").astype(str)
    return table


def _identity(campaign: CampaignFolder, run: Mapping[str, Any]) -> dict[str, Any]:
    values = run["values"]
    return {"key": run["key"], "scenario": run["scenario"], "seed": run["seed"],
            **{c: _cell(values[c]) if c in values else None for c in campaign.columns}}


def _cell(value: Any) -> Any:
    return json.dumps(value) if isinstance(value, list) else value


# -- targets ---------------------------------------------------------------------------------

@dataclass(frozen=True)
class TargetCheck:
    """One safety target over the finished runs.

    ``met`` is ``None`` when it is not shown: some finished run's summary lacks the key (and
    no run breaks it), or no run finished. ``offenders`` are (key, value) of the runs that
    break it, worst first; ``missing`` the keys of runs whose summary lacks the figure.
    """

    label: str
    measured: str
    met: bool | None
    offenders: tuple[tuple[str, str], ...]
    missing: tuple[str, ...]

    @property
    def verdict(self) -> str:
        return {True: "met", False: "MISSED", None: "not shown"}[self.met]

    def breaking_lines(self) -> list[str]:
        """Lines naming the runs that break the target and those whose summary lacks its
        key (the first :data:`LISTED_MAX` of each); none when it is met."""
        lines = []
        if self.offenders:
            shown = ", ".join(f"{key} ({value})" for key, value in self.offenders[:LISTED_MAX])
            lines.append(f"MISSED {self.label}: {shown}{_more(len(self.offenders))}")
        if self.missing:
            lines.append(f"NOT SHOWN {self.label}: {len(self.missing)} summaries lack the key: "
                         + ", ".join(self.missing[:LISTED_MAX]) + _more(len(self.missing)))
        if self.met is None and not self.missing:
            lines.append(f"NOT SHOWN {self.label}: no run finished")
        return lines


@dataclass(frozen=True)
class _Target:
    key: str
    label: str
    breaks: Callable[[pd.Series], pd.Series]  # per run: does it break the target?
    measure: Callable[[pd.Series, int], str]  # values present, runs breaking -> text
    worst_first: bool  # sort offenders by value, largest first (else plan order)


def _total(values: pd.Series, breaking: int) -> str:
    where = f"in {breaking} of" if breaking else "over"
    return f"{int(values.sum())} {where} {len(values)} runs"


TARGETS = (
    _Target(COLLISIONS, "collisions (events) = 0", lambda v: v > 0, _total, True),
    _Target(VIOLATIONS, "containment violations (every set, refined region) = 0",
            lambda v: v > 0, _total, True),
    _Target(ROUTE_COMPLETED, "runs that never finish the route = 0", lambda v: ~v,
            lambda v, n: f"{n} of {len(v)} runs", False),
    _Target(STANDSTILL, "longest hold (creep, stop, brake) while the truth left the path clear "
            f"<= {STANDSTILL_LIMIT_S:g} s",
            lambda v: v > STANDSTILL_LIMIT_S,
            lambda v, n: f"max {_num(v.max())} s over {len(v)} runs", True),
)


def check_targets(table: pd.DataFrame) -> list[TargetCheck]:
    """Every target over the finished runs of ``table``."""
    done = table[table["status"] == OK]
    return [_check(target, done) for target in TARGETS]


def _check(target: _Target, done: pd.DataFrame) -> TargetCheck:
    missing = done[_lacks(done, target.key)]
    present = done[done[target.key].notna()]
    values = present[target.key]
    broken = present[target.breaks(values).astype(bool)]
    if target.worst_first:
        broken = broken.sort_values(target.key, ascending=False, kind="stable")
    offenders = tuple((row.key, _num(getattr(row, target.key)))
                      for row in broken[["key", target.key]].itertuples(index=False))
    measured = target.measure(values, len(broken)) if len(values) else "no value"
    met = False if offenders else None if len(missing) or present.empty else True
    return TargetCheck(target.label, measured, met, offenders, tuple(missing["key"]))


def _lacks(runs: pd.DataFrame, key: str) -> pd.Series:
    """Per run: whether its summary lacks ``key``."""
    return runs[MISSING].map(lambda keys: key in keys.split()).astype(bool)


# -- tables ----------------------------------------------------------------------------------

# Column of the per-scenario table -> (summary key, how runs combine).
FIGURE_COLUMNS: dict[str, tuple[str, str]] = {
    "collisions": (COLLISIONS, "sum"),
    "containment violations": (VIOLATIONS, "sum"),
    "route not finished": (ROUTE_COMPLETED, "not"),
    "longest needless hold, max (s)": (STANDSTILL, "max"),
    "min distance, min (m)": (MIN_DISTANCE, "min"),
    "min distance to the campaign's pedestrian, min (m)": (OWN_DISTANCE, "min"),
    "average speed, mean (m/s)": (SPEED, "mean"),
    "average speed, min (m/s)": (SPEED, "min"),
    "average speed, max (m/s)": (SPEED, "max"),
    "time stopped, mean (s)": (STOPPED, "mean"),
    "time stopped, max (s)": (STOPPED, "max"),
}


def scenario_rows(table: pd.DataFrame) -> list[dict[str, str]]:
    """Per scenario, then overall: runs, how many did not finish, and every figure (a figure
    that some runs lack says in how many)."""
    planned = table[table["status"] != NOT_FEASIBLE]
    groups = [*planned.groupby("scenario", sort=False), ("all", planned)]
    rows = []
    for scenario, runs in groups:
        done = runs[runs["status"] == OK]
        row = {"scenario": str(scenario), "runs": str(len(runs)),
               "failed or unfinished": str(len(runs) - len(done))}
        for column, (key, how) in FIGURE_COLUMNS.items():
            row[column] = _figure(done, key, how)
        rows.append(row)
    return rows


def _figure(done: pd.DataFrame, key: str, how: str) -> str:
    values = done[key].dropna()
    lacking = int(_lacks(done, key).sum())
    if values.empty:
        return f"missing ({lacking} runs)" if lacking else "—"
    if how == "not":
        text = str(int((~values.astype(bool)).sum()))
    elif how == "sum":
        text = str(int(values.sum()))
    else:
        text = _num(getattr(values.astype(float), how)())
    return f"{text} ({lacking} missing)" if lacking else text


WORST: dict[str, tuple[str, str]] = {  # figure -> (summary key, which run is worst)
    "collisions": (COLLISIONS, "count"),
    "containment violations": (VIOLATIONS, "count"),
    "route not finished": (ROUTE_COMPLETED, "false"),
    "longest needless hold (s)": (STANDSTILL, "max"),
    "min distance (m)": (MIN_DISTANCE, "min"),
    "min distance to the campaign's pedestrian (m)": (OWN_DISTANCE, "min"),
    "average speed (m/s)": (SPEED, "min"),
    "time stopped (s)": (STOPPED, "max"),
}


def worst_runs(table: pd.DataFrame) -> list[dict[str, str]]:
    """For each figure, the worst finished run (the first in plan order on ties); none for
    a count that no run has, or a route that every run finished."""
    done = table[table["status"] == OK]
    rows = []
    for figure, (key, which) in WORST.items():
        values = done[key].dropna()
        if which == "false":
            values = values[~values.astype(bool)]
        elif which == "count":
            values = values[values > 0]
        if values.empty:
            index = None
        elif which == "false":
            index = values.index[0]
        else:
            floats = values.astype(float)
            index = floats.idxmin() if which == "min" else floats.idxmax()
        if index is None:
            rows.append({"figure": figure, "worst": "—", "run": "—"})
        else:
            rows.append({"figure": figure, "worst": _num(done.at[index, key]),
                         "run": f"`{done.at[index, 'key']}`"})
    return rows


def violations_by_set(table: pd.DataFrame) -> dict[str, int]:
    """Containment violations summed per set over the finished runs, by set name."""
    totals: dict[str, int] = {}
    for text in table.loc[table["status"] == OK, VIOLATIONS_BY_SET].dropna():
        for name, count in json.loads(text).items():
            totals[name] = totals.get(name, 0) + int(count)
    return dict(sorted(totals.items()))


def not_feasible_rows(table: pd.DataFrame, columns: Sequence[str]) -> list[dict[str, str]]:
    """Combinations not run, one row per reason (plan order): the axis values they share,
    the reason, how many runs and which scenarios."""
    left_out = table[table["status"] == NOT_FEASIBLE]
    rows = []
    for reason, runs in left_out.groupby("error", sort=False):
        shared = [f"{c}={_value_text(runs[c].iloc[0])}" for c in columns
                  if runs[c].notna().all() and runs[c].nunique() == 1]
        rows.append({"values": ", ".join(shared), "reason": str(reason),
                     "runs": str(len(runs)),
                     "scenarios": ", ".join(dict.fromkeys(runs["scenario"]))})
    return rows


# -- heat maps -------------------------------------------------------------------------------

def heat_map(runs: pd.DataFrame, plan: Mapping[str, Any], key: str, scenario: str) -> Figure:
    """``key`` over step-out time (x) x walking speed (y) for one scenario's finished runs,
    combined over every other parameter; cells without a value are grey."""
    spec = HEAT_MAPS[key]
    x, y = plan["heat_map"]["x"], plan["heat_map"]["y"]
    axes = {a["column"]: a["values"] for a in plan["axes"]}
    grid = (runs.dropna(subset=[key]).astype({key: float}).groupby([y, x])[key].agg(spec.how)
            .unstack().reindex(index=axes[y], columns=axes[x]))
    values = np.ma.masked_invalid(grid.to_numpy(dtype=float))
    cmap = plt.get_cmap("viridis").with_extremes(bad="0.85")
    fig, ax = plt.subplots(figsize=(1.0 * len(axes[x]) + 2.5, 0.6 * len(axes[y]) + 2.0))
    image = ax.imshow(values, origin="lower", aspect="auto", cmap=cmap)
    for (row, col), value in np.ndenumerate(grid.to_numpy(dtype=float)):
        text = "—" if np.isnan(value) else f"{value:.2f}"
        light = not np.isnan(value) and image.norm(value) > 0.6
        ax.text(col, row, text, ha="center", va="center", fontsize=8,
                color="black" if light or np.isnan(value) else "white")
    ax.set_xticks(range(len(axes[x])), [f"{v:g}" for v in axes[x]], fontsize=8)
    ax.set_yticks(range(len(axes[y])), [f"{v:g}" for v in axes[y]], fontsize=8)
    ax.set_xlabel(f"{x} (step-out time)", fontsize=9)
    ax.set_ylabel(f"{y} (walking speed)", fontsize=9)
    ax.set_title(f"{scenario}: {spec.label}, {spec.how} over the other parameters", fontsize=9)
    fig.colorbar(image, ax=ax, label=spec.label)
    fig.tight_layout()
    return fig


def heat_map_name(scenario: str, key: str) -> str:
    """``safety_<scenario>_<figure>.png``."""
    return f"safety_{scenario}_{HEAT_MAPS[key].name}.png"


# -- the report ------------------------------------------------------------------------------

@dataclass(frozen=True)
class SafetyReport:
    """What the report found: the targets, and the runs that failed or did not finish."""

    markdown: Path
    written: tuple[Path, ...]
    targets: tuple[TargetCheck, ...]
    failed: tuple[tuple[str, str], ...]  # (key, error) of failed and unfinished runs
    runs: int
    not_feasible: int


def report_path(folder: Path) -> Path:
    """Where the report goes: beside the campaign folder, named after it."""
    folder = folder.resolve()
    return folder.parent / f"{folder.name}.md"


def write_safety_report(folder: Path) -> SafetyReport:
    """Rebuild ``safety.csv``, the heat maps and the report from ``folder``."""
    campaign = read_campaign(folder)
    table = campaign_table(campaign)
    with atomic_path(folder / SAFETY_TABLE) as tmp:
        table.to_csv(tmp, index=False)
    written = [folder / SAFETY_TABLE]
    done = table[table["status"] == OK]
    images: dict[str, list[str]] = {}
    for scenario in dict.fromkeys(table["scenario"]):
        for key in HEAT_MAPS:
            name = heat_map_name(scenario, key)
            fig = heat_map(done[done["scenario"] == scenario], campaign.plan, key, scenario)
            written.append(plots.save_figure(fig, folder / name))
            images.setdefault(scenario, []).append(name)
    targets = check_targets(table)
    unfinished = table[table["status"].isin([FAILED, UNFINISHED])]
    failed = tuple((row.key, row.error or "did not finish")
                   for row in unfinished.itertuples(index=False))
    markdown = report_path(folder)
    text = render(campaign, table, targets, failed, images, Path(folder).resolve().name)
    write_text_atomic(markdown, text)
    return SafetyReport(markdown, (*written, markdown), tuple(targets), failed,
                        int((table["status"] != NOT_FEASIBLE).sum()),
                        int((table["status"] == NOT_FEASIBLE).sum()))


def render(campaign: CampaignFolder, table: pd.DataFrame, targets: Sequence[TargetCheck],
           failed: Sequence[tuple[str, str]], images: Mapping[str, Sequence[str]],
           folder_name: str) -> str:
    """The report's Markdown (figures linked from ``folder_name/``)."""
    plan = campaign.plan
    status = table["status"].value_counts()
    count = {s: int(status.get(s, 0)) for s in (OK, FAILED, UNFINISHED, NOT_FEASIBLE)}
    lines = [
        "# Safety campaign",
        "",
        "The claim: under the model's assumptions the bus never hits a pedestrian who steps "
        "onto the zebra in front of it at any walking speed up to the estimator's bound, and "
        "always finishes its route. This campaign runs the hard cases.",
        "",
        f"Made by `{plan['command']}` from `{plan['campaign']}`"
        + (f" ({plan['description']})." if plan["description"] else "."),
        "Every figure is read from the runs' `summary.json`; a key a summary lacks is reported "
        "as missing, never filled in.",
        "",
        "## Grid",
        "",
        markdown_table([{"axis": "scenarios", "field": "",
                 "values": ", ".join(f"`{Path(s).stem}`" for s in plan["scenarios"])},
                *({"axis": a["column"], "field": f"`{a['path']}`",
                   "values": ", ".join(_value_text(v) for v in a["values"])}
                  for a in plan["axes"]),
                {"axis": "seeds", "field": "`simulation.seed`",
                 "values": ", ".join(map(str, plan["seeds"]))}]),
        "",
        *([f"Fixed for every run: {_fixed(plan['set'])}.", ""] if plan["set"] else []),
        "A parameter whose pattern selects nothing in a scenario is not varied there "
        "(S1 has no sensor off the bus).",
        "",
        f"Combinations: {len(table)}; not feasible, not run: {count[NOT_FEASIBLE]}; "
        f"runs: {len(table) - count[NOT_FEASIBLE]} ({count[OK]} finished, {count[FAILED]} "
        f"failed, {count[UNFINISHED]} unfinished).",
        "",
        "## Targets",
        "",
        markdown_table([{"target": t.label, "measured": t.measured, "verdict": t.verdict,
                 "runs that break it": _keys(k for k, _ in t.offenders),
                 "runs whose summary lacks the key": _keys(t.missing)} for t in targets]),
        "",
        "## Per scenario and overall",
        "",
        markdown_table(scenario_rows(table)),
        "",
        "Containment violations per set: " + (
            ", ".join(f"`{name}` {n}" for name, n in violations_by_set(table).items())
            or "none") + ".",
        "",
        "## Worst runs",
        "",
        markdown_table(worst_runs(table)),
        "",
        "## Heat maps",
        "",
        "Over step-out time x walking speed: the mean average speed and the least minimum "
        "distance over every other parameter; a grey cell has no finished run (not feasible).",
        "",
        *(f"![{name}]({folder_name}/{name})" for names in images.values() for name in names),
        "",
        "## Not feasible, not run",
        "",
        "The pedestrian cannot walk from its start to the zebra by the step-out time (the "
        "demand planner's verdict, `sse_cosim.world.demand.plan_actors`).",
        "",
        (markdown_table(not_feasible_rows(table, campaign.columns)) if count[NOT_FEASIBLE]
         else "None."),
        "",
        "## Failed and unfinished runs",
        "",
        "\n".join(f"- `{key}`: {error}" for key, error in failed) if failed else "None.",
        "",
    ]
    return "\n".join(lines)


def markdown_table(rows: Sequence[Mapping[str, str]]) -> str:
    """``rows`` (each header -> cell) as a Markdown table; "None." without rows."""
    if not rows:
        return "None."
    header = list(rows[0])
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(r[h]).replace("|", "\\|") for h in header) + " |"
              for r in rows]
    return "\n".join(lines)


def _keys(keys: Iterable[str]) -> str:
    keys = list(keys)
    if not keys:
        return "—"
    return ", ".join(f"`{k}`" for k in keys[:LISTED_MAX]) + _more(len(keys))


def _more(count: int) -> str:
    return f" and {count - LISTED_MAX} more" if count > LISTED_MAX else ""


def _num(value: Any) -> str:
    if isinstance(value, bool | np.bool_):
        return str(bool(value)).lower()
    if isinstance(value, int | np.integer):
        return str(int(value))
    return f"{float(value):.2f}"


def _value_text(value: Any) -> str:
    if isinstance(value, int | float) and not isinstance(value, bool):
        return f"{value:g}"
    return json.dumps(value)


def _fixed(overrides: Mapping[str, Any]) -> str:
    return ", ".join(f"`{path} = {json.dumps(value)}`" for path, value in overrides.items())

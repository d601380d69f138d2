"""The falsifier's outputs: every evaluation, the best margin against evaluations, the worst
cases as scenario files, and the report.

Written into the search folder (``results/falsify/<scenario>/``):

- ``falsify.json``: the plan (command, scenario and its digest as it resolves, objective,
  methods, budget, seed, the box);
- ``evaluations.csv.gz`` (after every generation; the ledger a resumed search reads): one row per
  evaluation, in method then evaluation order: its values,
  margin, whether it failed, what it broke, why it did not run;
- ``falsify_progress.png``: each method's least margin so far against evaluations;
- ``worst_<method>.toml``: the method's worst case, a scenario file that extends the searched
  one with the case's overrides (``sse-cosim run`` reproduces it), and ``worst_<method>/``, that
  run with its replay;
- ``report.md``.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import tomli_w
from matplotlib import pyplot as plt
from matplotlib.figure import Figure

from sse_cosim.files import write_json_atomic, write_text_atomic
from sse_cosim.reporting import plots
from sse_cosim.reporting.safety_report import markdown_table

FALSIFY_PLAN = "falsify.json"
EVALUATIONS = "evaluations.csv.gz"  # gzipped: a row per run (files.write_text_atomic)
PROGRESS_PLOT = "falsify_progress.png"
REPORT = "report.md"
UNFINISHED = "route_unfinished"
"""The column of ``evaluations.csv.gz`` that says whether a run left a route unfinished."""
CHECKPOINTS = (10, 20, 50, 100, 200, 500, 1000, 2000)
"""Evaluation counts at which the report gives each method's least margin so far."""


@dataclass(frozen=True)
class WorstCase:
    """A method's worst evaluation, its scenario file and what rerunning that file gave."""

    method: str
    evaluation: int
    margin: float
    file: Path
    run_folder: Path
    reproduced_margin: float | None
    error: str | None = None

    @property
    def reproduced(self) -> bool:
        return self.reproduced_margin is not None and np.isclose(
            self.reproduced_margin, self.margin, rtol=0.0, atol=1e-9)


def evaluations_table(rows: Sequence[Mapping[str, Any]]) -> pd.DataFrame:
    """One row per evaluation (method, evaluation, generation, key, the values, margin,
    failed, broken, not_feasible, error), in the order given."""
    return pd.DataFrame(list(rows))


def least_so_far(table: pd.DataFrame, method: str) -> np.ndarray:
    """The method's least margin after each evaluation, shape (evaluations,); NaN until a
    run has a margin."""
    margins = table.loc[table["method"] == method, "margin"].to_numpy(dtype=float)
    filled = np.where(np.isnan(margins), np.inf, margins)
    least = np.minimum.accumulate(filled)
    return np.where(np.isinf(least), np.nan, least)


def first_failure(table: pd.DataFrame, method: str) -> int | None:
    """How many evaluations the method needed to find its first failure (None: none)."""
    failed = table.loc[table["method"] == method, "failed"].to_numpy(dtype=bool)
    hits = np.flatnonzero(failed)
    return int(hits[0]) + 1 if hits.size else None


def progress_figure(table: pd.DataFrame, methods: Sequence[str], objective: str,
                    unit: str, scenario: str) -> Figure:
    """Each method's least margin so far against the number of evaluations."""
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    for method in methods:
        least = least_so_far(table, method)
        ax.step(np.arange(1, least.size + 1), least, where="post", label=method)
    ax.axhline(0.0, color="0.3", lw=0.8, ls=":")
    ax.set_xlabel("evaluations")
    ax.set_ylabel(f"least {objective} margin ({unit})")
    ax.set_title(f"{scenario}: least margin found")
    ax.legend()
    fig.tight_layout()
    return fig


def worst_case_document(scenario_file: Path, target: Path, overrides: Mapping[str, Any],
                        description: str, margins: Sequence[str] = ()) -> str:
    """A scenario file (TOML) at ``target`` that extends ``scenario_file`` with
    ``overrides`` (dotted path -> value); its first line says how to reproduce it (with the
    ``margins`` the objective reads)."""
    nested: dict[str, Any] = {}
    for dotted, value in overrides.items():
        node = nested
        *tables, last = dotted.split(".")
        for part in tables:
            node = node.setdefault(part, {})
        node[last] = value
    extends = Path(os.path.relpath(scenario_file.resolve(), target.parent.resolve())).as_posix()
    body = tomli_w.dumps({"extends": extends, "description": description, **nested})
    how = f"`{run_command(target.name, margins)}`" if margins else "`sse-cosim run` on this file"
    return f"# Written by `sse-cosim falsify`: reproduce it with {how}.\n" + body


def run_command(scenario_file: str, margins: Sequence[str] = ()) -> str:
    """The command that runs ``scenario_file`` with the ``margins`` an objective reads."""
    return f"sse-cosim run {scenario_file}" + "".join(f" --margin {name}" for name in margins)


def write_outputs(folder: Path, plan: Mapping[str, Any], table: pd.DataFrame) -> None:
    """``falsify.json``, ``evaluations.csv.gz`` and the progress plot, written atomically."""
    write_json_atomic(folder / FALSIFY_PLAN, plan)
    write_text_atomic(folder / EVALUATIONS, table.to_csv(index=False))
    fig = progress_figure(table, plan["methods"], plan["objective"], plan["unit"],
                          plan["scenario"])
    plots.save_figure(fig, folder / PROGRESS_PLOT)


def write_report(folder: Path, plan: Mapping[str, Any], table: pd.DataFrame,
                 worst: Sequence[WorstCase]) -> Path:
    """``report.md`` from the plan, the evaluations and the worst cases."""
    return write_text_atomic(folder / REPORT, render(plan, table, worst, folder))


def render(plan: Mapping[str, Any], table: pd.DataFrame, worst: Sequence[WorstCase],
           folder: Path) -> str:
    methods = plan["methods"]
    return "\n".join([
        f"# Falsification of {plan['scenario']}: {plan['objective']}",
        "",
        f"Command: `{plan['command']}`",
        "",
        f"Objective: {plan['objective_help']} (margin in {plan['unit']}; the search drives it "
        "down). "
        f"Budget: {plan['budget']} evaluations per method, in generations of "
        f"{plan['generation']}; seed {plan['seed']}.",
        "",
        "## The search box",
        "",
        markdown_table([{"value": d["name"], "low": f"{d['low']:g}", "high": f"{d['high']:g}"}
                        for d in plan["dims"]]),
        "",
        "## Results",
        "",
        markdown_table([_method_row(table, m) for m in methods]),
        "",
        "Routes unfinished: runs that ended (at the scenario's duration) with an automated "
        f"vehicle short of its route's end, whatever the objective (`{UNFINISHED}` in "
        f"`{EVALUATIONS}`), a liveness finding to look into: the bus stood or crept for "
        "good, or the duration was too short for the way it went (a late step-out).",
        "",
        "Least margin so far, by evaluations:",
        "",
        markdown_table(_checkpoint_rows(table, methods)),
        "",
        f"![least margin against evaluations]({PROGRESS_PLOT})",
        "",
        "## Worst cases",
        "",
        markdown_table([_worst_row(w, table, folder) for w in worst]),
        "",
        "## Broken promises, and walk-ins",
        "",
        "Runs with a collision (contact with a moving vehicle) or a containment violation "
        "before any break of the assumptions, whatever the objective; and runs in which a "
        "pedestrian walked into the standing bus (a walk-in: the claim is that the bus stands "
        "before any contact, docs/controller.md), whenever it came:",
        "",
        markdown_table(_broken_rows(table)),
        "",
        "## The world's breaks of the assumptions",
        "",
        "Runs in which SUMO moved a walker off the estimator's model or off the walkable "
        "ground (counted, not fatal: every search run lists them in `breaks_assumptions`). "
        "A failure counts only if it began before the first break; what came after is listed "
        "here, not above.",
        "",
        markdown_table([{"method": r.method, "evaluation": str(int(r.evaluation) + 1),
                         "first break (s)": f"{r.first_break_t:g}",
                         "objective failed after it": str(bool(r.failed_outside)).lower(),
                         "run": f"runs/{r.key}"}
                        for r in table[table["first_break_t"].notna()].itertuples()]),
        "",
        "## Failed runs",
        "",
        markdown_table([{"method": r.method, "evaluation": int(r.evaluation) + 1,
                         "error": r.error} for r in table[table["error"].notna()].itertuples()]),
        "",
    ])


def _method_row(table: pd.DataFrame, method: str) -> dict[str, str]:
    rows = table[table["method"] == method]
    least = least_so_far(table, method)
    found = first_failure(table, method)
    return {"method": method, "evaluations": str(len(rows)),
            "not feasible": str(int(rows["not_feasible"].notna().sum())),
            "failed runs": str(int(rows["error"].notna().sum())),
            "failures found": str(int(rows["failed"].sum())),
            "after a break": str(int(rows["failed_outside"].sum())),
            "runs with a break": str(int(rows["first_break_t"].notna().sum())),
            "routes unfinished": _unfinished(rows),
            "first failure at": "—" if found is None else f"evaluation {found}",
            "least margin": _num(least[-1] if least.size else np.nan)}


def _unfinished(rows: pd.DataFrame) -> str:
    """How many runs left a route unfinished ("—" where the ledger does not say)."""
    if UNFINISHED not in rows or rows[UNFINISHED].isna().all():
        return "—"
    return str(int((rows[UNFINISHED] == True).sum()))  # noqa: E712 (True, False or missing)


def _checkpoint_rows(table: pd.DataFrame, methods: Sequence[str]) -> list[dict[str, str]]:
    counts = sorted({c for c in CHECKPOINTS if c < len(table) // len(methods)}
                    | {len(table) // len(methods)})
    rows = []
    for method in methods:
        least = least_so_far(table, method)
        rows.append({"method": method,
                     **{str(c): _num(least[c - 1]) for c in counts if c <= least.size}})
    return rows


def _worst_row(case: WorstCase, table: pd.DataFrame, folder: Path) -> dict[str, str]:
    row = table[(table["method"] == case.method)
                & (table["evaluation"] == case.evaluation)].iloc[0]
    values = ", ".join(f"{name} {row[name]:g}" for name in _value_columns(table))
    if case.error is not None:
        rerun = f"failed: {case.error}"
    else:
        rerun = (f"{_num(case.reproduced_margin)}"
                 + ("" if case.reproduced else " (NOT the search's margin)"))
    return {"method": case.method, "evaluation": str(case.evaluation + 1),
            "margin": _num(case.margin), "rerun's margin": rerun,
            "scenario file": f"[{case.file.name}]({case.file.relative_to(folder).as_posix()})",
            "values": values}


def _broken_rows(table: pd.DataFrame) -> list[dict[str, str]]:
    broken = table[table["broken"].fillna("") != ""]
    return [{"method": r.method, "evaluation": str(int(r.evaluation) + 1), "broke": r.broken,
             "run": f"runs/{r.key}"} for r in broken.itertuples()]


def _value_columns(table: pd.DataFrame) -> list[str]:
    fixed = {"method", "evaluation", "generation", "key", "margin", "failed", "failed_outside",
             "first_break_t", "broken", "not_feasible", "error", UNFINISHED}
    return [c for c in table.columns if c not in fixed]


def _num(value: Any) -> str:
    if value is None or (isinstance(value, float) and np.isnan(value)):
        return "—"
    return f"{float(value):.3f}"

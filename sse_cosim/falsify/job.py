"""``sse-cosim falsify`` as one job: plan the search, run it, write what it found.

The search (:func:`~sse_cosim.falsify.search.run_search`) gives every evaluation; this module
writes them (:mod:`sse_cosim.reporting.falsify_report`), then turns each method's worst case
into a scenario file and runs that file again, in full with its replay, to show that it
reproduces the margin the search saw.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd

from sse_cosim.errors import UserError
from sse_cosim.falsify.objectives import OBJECTIVES
from sse_cosim.falsify.search import Evaluation, Progress, SearchSetup, run_search
from sse_cosim.falsify.searchers import SEARCHERS
from sse_cosim.falsify.space import build_space, load_falsify_file
from sse_cosim.files import portable_path, write_text_atomic
from sse_cosim.reporting import falsify_report as report
from sse_cosim.reporting.margins import check_margins
from sse_cosim.runner.executors import Execution, execute
from sse_cosim.runner.safety import ActorPlanner
from sse_cosim.runner.tasks import RunTask
from sse_cosim.scenario.loader import load_scenario_data, validate_scenario


@dataclass(frozen=True)
class FalsifyOutcome:
    """What a search found: its evaluations (as written), the worst cases, the report."""

    table: pd.DataFrame
    worst: tuple[report.WorstCase, ...]
    report: Path


def prepare(scenario: Path, spec_file: Path, objective: str, methods: Sequence[str],
            budget: int, seed: int) -> SearchSetup:
    """The search, checked before anything runs (:class:`UserError` for bad input)."""
    unknown = [m for m in methods if m not in SEARCHERS]
    if unknown:
        raise UserError("command line", "--method", f"unknown method {unknown[0]!r}",
                        f"use {', '.join(SEARCHERS)}")
    if len(set(methods)) < len(methods):
        raise UserError("command line", "--method", "a method is given twice",
                        "give each method once")
    data = load_scenario_data(scenario)
    space = build_space(load_falsify_file(spec_file), data, str(scenario), str(spec_file),
                        ActorPlanner().crossings)
    check_margins(OBJECTIVES[objective].margins, validate_scenario(data, str(scenario)),
                  str(scenario))
    return SearchSetup(scenario, data, space, OBJECTIVES[objective], tuple(methods), budget,
                       seed)


def falsify(setup: SearchSetup, out_dir: Path, execution: Execution, command: str,
            progress: Progress | None = None) -> FalsifyOutcome:
    """Run the search into ``out_dir``, write its outputs and reproduce its worst cases."""
    evaluations = run_search(setup, out_dir, execution, progress)
    table = report.evaluations_table([_row(e) for e in evaluations])
    plan = plan_document(setup, command)
    report.write_outputs(out_dir, plan, table)
    worst = tuple(_reproduce(setup, case, out_dir, execution)
                  for case in _worst(evaluations, setup.methods))
    return FalsifyOutcome(table, worst, report.write_report(out_dir, plan, table, worst))


def plan_document(setup: SearchSetup, command: str) -> dict[str, Any]:
    """``falsify.json``: what was searched, and how."""
    objective = setup.objective
    return {"command": command, "scenario": setup.data.get("name", setup.scenario.stem),
            "scenario_file": portable_path(setup.scenario), "objective": objective.name,
            "objective_help": objective.help, "unit": objective.unit,
            "methods": list(setup.methods), "budget": setup.budget, "seed": setup.seed,
            "generation": setup.generation, "generations": setup.generations,
            "dims": [{"name": d.name, "low": d.low, "high": d.high}
                     for d in setup.space.dims]}


def _row(e: Evaluation) -> dict[str, Any]:
    return {"method": e.method, "evaluation": e.index, "generation": e.generation,
            "key": e.key, **e.values, "margin": e.margin, "failed": e.failed,
            "failed_outside": e.failed_outside, "first_break_t": e.first_break_t,
            "broken": "; ".join(e.broken), "not_feasible": e.not_feasible, "error": e.error}


def _worst(evaluations: Sequence[Evaluation], methods: Sequence[str]) -> list[Evaluation]:
    """Each method's evaluation with the least margin (the first of equals); none for a
    method none of whose points ran."""
    out = []
    for method in methods:
        ran = [e for e in evaluations if e.method == method and e.margin is not None]
        if ran:
            out.append(min(ran, key=lambda e: e.margin))
    return out


def _reproduce(setup: SearchSetup, case: Evaluation, out_dir: Path,
               execution: Execution) -> report.WorstCase:
    """A method's worst case as a scenario file, run again in full (plots, replay)."""
    method = case.method
    target = out_dir / f"worst_{method}.toml"
    description = (f"{setup.data.get('name', setup.scenario.stem)}: the worst case "
                   f"({setup.objective.name} margin {case.margin:.3f} {setup.objective.unit})"
                   f" that {method} found at evaluation {case.index + 1}")
    write_text_atomic(target, report.worst_case_document(setup.scenario, target,
                                                         case.overrides, description,
                                                         setup.objective.margins))
    folder = out_dir / f"worst_{method}"
    task = RunTask(key=f"worst_{method}", scenario=str(target.resolve()), out_dir=str(folder),
                   margins=setup.objective.margins)
    (outcome,) = execute([task], Execution(1, execution.executor, execution.scheduler,
                                           progress=False))
    if not outcome.ok:
        return report.WorstCase(method, case.index, case.margin, target, folder, None,
                                outcome.error)
    return report.WorstCase(method, case.index, case.margin, target, folder,
                            setup.objective.margin(outcome.summary))

"""``sse-cosim falsify`` as one job: plan the search, run it, write what it found.

The search (:func:`~sse_cosim.falsify.search.run_search`) gives every evaluation; this module
writes them (:mod:`sse_cosim.reporting.falsify_report`) after every round, then turns each
method's worst case into a scenario file and runs that file again, in full with its replay, to
show that it reproduces the margin the search saw.

``evaluations.csv.gz`` is the search's ledger: with ``resume``, an evaluation it records as run
(with a margin) is taken from it, not run again, provided ``falsify.json`` names the same
search (:data:`SAME_SEARCH`; the scenario compared as it resolves). So a search can be
committed part-way and go on in a fresh checkout, where the runs' folders are gone. Made by
other code (``code_sha256``: :func:`code_digest`), neither the ledger nor the runs' folders
are taken: the resume is refused, since one search's figures must come from one code.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd
from tqdm import tqdm

from sse_cosim.errors import UserError
from sse_cosim.falsify.objectives import OBJECTIVES
from sse_cosim.falsify.search import (
    Evaluation,
    Progress,
    Recorded,
    SearchSetup,
    evaluation_key,
    run_search,
)
from sse_cosim.falsify.searchers import SEARCHERS
from sse_cosim.falsify.space import build_space, load_falsify_file, step_out_path
from sse_cosim.files import portable_path, refuse_plain, write_text_atomic
from sse_cosim.reporting import falsify_report as report
from sse_cosim.reporting.falsify_report import UNFINISHED
from sse_cosim.reporting.margins import check_margins
from sse_cosim.reporting.outputs import portable_scenario
from sse_cosim.runner.executors import Execution, execute
from sse_cosim.runner.safety import ActorPlanner
from sse_cosim.runner.tasks import RunTask
from sse_cosim.scenario.loader import apply_overrides, load_scenario_data, validate_scenario

SAME_SEARCH = ("scenario_file", "scenario_sha256", "objective", "seed", "dims")
"""The fields of ``falsify.json`` that must agree for a resumed search to take an earlier
one's evaluations from its ledger (the run keys name the method, evaluation, seed, margins
asked and overrides, not these)."""


CODE_FIELD = "code_sha256"
"""The field of ``falsify.json`` naming the code that made the search's runs."""


def code_digest() -> str:
    """SHA-256 of this package's Python sources (paths and contents, in path order): the
    same on every checkout of one commit, different once any of them changes."""
    package = Path(__file__).resolve().parents[1]
    digest = hashlib.sha256()
    for source in sorted(package.rglob("*.py")):
        digest.update(source.relative_to(package).as_posix().encode() + b"\0")
        digest.update(source.read_bytes() + b"\0")
    return digest.hexdigest()


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
    check_margins(OBJECTIVES[objective].margins,  # as every run has it: with the box's [set]
                  validate_scenario(apply_overrides(data, space.fixed, str(scenario)),
                                    str(scenario)), str(scenario))
    return SearchSetup(scenario, data, space, OBJECTIVES[objective], tuple(methods), budget,
                       seed)


def falsify(setup: SearchSetup, out_dir: Path, execution: Execution, command: str,
            progress: Progress | None = None) -> FalsifyOutcome:
    """Run the search into ``out_dir``, write its outputs after every round and reproduce
    its worst cases."""
    plan = plan_document(setup, command, out_dir)
    if execution.resume:
        check_same_code(out_dir, plan)
    recorded = recorded_outcomes(out_dir, plan) if execution.resume else {}

    def checkpoint(evaluations: list[Evaluation]) -> None:
        report.write_outputs(out_dir, plan, _table(evaluations))

    evaluations = run_search(setup, out_dir, execution, progress, checkpoint, recorded)
    table = _table(evaluations)
    worst = tuple(_reproduce(setup, case, out_dir, execution)
                  for case in _worst(evaluations, setup.methods))
    return FalsifyOutcome(table, worst, report.write_report(out_dir, plan, table, worst))


def plan_document(setup: SearchSetup, command: str, out_dir: Path) -> dict[str, Any]:
    """``falsify.json``: what was searched, and how (the scenario's digest as it resolves,
    its network's paths relative to ``out_dir``)."""
    objective = setup.objective
    resolved = portable_scenario(validate_scenario(setup.data, str(setup.scenario)), out_dir)
    digest = hashlib.sha256(json.dumps(resolved, sort_keys=True).encode()).hexdigest()
    return {"command": command, "scenario": setup.data.get("name", setup.scenario.stem),
            "scenario_file": portable_path(setup.scenario), "scenario_sha256": digest,
            CODE_FIELD: code_digest(),
            "objective": objective.name,
            "objective_help": objective.help, "unit": objective.unit,
            "methods": list(setup.methods), "budget": setup.budget, "seed": setup.seed,
            "generation": setup.generation, "generations": setup.generations,
            "dims": [{"name": d.name, "low": d.low, "high": d.high}
                     for d in setup.space.dims]}


def check_same_code(out_dir: Path, plan: dict[str, Any]) -> None:
    """Refuse (:class:`UserError`) to resume a search in ``out_dir`` whose ``falsify.json``
    says other code made its runs, or does not say which: its ledger and its runs' folders
    would mix two codes' figures in one search."""
    plan_file = out_dir / report.FALSIFY_PLAN
    if not plan_file.is_file():
        return
    earlier = json.loads(plan_file.read_text()).get(CODE_FIELD)
    if earlier != plan[CODE_FIELD]:
        made = "other code than this checkout's" if earlier else "code it does not name"
        raise UserError(str(plan_file), CODE_FIELD, f"its runs were made by {made}",
                        "run without --resume to make them again, or give --out another "
                        "folder")


def recorded_outcomes(out_dir: Path, plan: dict[str, Any]) -> dict[str, Recorded]:
    """The outcomes ``out_dir``'s ledger records, by run key: the rows with a margin (a run
    that failed, or a point not feasible, is planned again). None if the folder holds no
    ledger, and none, with one line saying why, if it holds another search's."""
    plan_file, ledger = out_dir / report.FALSIFY_PLAN, out_dir / report.EVALUATIONS
    refuse_plain(ledger)
    if not (plan_file.is_file() and ledger.is_file()):
        return {}
    differs = _differs(json.loads(plan_file.read_text()), plan)
    if differs is not None:
        tqdm.write(f"{ledger}: recorded by another search (its {differs} differs): its "
                   "evaluations are not taken; finished runs are read back from runs/")
        return {}
    table = pd.read_csv(ledger, keep_default_na=False, na_values={"margin": [""],
                                                                  "first_break_t": [""]})
    if len(table) and table["generation"].max() >= plan["generations"]:
        raise UserError(str(ledger), "generation",
                        f"records {table['generation'].max() + 1} generations, more than "
                        f"--budget {plan['budget']} makes ({plan['generations']}): resuming "
                        "would drop them", "give a budget at least as large, or another --out")
    ran = table[table["margin"].notna() & (table["error"] == "")]
    return {row.key: Recorded(float(row.margin), _flag(row.failed), _flag(row.failed_outside),
                              None if pd.isna(row.first_break_t) else float(row.first_break_t),
                              tuple(part for part in str(row.broken).split("; ") if part),
                              _known_flag(getattr(row, UNFINISHED, "")))
            for row in ran.itertuples()}


def _differs(earlier: dict[str, Any], plan: dict[str, Any]) -> str | None:
    """The first field of :data:`SAME_SEARCH` in which an earlier search's ``falsify.json``
    differs from ``plan``; None if it is the same search."""
    return next((field for field in SAME_SEARCH if earlier.get(field) != plan[field]), None)


def write_case(setup: SearchSetup, out_dir: Path, method: str, number: int) -> Path:
    """``method``'s evaluation ``number`` (from 1, as the report counts) of the search in
    ``out_dir`` as a scenario file, ``case_<method>_<number>.toml`` in ``out_dir``.

    Its overrides are those the search's values recorded in ``evaluations.csv.gz`` make (its
    step-out times as recorded: the planner timed them), checked against the run's key, so
    that the file is the run the search made; :class:`UserError` if the folder holds no such
    search or evaluation, or if the falsify file or scenario now make other overrides."""
    plan_file, ledger = out_dir / report.FALSIFY_PLAN, out_dir / report.EVALUATIONS
    refuse_plain(ledger)
    for needed in (plan_file, ledger):
        if not needed.is_file():
            raise UserError(str(needed), "--case", "no search's ledger is here",
                            "give --out the folder of the search the case is from")
    differs = _differs(json.loads(plan_file.read_text()), plan_document(setup, "", out_dir))
    if differs is not None:
        raise UserError(str(plan_file), differs, "is another search's than the command's",
                        "give the search's scenario, --file, --objective and --seed")
    table = pd.read_csv(ledger)
    rows = table[(table["method"] == method) & (table["evaluation"] == number - 1)]
    if rows.empty:
        counted = int((table["method"] == method).sum())
        raise UserError(str(ledger), "--case", f"has no evaluation {number} of {method}",
                        f"give one from 1 to {counted}" if counted else
                        f"give a method of the search ({', '.join(sorted(set(table['method'])))})")
    row = rows.iloc[0]
    space = setup.space
    overrides = space.overrides({d.name: float(row[d.name]) for d in space.dims})
    overrides.update({step_out_path(w.pedestrian): float(row[w.derived])
                      for w in space.step_outs if pd.notna(row.get(w.derived))})
    if evaluation_key(setup, method, number - 1, overrides) != row["key"]:
        raise UserError(str(ledger), "key", f"{method}'s evaluation {number} ran with other "
                        "overrides than the falsify file and scenario make of its values now",
                        "use the falsify file and scenario the search used")
    target = out_dir / f"case_{method}_{number}.toml"
    outcome = (f"{setup.objective.name} margin {row['margin']:.3f} {setup.objective.unit}"
               if pd.notna(row["margin"]) else
               f"not feasible: {row['not_feasible']}" if pd.notna(row["not_feasible"]) else
               "its run failed")
    description = (f"{setup.data.get('name', setup.scenario.stem)}: {method}'s evaluation "
                   f"{number} ({outcome})")
    write_text_atomic(target, report.worst_case_document(setup.scenario, target, overrides,
                                                         description, setup.objective.margins))
    return target


def _flag(value: Any) -> bool:
    """A ledger's True/False (read as a bool or as its text)."""
    return value is True or str(value) == "True"


def _known_flag(value: Any) -> bool | None:
    """A ledger's True/False, None where it is empty or missing."""
    return None if str(value) == "" else _flag(value)


def _table(evaluations: Sequence[Evaluation]) -> pd.DataFrame:
    return report.evaluations_table([_row(e) for e in evaluations])


def _row(e: Evaluation) -> dict[str, Any]:
    return {"method": e.method, "evaluation": e.index, "generation": e.generation,
            "key": e.key, **e.values, "margin": e.margin, "failed": e.failed,
            "failed_outside": e.failed_outside, "first_break_t": e.first_break_t,
            "broken": "; ".join(e.broken), "not_feasible": e.not_feasible, "error": e.error,
            UNFINISHED: e.unfinished}


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

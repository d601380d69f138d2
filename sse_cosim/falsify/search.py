"""The falsifier's loop: a searcher proposes a generation, the runs execute, margins come back.

Each method (:mod:`sse_cosim.falsify.searchers`) spends the same budget, generation by
generation, from the same seed. A point becomes a scenario (:mod:`sse_cosim.falsify.space`);
the project's demand planner times the walk before a ``[step_out]`` wait and rules out the
points that cannot happen (with a step-out time searched directly, the pedestrian may not
reach the zebra by then): they are not run and score :data:`NOT_RUN_MARGIN`, so the search
moves away from them. The others run through the sweeps' executors (local pool or
Dask), into ``runs/<key>`` under the search's folder, the key a hash of the method, the
evaluation and the overrides.

A killed search resumes: with ``resume`` the finished runs are read back, every searcher is
rebuilt from its seed and told the same margins again, so it proposes the same points and the
search goes on where it stopped, with the results an uninterrupted search gives. What a search
has found is also handed to ``checkpoint`` after every round (the job writes it to
``evaluations.csv.gz``), and a resumed search takes an evaluation from ``recorded`` (those rows,
by key) without its run: a search can go on in another checkout, where ``runs/`` is gone.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from sse_cosim.falsify.objectives import Objective, broken, first_break_t
from sse_cosim.falsify.searchers import SEARCHERS, generation_size
from sse_cosim.falsify.space import SearchSpace, scenario_of
from sse_cosim.reporting.outputs import RUNS_FOLDER, TaskOutcome
from sse_cosim.runner.executors import Execution, execute
from sse_cosim.runner.safety import ActorPlanner
from sse_cosim.runner.sweep import run_key
from sse_cosim.runner.tasks import RunTask

Progress = Callable[[int, int, dict[str, float | None], int], None]
"""Told after each round: the round, the rounds, each method's least margin so far, and how
many runs the round made (0: every evaluation was recorded, or not feasible)."""

Checkpoint = Callable[[list["Evaluation"]], None]
"""Told after each round, before :data:`Progress`: every evaluation so far, in method then
evaluation order."""

NOT_RUN_MARGIN = 1e6
"""The margin given to a point that is not run (not feasible) or whose run failed: far above
any real margin, so every method turns away from it."""


@dataclass(frozen=True)
class Evaluation:
    """One point of one method's search: its values, its run and what the run showed.

    ``margin`` is None when the point did not run (``not_feasible``: the planner's reason) or
    its run failed (``error``). ``failed``: the objective's failure, within the assumptions
    (it began before ``first_break_t``, the first time the world broke one, or the world broke
    none); ``failed_outside``: a failure that came after such a break, or whose start the
    summary does not give in a run with a break. ``broken``: collisions and containment
    violations within the assumptions, and walk-ins, whatever the objective. ``unfinished``:
    whether the run ended with an automated vehicle's route unfinished (liveness, whatever the
    objective; None where not known).
    """

    method: str
    index: int
    generation: int
    values: dict[str, float]
    overrides: dict[str, Any]
    key: str
    margin: float | None
    failed: bool
    failed_outside: bool = False
    first_break_t: float | None = None
    broken: tuple[str, ...] = ()
    not_feasible: str | None = None
    error: str | None = None
    unfinished: bool | None = None

    @property
    def search_margin(self) -> float:
        """The margin the searcher is told."""
        return NOT_RUN_MARGIN if self.margin is None else self.margin


@dataclass(frozen=True)
class Recorded:
    """A run's outcome as a checkpoint recorded it (see :class:`Evaluation`): what a resumed
    search takes instead of making the run again."""

    margin: float
    failed: bool
    failed_outside: bool
    first_break_t: float | None
    broken: tuple[str, ...]
    unfinished: bool | None = None  # None: a ledger written before it was recorded


@dataclass(frozen=True)
class SearchSetup:
    """What one search runs: a scenario file (and its resolved data), its space, the
    objective, the methods, the budget per method and the seed."""

    scenario: Path
    data: Mapping[str, Any]
    space: SearchSpace
    objective: Objective
    methods: tuple[str, ...]
    budget: int
    seed: int

    @property
    def generation(self) -> int:
        return generation_size(self.space.size)

    @property
    def generations(self) -> int:
        """Generations per method: the budget rounded up to whole generations."""
        return -(-self.budget // self.generation)


def run_search(setup: SearchSetup, out_dir: Path, execution: Execution,
               progress: Progress | None = None, checkpoint: Checkpoint | None = None,
               recorded: Mapping[str, Recorded] | None = None) -> list[Evaluation]:
    """Every method's evaluations, in method then evaluation order.

    The methods advance together, one generation each per round, so that their runs share
    each round's workers. ``checkpoint(evaluations)`` and then ``progress(round, rounds,
    best, ran)`` are called after each round (``best``: method -> least margin so far;
    ``ran``: the runs made in it). A planned
    evaluation whose key is in ``recorded`` takes its outcome from there and is not run.
    """
    recorded = recorded or {}
    planner = ActorPlanner()
    searchers = {m: SEARCHERS[m](setup.space.size, setup.seed, setup.generation)
                 for m in setup.methods}
    done: dict[str, list[Evaluation]] = {m: [] for m in setup.methods}
    for round_ in range(setup.generations):
        proposed = {m: searchers[m].ask() for m in setup.methods}
        planned = {m: [_plan(setup, m, round_, i, p, planner, out_dir)
                       for i, p in enumerate(points)] for m, points in proposed.items()}
        tasks = [task for plans in planned.values() for _, task in plans
                 if task is not None and task.key not in recorded]
        outcomes = {o.key: o for o in execute(tasks, execution,
                                              description=f"falsify {round_ + 1}")}
        for method in setup.methods:
            evaluations = [_recalled(plan, recorded[plan.key]) if plan.key in recorded
                           else _scored(setup.objective, plan, outcomes)
                           for plan, _ in planned[method]]
            searchers[method].tell(proposed[method], [e.search_margin for e in evaluations])
            done[method] += evaluations
        if checkpoint is not None:
            checkpoint([e for m in setup.methods for e in done[m]])
        if progress is not None:
            progress(round_ + 1, setup.generations, {m: _least(done[m]) for m in done},
                     len(tasks))
    return [e for m in setup.methods for e in done[m]]


def _plan(setup: SearchSetup, method: str, generation: int, position: int, point: np.ndarray,
          planner: ActorPlanner, out_dir: Path) -> tuple[Evaluation, RunTask | None]:
    """The evaluation of ``point`` as planned (its margin still unknown) and its run (None if
    the point is not feasible)."""
    index = generation * setup.generation + position
    source = str(setup.scenario)
    values, overrides, scenario = scenario_of(setup.space, setup.data, point, source,
                                              planner.walk_times)
    key = evaluation_key(setup, method, index, overrides)
    planned = Evaluation(method, index, generation, values, overrides, key, None, False)
    reason = planner(scenario, source)
    if reason is not None:
        return replace(planned, not_feasible=reason), None
    task = RunTask(key=key, scenario=str(setup.scenario.resolve()),
                   out_dir=str(out_dir / RUNS_FOLDER / key), overrides=overrides,
                   plots=False, summary_only=True, margins=setup.objective.margins)
    return planned, task


def evaluation_key(setup: SearchSetup, method: str, index: int,
                   overrides: Mapping[str, Any]) -> str:
    """The run key of ``method``'s evaluation ``index`` (from 0) with ``overrides``: the
    method, the evaluation, the margins asked (part of the run's identity: its summary
    differs) and the seed, and a digest of the overrides."""
    asked = setup.objective.margins
    return run_key("-".join([f"{method}-{index:04d}", *asked]), [], setup.seed, overrides)


def _scored(objective: Objective, planned: Evaluation,
            outcomes: Mapping[str, TaskOutcome]) -> Evaluation:
    if planned.not_feasible is not None:
        return planned
    outcome = outcomes[planned.key]
    if not outcome.ok:
        return replace(planned, error=outcome.error)
    summary = outcome.summary
    failed, since = objective.failed(summary), first_break_t(summary)
    at = objective.failed_at(summary)
    within = since is None or (at is not None and at < since)
    return replace(planned, margin=objective.margin(summary), failed=failed and within,
                   failed_outside=failed and not within, first_break_t=since,
                   broken=tuple(broken(summary)),
                   unfinished=summary.get("route_completed") is False)


def _recalled(planned: Evaluation, recorded: Recorded) -> Evaluation:
    """``planned`` with the outcome ``recorded`` for its key (its run is not made again)."""
    return replace(planned, margin=recorded.margin, failed=recorded.failed,
                   failed_outside=recorded.failed_outside,
                   first_break_t=recorded.first_break_t, broken=recorded.broken,
                   unfinished=recorded.unfinished)


def _least(evaluations: Sequence[Evaluation]) -> float | None:
    margins = [e.margin for e in evaluations if e.margin is not None]
    return min(margins) if margins else None

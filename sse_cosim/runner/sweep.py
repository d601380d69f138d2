"""Parameter sweeps: scenarios x parameter values x seeds, one run per combination.

A parameter is a dotted path into the scenario (``v2x.latency_steps``) and the values it
takes; the path may be a pattern (:mod:`sse_cosim.scenario.paths`: globs over keys, filters
on a field). Patterns are expanded against each scenario's resolved fields; every field a
pattern selects takes the same value, and a pattern that selects nothing is an error.

Everything is checked before anything runs: a path that names no field, or a value whose
shape does not fit its field (a number for a list field), stops the sweep with a
:class:`UserError`. A combination whose *value* the schema rejects (a negative noise
bound) becomes a failed run with its error, and the other runs go on.

A run's key (its folder ``runs/<key>``) is derived from the scenario file's name, its
overrides and its seed only, so every sweep that makes the same run finds the same folder;
``--resume`` relies on that.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import re
from collections import Counter
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any

from pydantic import BaseModel, ConfigDict, Field, model_validator

from sse_cosim.errors import UserError
from sse_cosim.files import portable_path, read_toml_model, write_json_atomic
from sse_cosim.reporting.outputs import RUNS_FOLDER, TaskOutcome
from sse_cosim.reporting.sweep_report import SWEEP_PLAN
from sse_cosim.runner.batch import scenario_files
from sse_cosim.runner.executors import Execution, execute
from sse_cosim.runner.parameters import blame_assignments, parse_value, split_assignment
from sse_cosim.runner.tasks import RunTask, record_failure
from sse_cosim.scenario.loader import apply_overrides, load_scenario_data, validate_scenario
from sse_cosim.scenario.paths import PART_FILTER, expand_pattern, split_path

SEED_PATH = "simulation.seed"
CLI = "command line"
VALUES_FIX = "write [v1, v2, ...], range(start, stop[, step]) or linspace(start, stop, num)"
KEY_TEXT_MAX = 90  # characters of the readable part of a run key
_CALL = re.compile(r"^(range|linspace)\((.*)\)$")
_UNSAFE = re.compile(r"[^A-Za-z0-9._=+-]+")


# -- parameters and values -------------------------------------------------------------------

@dataclass(frozen=True)
class Parameter:
    """One swept parameter: a dotted path pattern and its values, in order."""

    pattern: str
    values: tuple[Any, ...]
    name: str = ""

    @property
    def column(self) -> str:
        """The parameter's column in ``sweep.csv``: its name, else its pattern."""
        return self.name or self.pattern


def parse_values(text: str, option: str, source: str = CLI) -> list[Any]:
    """The values of ``VALUES``: a TOML list, ``range(...)`` or ``linspace(...)``.

    ``range(start, stop[, step])`` is Python's (integers, ``stop`` excluded);
    ``linspace(start, stop, num)`` gives ``num`` evenly spaced values, both ends included.
    A list field's values are lists themselves: ``[[0.5, 0.5], [1.0, 1.0]]``.
    """
    text = text.strip()
    call = _CALL.match(text)
    if call:
        args = [parse_value(arg.strip()) for arg in call.group(2).split(",")]
        if not all(_is_number(a) for a in args):
            raise UserError(source, option, f"{text!r}: the arguments must be numbers", VALUES_FIX)
        return _range(call.group(1), args, text, option, source)
    values = parse_value(text)
    if not isinstance(values, list) or not values:
        raise UserError(source, option, f"{text!r} is not a list of values or a range",
                        VALUES_FIX)
    return values


def linspace_values(start: float, stop: float, num: int) -> list[int | float]:
    """``num`` evenly spaced values from ``start`` to ``stop`` (both included).

    Integers when both ends and every value are whole (``linspace(0, 4, 5)`` is 0..4, as a
    field like ``v2x.latency_steps`` needs); floats are rounded to 12 significant digits so
    that 0.2 + 0.4 reads as 0.6 in tables and keys.
    """
    if num == 1:
        return [start]
    values = [start + (stop - start) * i / (num - 1) for i in range(num)]
    if all(isinstance(v, int) for v in (start, stop)) and all(v.is_integer() for v in values):
        return [int(v) for v in values]
    return [float(f"{v:.12g}") for v in values]


def parse_parameter(text: str) -> Parameter:
    """``--param PATH=VALUES`` (the first ``=`` outside brackets separates them)."""
    parts = split_assignment(text)
    if parts is not None:
        return Parameter(parts[0], tuple(parse_values(parts[1], "--param")))
    raise UserError(CLI, "--param", f"{text!r} is not PATH=VALUES",
                    "write it like v2x.latency_steps=[0, 1, 2] or v2x.latency_steps=range(0,5)")


def parse_seeds(text: str, option: str = "--seeds", source: str = CLI) -> tuple[int, ...]:
    """Seeds given like any parameter's values; each a whole number >= 0."""
    seeds = parse_values(text, option, source)
    if not all(isinstance(s, int) and not isinstance(s, bool) and s >= 0 for s in seeds):
        raise UserError(source, option, f"{text!r}: seeds are whole numbers >= 0",
                        "write e.g. [1, 2, 3] or range(1, 4)")
    return tuple(seeds)


def _range(kind: str, args: list[Any], text: str, option: str, source: str) -> list[Any]:
    if kind == "range" and len(args) in (2, 3) and all(isinstance(a, int) for a in args):
        values: list[Any] = list(range(*args))
    elif kind == "linspace" and len(args) == 3 and isinstance(args[2], int) and args[2] >= 1:
        values = linspace_values(args[0], args[1], args[2])
    else:
        raise UserError(source, option, f"{text!r} is not a valid {kind}",
                        "range(start, stop[, step]) takes integers; "
                        "linspace(start, stop, num) takes a whole num >= 1")
    if not values:
        raise UserError(source, option, f"{text!r} is empty", "check start, stop and step")
    return values


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


# -- sweep files -----------------------------------------------------------------------------

class _FileModel(BaseModel):
    model_config = ConfigDict(extra="forbid", populate_by_name=True)


class ParameterEntry(_FileModel):
    """``[[params]]`` in a sweep file: a path and either ``values`` or ``start/stop/num``."""

    path: str = Field(min_length=1)
    name: str | None = None
    values: list[Any] | None = Field(None, min_length=1)
    start: int | float | None = None
    stop: int | float | None = None
    num: int | None = Field(None, ge=1)

    @model_validator(mode="after")
    def _values_or_range(self) -> ParameterEntry:
        ranged = [v is not None for v in (self.start, self.stop, self.num)]
        if self.values is None and not all(ranged):
            raise ValueError("give values = [...] or all of start, stop and num")
        if self.values is not None and any(ranged):
            raise ValueError("give either values or start/stop/num, not both")
        return self

    def parameter(self) -> Parameter:
        if self.values is not None:
            values = self.values
        else:
            values = linspace_values(self.start, self.stop, self.num)  # type: ignore[arg-type]
        return Parameter(self.path, tuple(values), self.name or "")


class SweepFile(_FileModel):
    """A sweep file: scenarios (relative to the file), seeds, fixed overrides, parameters."""

    description: str = ""
    scenarios: list[str] = Field(min_length=1)
    seeds: list[Annotated[int, Field(ge=0)]] | None = Field(None, min_length=1)
    overrides: dict[str, Any] = Field(default_factory=dict, alias="set")
    params: list[ParameterEntry] = Field(default_factory=list)


@dataclass(frozen=True)
class SweepSpec:
    """What to sweep: scenario files x parameter values x seeds, with fixed overrides.

    ``seeds=None`` keeps each scenario's own ``simulation.seed``. ``fixed_given``: for a fixed
    override from the command line, the option as given (``"--set PATH=VALUE"``), which its
    errors name; the others came from the sweep file (``source``).
    """

    scenarios: tuple[Path, ...]
    parameters: tuple[Parameter, ...] = ()
    seeds: tuple[int, ...] | None = None
    fixed: Mapping[str, Any] = field(default_factory=dict)
    source: str = CLI
    fixed_given: Mapping[str, str] = field(default_factory=dict)

    def blame(self, pattern: str) -> str:
        """Who set the fixed override ``pattern``: the option as given, or the sweep file."""
        return self.fixed_given.get(pattern, f"{self.source}: set")


def load_sweep_file(path: Path) -> SweepSpec:
    """Read and validate a sweep file; problems become one-line errors naming file and field."""
    model = read_toml_model(path, SweepFile, "sweep file", "check the path",
                            "see sweeps/noise.toml for a complete example")
    return SweepSpec(
        scenarios=tuple(scenario_files([path.parent / s for s in model.scenarios])),
        parameters=tuple(entry.parameter() for entry in model.params),
        seeds=tuple(model.seeds) if model.seeds else None,
        fixed=model.overrides,
        source=str(path),
    )


def combine(
    base: SweepSpec | None,
    scenarios: Sequence[Path] = (),
    parameters: Sequence[Parameter] = (),
    seeds: tuple[int, ...] | None = None,
    fixed: Mapping[str, Any] | None = None,
    fixed_given: Mapping[str, str] | None = None,
) -> SweepSpec:
    """``base`` (a sweep file) with command-line additions: scenarios and seeds replace the
    file's, parameters replace the file's parameter of the same path or are added, fixed
    overrides are merged over the file's (``fixed_given``: each one's option as given)."""
    if base is None and not scenarios:
        raise UserError(CLI, "SCENARIOS", "no scenario to sweep",
                        "name scenario files or folders, or a sweep file with --file")
    base = base or SweepSpec(scenarios=())
    given = {p.pattern for p in parameters}
    return SweepSpec(
        scenarios=tuple(scenario_files(scenarios)) if scenarios else base.scenarios,
        parameters=(*(p for p in base.parameters if p.pattern not in given), *parameters),
        seeds=seeds if seeds is not None else base.seeds,
        fixed={**base.fixed, **(fixed or {})},
        source=base.source,
        fixed_given=dict(fixed_given or {}),
    )


# -- expanding patterns and planning runs ----------------------------------------------------

@dataclass(frozen=True)
class PlannedRun:
    """One combination: its folder key, scenario file, seed, values and overrides.

    ``error`` is set when the combination's scenario does not validate: the run is then
    recorded as failed without running.
    """

    key: str
    scenario: str
    seed: int
    values: dict[str, Any]
    overrides: dict[str, Any]
    error: str | None = None

    def task(self, runs_dir: Path, summary_only: bool) -> RunTask:
        return RunTask(key=self.key, scenario=self.scenario, out_dir=str(runs_dir / self.key),
                       overrides=dict(self.overrides), plots=not summary_only,
                       summary_only=summary_only)


def plan_sweep(spec: SweepSpec) -> list[PlannedRun]:
    """Every run of ``spec`` in a fixed order (scenario, then values, then seed), checked.

    Raises :class:`UserError` for anything wrong with the sweep itself (paths, shapes,
    conflicts, two identical runs); combinations with invalid values carry their error.
    """
    if not spec.scenarios:
        raise UserError(spec.source, "scenarios", "no scenario to sweep", "name at least one")
    columns = [p.column for p in spec.parameters]
    if len(set(columns)) < len(columns):
        raise UserError(spec.source, "params", "a parameter is given twice",
                        "give each path (or name) once")
    runs = [run for scenario in spec.scenarios for run in _plan_scenario(spec, scenario)]
    twice = sorted(key for key, n in Counter(run.key for run in runs).items() if n > 1)
    if twice:
        raise UserError(spec.source, "", f"some runs would be identical ({twice[0]}, ...)",
                        "remove repeated values, seeds or scenario files of the same name")
    return runs


def run_key(stem: str, labelled: Sequence[tuple[str, Any]], seed: int,
            overrides: Mapping[str, Any]) -> str:
    """``<stem>__<label>=<value>__...__seed<n>__<hash>``: readable, safe in file names.

    The readable part may be cut short; the hash (of the stem, the overrides and the seed)
    keeps keys of different runs apart and equal keys for equal runs.
    """
    text = "__".join([stem, *(f"{label}={_key_text(v)}" for label, v in labelled), f"seed{seed}"])
    readable = _UNSAFE.sub("_", text)[:KEY_TEXT_MAX].lstrip(".")
    identity = json.dumps({"scenario": stem, "seed": seed, "overrides": overrides},
                          sort_keys=True)
    return f"{readable}__{hashlib.sha1(identity.encode()).hexdigest()[:8]}"


def _plan_scenario(spec: SweepSpec, scenario: Path) -> Iterator[PlannedRun]:
    source = str(scenario)
    data = load_scenario_data(scenario)
    base = validate_scenario(data, source)
    fields = base.model_dump(mode="json")
    fixed = _fixed_overrides(spec, data, fields, scenario)
    targets = [_targets(p.pattern, p.values, fields, source) for p in spec.parameters]
    _check_disjoint(spec, fixed, targets, source)
    labels = _labels([p.pattern for p in spec.parameters])
    for combination in itertools.product(*(p.values for p in spec.parameters)):
        for seed in spec.seeds or (None,):
            overrides = dict(fixed)
            for paths, value in zip(targets, combination, strict=True):
                overrides.update(dict.fromkeys(paths, value))
            if seed is not None:
                overrides[SEED_PATH] = seed
            effective = overrides.get(SEED_PATH, base.simulation.seed)
            yield PlannedRun(
                key=run_key(scenario.stem, list(zip(labels, combination, strict=True)),
                            effective, overrides),
                scenario=str(scenario.resolve()),
                seed=effective,
                values={p.column: v for p, v in zip(spec.parameters, combination, strict=True)},
                overrides=overrides,
                error=_validation_error(data, overrides, source),
            )


def _fixed_overrides(spec: SweepSpec, data: Mapping[str, Any], fields: Mapping[str, Any],
                     scenario: Path) -> dict[str, Any]:
    """Path -> value of every fixed override on ``scenario``, checked before any run: they
    hold for every run, so a pattern that selects nothing or a value the scenario refuses
    stops the sweep with a one-line error naming the option (or the sweep file's ``set``)."""
    fixed: dict[str, Any] = {}
    owners: dict[str, str] = {}
    for pattern, value in spec.fixed.items():
        blame = f"{spec.blame(pattern)} ({scenario.name})"
        for path in _targets(pattern, [value], fields, blame):
            fixed[path], owners[path] = value, blame
    try:
        validate_scenario(apply_overrides(data, fixed, str(scenario)), str(scenario))
    except UserError as exc:
        raise blame_assignments(exc, owners, always=True) from None
    return fixed


def _targets(pattern: str, values: Sequence[Any], fields: Mapping[str, Any],
             source: str) -> list[str]:
    """The paths ``pattern`` selects, after checking each value's shape against each field."""
    matches = expand_pattern(pattern, fields, source)
    for path, current in matches:
        if isinstance(current, Mapping):
            raise UserError(source, pattern, f"{path} is a table, not a field",
                            "name one of its fields (`sse-cosim fields` lists them)")
        for value in values:
            if current is not None and isinstance(current, list) != isinstance(value, list):
                kind = "a list" if isinstance(current, list) else "a single value"
                fix = ("each value of a list field is a list: write [[0.5, 0.5], [1.0, 1.0]]"
                       if isinstance(current, list) else "give one plain value per run")
                raise UserError(source, pattern, f"{path} holds {kind}, got {value!r}", fix)
    return [path for path, _ in matches]


def _check_disjoint(spec: SweepSpec, fixed: Mapping[str, Any], targets: list[list[str]],
                    source: str) -> None:
    """No field may be set by two parameters, a parameter and ``set``, or by seeds too."""
    owners: dict[str, str] = {}
    claims = [*((path, f"set {path}") for path in fixed),
              *((path, p.pattern) for p, paths in zip(spec.parameters, targets, strict=True)
                for path in paths)]
    if spec.seeds is not None:
        claims.append((SEED_PATH, "seeds"))
    for path, owner in claims:
        if path in owners and owners[path] != owner:
            raise UserError(source, owner, f"sets {path}, which {owners[path]} sets too",
                            "set each field from one place only")
        owners[path] = owner


def _validation_error(data: Mapping[str, Any], overrides: Mapping[str, Any],
                      source: str) -> str | None:
    try:
        validate_scenario(apply_overrides(data, overrides, source), source)
    except UserError as exc:
        return str(exc)
    return None


def _labels(patterns: Sequence[str]) -> list[str]:
    """Short labels for keys: the last part of each pattern, more parts if they collide."""
    parts = [[PART_FILTER.sub(r"\g<keys>", p) for p in split_path(pattern)] for pattern in patterns]
    for depth in range(1, max((len(p) for p in parts), default=1) + 1):
        labels = [".".join(p[-depth:]) for p in parts]
        if len(set(labels)) == len(labels):
            return labels
    return labels


def _key_text(value: Any) -> str:
    if isinstance(value, list):
        return "x".join(_key_text(v) for v in value)
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)


# -- running ---------------------------------------------------------------------------------

def plan_document(spec: SweepSpec, runs: Sequence[PlannedRun], command: str,
                  summary_only: bool) -> dict[str, Any]:
    """``sweep.json``: how the sweep was made and every planned run (what reports read)."""
    return {
        "command": command,
        "source": portable_path(spec.source) if spec.source != CLI else spec.source,
        "scenarios": [portable_path(s) for s in spec.scenarios],
        "seeds": list(spec.seeds) if spec.seeds is not None else None,
        "set": dict(spec.fixed),
        "parameters": [{"column": p.column, "path": p.pattern, "values": list(p.values)}
                       for p in spec.parameters],
        "summary_only": summary_only,
        "runs": [{"key": r.key, "scenario": Path(r.scenario).stem,
                  "source": portable_path(r.scenario),
                  "seed": r.seed, "values": r.values, "overrides": r.overrides}
                 for r in runs],
    }


def run_sweep(
    spec: SweepSpec,
    runs: Sequence[PlannedRun],
    out_dir: Path,
    command: str,
    summary_only: bool,
    execution: Execution,
) -> list[TaskOutcome]:
    """Write ``sweep.json``, then run the plan (:func:`run_planned`); outcomes in plan order."""
    write_json_atomic(out_dir / SWEEP_PLAN, plan_document(spec, runs, command, summary_only))
    return run_planned(runs, out_dir, summary_only, execution, "sweep")


def run_planned(
    runs: Sequence[PlannedRun],
    out_dir: Path,
    summary_only: bool,
    execution: Execution,
    description: str,
) -> list[TaskOutcome]:
    """Run planned runs into ``out_dir/runs/<key>``: invalid combinations are recorded as
    failed, the rest run as ``execution`` says; outcomes in plan order.

    The one execution path of every planned run, whether a Cartesian sweep planned it or
    another planner (the safety campaign's constrained grid) built the list.
    """
    tasks = {run.key: run.task(out_dir / RUNS_FOLDER, summary_only) for run in runs}
    outcomes = {run.key: record_failure(tasks[run.key], run.error) for run in runs if run.error}
    valid = [tasks[run.key] for run in runs if not run.error]
    for outcome in execute(valid, execution, description):
        outcomes[outcome.key] = outcome
    return [outcomes[run.key] for run in runs]

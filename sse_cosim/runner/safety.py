"""The safety campaign: the hard cases of the occluded zebra, planned as one list of runs.

The claim under test: under the model's assumptions the bus never hits a pedestrian who
steps onto the zebra in front of it at any walking speed up to the estimator's bound, and
always finishes its route. The campaign varies when the pedestrian steps out, how fast it
walks, where it starts behind the parked truck, where the truck is parked, how noisy the
shared sensors are, and the seed.

The grid is not Cartesian over scenario fields: the pedestrian's start is given as an offset
behind the truck's front (``pedestrians.pedestrian.start_pos_m = parked.truck.end_pos_m -
offset``), so it moves with the truck, and a parameter whose pattern selects nothing in a
scenario (the shared sensors' noise in S1, which has none) is simply not varied there, nor is
the start in a scenario without a truck (the junction's pedestrian keeps its start). So the
campaign builds its list of runs here, with the sweep's run type and key scheme
(:class:`~sse_cosim.runner.sweep.PlannedRun`, :func:`~sse_cosim.runner.sweep.run_key`), and
hands it to the sweep's execution path (:func:`~sse_cosim.runner.sweep.run_planned`).

Some combinations cannot happen: the pedestrian cannot walk from its start to the zebra by
the step-out time. The project's own demand planner (:func:`sse_cosim.world.demand.plan_actors`)
decides; such combinations are not run, and are listed in the report as not feasible.

Everything is checked before anything runs: a combination the schema rejects stops the
campaign with a :class:`UserError` (a safety grid holds only meaningful values).
"""

from __future__ import annotations

import itertools
from collections import Counter
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

from pydantic import BaseModel, ConfigDict, Field, model_validator

from sse_cosim.errors import UserError
from sse_cosim.files import read_toml_model, write_json_atomic
from sse_cosim.reporting.outputs import TaskOutcome
from sse_cosim.reporting.safety_report import CAMPAIGN_PEDESTRIAN, SAFETY_PLAN
from sse_cosim.runner.batch import scenario_files
from sse_cosim.runner.executors import Execution
from sse_cosim.runner.sweep import (
    SEED_PATH,
    Parameter,
    ParameterEntry,
    PlannedRun,
    run_key,
    run_planned,
)
from sse_cosim.scenario.loader import apply_overrides, load_scenario_data, validate_scenario
from sse_cosim.scenario.model import Network, Scenario
from sse_cosim.scenario.paths import expand_overrides, expand_pattern, selected_paths

if TYPE_CHECKING:
    from sse_cosim.world.roadmap import RoadMap
    from sse_cosim.world.walk_probe import ProbeTimer

# The campaign moves the pedestrian ``pedestrian`` and the parked truck ``truck`` of each
# scenario (the paper's ids); any other actor of a scenario stays as the scenario sets it.
STEP_OUT_PATH = f"pedestrians.{CAMPAIGN_PEDESTRIAN}.steps_onto_crossing_s"
WALKING_SPEED_PATH = f"pedestrians.{CAMPAIGN_PEDESTRIAN}.walking_speed_mps"
START_PATH = f"pedestrians.{CAMPAIGN_PEDESTRIAN}.start_pos_m"
TRUCK = "truck"
TRUCK_FRONT_PATH = f"parked.{TRUCK}.end_pos_m"
BEHIND_TRUCK = f"{START_PATH} = {TRUCK_FRONT_PATH} - value"
FILE_FIX = "see sweeps/safety.toml for a complete example"

# Why a resolved scenario cannot be run as configured (None: it can). Arguments: the
# scenario and the source to name in errors.
Feasibility = Callable[[Scenario, str], str | None]


# -- the campaign file -----------------------------------------------------------------------

class _FileModel(BaseModel):
    model_config = ConfigDict(extra="forbid", populate_by_name=True)


class StartBehindTruck(_FileModel):
    """``[start_behind_truck]``: the pedestrian's start as offsets (m) behind the truck's
    front, so that it stays hidden wherever the truck is parked."""

    name: str = Field("behind_truck_m", min_length=1)
    values: list[Annotated[float, Field(ge=0)]] = Field(min_length=1)


class QuickSubset(_FileModel):
    """``[quick]``: the few runs of ``--quick``. Each entry keeps only the values it lists
    (scenarios, seeds, and ``values`` per axis name); anything not listed keeps all."""

    scenarios: list[str] | None = Field(None, min_length=1)
    seeds: list[int] | None = Field(None, min_length=1)
    values: dict[str, list[Any]] = Field(default_factory=dict)


class CampaignFile(_FileModel):
    """A campaign file: a sweep file's fields plus the start offsets and the quick subset.

    The parameters must include the step-out time and the walking speed: the report's heat
    maps are drawn over them.
    """

    description: str = ""
    scenarios: list[str] = Field(min_length=1)
    seeds: list[Annotated[int, Field(ge=0)]] = Field(min_length=1)
    overrides: dict[str, Any] = Field(default_factory=dict, alias="set")
    params: list[ParameterEntry] = Field(min_length=1)
    start_behind_truck: StartBehindTruck
    quick: QuickSubset = Field(default_factory=QuickSubset)

    @model_validator(mode="after")
    def _heat_map_axes(self) -> CampaignFile:
        paths = [p.path for p in self.params]
        for needed in (STEP_OUT_PATH, WALKING_SPEED_PATH):
            if needed not in paths:
                raise ValueError(f"params: add a parameter with path = {needed!r} "
                                 "(the report's heat maps are drawn over it)")
        return self


@dataclass(frozen=True)
class Campaign:
    """What the campaign runs: scenario files x parameters x start offsets x seeds.

    ``scenario_names`` are the scenario files as the campaign file names them (for the
    report: no machine paths); ``source`` is the campaign file as given.
    """

    scenarios: tuple[Path, ...]
    scenario_names: tuple[str, ...]
    parameters: tuple[Parameter, ...]
    behind_truck: Parameter
    seeds: tuple[int, ...]
    fixed: Mapping[str, Any] = field(default_factory=dict)
    description: str = ""
    source: str = ""

    @property
    def axes(self) -> tuple[Parameter, ...]:
        """Every varied value but the seed, in the order runs are planned."""
        return (*self.parameters, self.behind_truck)

    @property
    def heat_map_columns(self) -> tuple[str, str]:
        """The step-out time's and the walking speed's columns (x and y of the heat maps)."""
        by_path = {p.pattern: p.column for p in self.parameters}
        return by_path[STEP_OUT_PATH], by_path[WALKING_SPEED_PATH]


def load_campaign(path: Path, quick: bool = False, only: Sequence[str] = ()) -> Campaign:
    """Read and validate a campaign file (its ``[quick]`` subset with ``quick``; with
    ``only``, just the scenarios whose file stems it names)."""
    model = _read_campaign_file(path)
    names = tuple(model.scenarios)
    files = tuple(scenario_files([path.parent / s for s in names]))
    if len(files) != len(names):
        raise UserError(str(path), "scenarios", "name scenario files, not folders",
                        "list each scenario file")
    campaign = Campaign(
        scenarios=files,
        scenario_names=names,
        parameters=tuple(entry.parameter() for entry in model.params),
        behind_truck=Parameter(BEHIND_TRUCK, tuple(model.start_behind_truck.values),
                               model.start_behind_truck.name),
        seeds=tuple(model.seeds),
        fixed=model.overrides,
        description=model.description,
        source=str(path),
    )
    columns = [axis.column for axis in campaign.axes]
    if len(set(columns)) < len(columns) or "seed" in columns:
        raise UserError(str(path), "params", "two axes share a name (or one is named 'seed')",
                        "give every parameter its own name")
    _check_every_parameter_selects(campaign, _scenario_fields(campaign))
    if only:
        campaign = _only_scenarios(campaign, only)
    return _quick_subset(campaign, model.quick) if quick else campaign


def _only_scenarios(campaign: Campaign, stems: Sequence[str]) -> Campaign:
    """``campaign`` with only the scenarios whose file stems ``stems`` names."""
    known = [path.stem for path in campaign.scenarios]
    for stem in stems:
        if stem not in known:
            raise UserError("--scenario", stem, f"is not a scenario of {campaign.source}",
                            f"choose from {', '.join(known)}")
    keep = [i for i, stem in enumerate(known) if stem in stems]
    return replace(campaign, scenarios=tuple(campaign.scenarios[i] for i in keep),
                   scenario_names=tuple(campaign.scenario_names[i] for i in keep))


def _read_campaign_file(path: Path) -> CampaignFile:
    return read_toml_model(path, CampaignFile, "campaign file",
                           "run from the project folder or give --file", FILE_FIX)


def _quick_subset(campaign: Campaign, quick: QuickSubset) -> Campaign:
    """``campaign`` restricted to ``[quick]``; every value kept must be one of the grid's."""
    source = f"{campaign.source}: quick"
    named = dict(zip(campaign.scenario_names, campaign.scenarios, strict=True))
    wanted = _subset(campaign.scenario_names, quick.scenarios, source, "scenarios")
    axes = {axis.column: axis for axis in campaign.axes}
    for column in quick.values:
        if column not in axes:
            raise UserError(source, f"values.{column}", "is not an axis of the campaign",
                            f"use one of {', '.join(axes)}")
    return replace(
        campaign,
        scenarios=tuple(named[name] for name in wanted),
        scenario_names=wanted,
        parameters=tuple(_kept(p, quick.values.get(p.column), source)
                         for p in campaign.parameters),
        behind_truck=_kept(campaign.behind_truck,
                           quick.values.get(campaign.behind_truck.column), source),
        seeds=_subset(campaign.seeds, quick.seeds, source, "seeds"),
    )


def _kept(axis: Parameter, wanted: list[Any] | None, source: str) -> Parameter:
    return replace(axis, values=_subset(axis.values, wanted, source, axis.column))


def _subset(values: Sequence[Any], wanted: Sequence[Any] | None, source: str,
            name: str) -> tuple[Any, ...]:
    """``values`` that ``wanted`` lists, in the grid's order (all of them without a list)."""
    if wanted is None:
        return tuple(values)
    extra = [v for v in wanted if v not in values]
    if extra:
        raise UserError(source, name, f"{extra[0]!r} is not among the campaign's values",
                        f"choose from {list(values)}")
    return tuple(v for v in values if v in wanted)


# -- planning --------------------------------------------------------------------------------

@dataclass(frozen=True)
class NotFeasible:
    """A combination that cannot happen (the planner's reason): listed, never run."""

    run: PlannedRun
    reason: str


@dataclass(frozen=True)
class CampaignPlan:
    """The feasible runs, in plan order, and the combinations left out."""

    runs: tuple[PlannedRun, ...]
    not_feasible: tuple[NotFeasible, ...]


def _is_step_out(field: str) -> bool:
    """Whether ``field`` is some pedestrian's ``steps_onto_crossing_s``."""
    table, _, name = STEP_OUT_PATH.split(".")
    parts = field.split(".")
    return len(parts) == 3 and parts[0] == table and parts[2] == name


class ActorPlanner:
    """Feasibility by the project's own demand planner, on the real road network.

    Each network is built (or found in the cache) once. A scenario is infeasible when the
    planner refuses a pedestrian's step-out time (it cannot walk to its zebra by then: a
    campaign's pedestrian starting far behind, or a falsify candidate's pedestrian sent to a
    far zebra); the reason is the planner's. Any other refusal (a truck off the parking strip)
    is a mistake in the grid, not a case that cannot happen, and stops the campaign.
    """

    def __init__(self) -> None:
        self._networks: dict[str, tuple[Path, RoadMap]] = {}
        self._timers: dict[tuple[Path, float | None], ProbeTimer] = {}

    def __call__(self, scenario: Scenario, source: str) -> str | None:
        from sse_cosim.world import demand

        net_path, roadmap = self._network(scenario.network, source)
        try:
            demand.plan_actors(scenario, net_path, roadmap, source,
                               self._timer(scenario, net_path))
        except UserError as exc:
            if not _is_step_out(exc.field):
                raise
            return exc.problem
        return None

    def walk_times(self, scenario: Scenario, source: str) -> dict[str, float]:
        """Each pedestrian's walk from its start to its crossing (s): the earliest step-out
        time the planner accepts."""
        from sse_cosim.world import demand

        net_path, roadmap = self._network(scenario.network, source)
        return demand.walk_times(scenario, net_path, roadmap, source,
                                 self._timer(scenario, net_path))

    def crossings(self, scenario: Scenario, source: str, pid: str) -> list[str]:
        """The crossings over an automated vehicle's route that pedestrian ``pid`` can take,
        the shortest walk first (:func:`~sse_cosim.world.demand.crossing_choices`)."""
        from sse_cosim.world import demand

        return demand.crossing_choices(scenario, pid, *self._network(scenario.network, source))

    def _timer(self, scenario: Scenario, net_path: Path) -> ProbeTimer:
        """The network's lone-walker timer for the scenario's speed ramp
        (:func:`~sse_cosim.world.demand.walk_timer`, as the planner would make it), kept with
        the times it has taken (walks that repeat over the grid are walked once)."""
        from sse_cosim.world.demand import walk_timer

        fresh = walk_timer(scenario, net_path)
        return self._timers.setdefault((net_path, fresh.accel_mps2), fresh)

    def _network(self, network: Network, source: str) -> tuple[Path, RoadMap]:
        key = f"{network.sources_dir}|{network.net_file}"
        if key not in self._networks:
            from sse_cosim.world.demand import read_net
            from sse_cosim.world.network import scenario_net_path
            from sse_cosim.world.roadmap import load_roadmap

            net_path = scenario_net_path(network, source)
            # with the network read once, not once per combination (the cached road map of
            # a whole network does not keep it)
            roadmap = replace(load_roadmap(net_path), net=read_net(net_path))
            self._networks[key] = (net_path, roadmap)
        return self._networks[key]


def plan_campaign(campaign: Campaign, feasibility: Feasibility | None = None) -> CampaignPlan:
    """Every combination in a fixed order (scenario, axes in file order, start offset, seed),
    split into feasible runs and the combinations ``feasibility`` rules out.

    Raises :class:`UserError` for anything wrong with the grid: a field set from two places,
    a value the schema rejects, two identical runs (a pattern that selects nothing anywhere
    is refused by :func:`load_campaign`).
    """
    check = feasibility or ActorPlanner()
    datas = [load_scenario_data(path) for path in campaign.scenarios]
    fields = _scenario_fields(campaign, datas)
    targets = _parameter_targets(campaign, fields)
    runs: list[PlannedRun] = []
    left_out: list[NotFeasible] = []
    for path, data, found, paths in zip(campaign.scenarios, datas, fields, targets,
                                        strict=True):
        for run, scenario in _scenario_runs(campaign, path, data, found, paths):
            reason = check(scenario, str(path))
            if reason is None:
                runs.append(run)
            else:
                left_out.append(NotFeasible(run, reason))
    keys = Counter(run.key for run in (*runs, *(n.run for n in left_out)))
    twice = sorted(key for key, n in keys.items() if n > 1)
    if twice:
        raise UserError(campaign.source, "", f"some runs would be identical ({twice[0]}, ...)",
                        "remove repeated values, seeds or scenario files of the same name")
    return CampaignPlan(tuple(runs), tuple(left_out))


def _scenario_fields(campaign: Campaign,
                     datas: Sequence[Mapping[str, Any]] | None = None) -> list[dict[str, Any]]:
    """Every scenario's fields, validated (from its file's ``datas`` if given)."""
    datas = datas or [load_scenario_data(path) for path in campaign.scenarios]
    return [validate_scenario(data, str(path)).model_dump(mode="json")
            for data, path in zip(datas, campaign.scenarios, strict=True)]


def _parameter_targets(campaign: Campaign,
                       fields: Sequence[Mapping[str, Any]]) -> list[list[list[str]]]:
    """Per scenario, per parameter, the concrete paths it sets (none where its pattern selects
    nothing there)."""
    return [[selected_paths(p.pattern, found, str(path)) for p in campaign.parameters]
            for found, path in zip(fields, campaign.scenarios, strict=True)]


def _check_every_parameter_selects(campaign: Campaign,
                                   fields: Sequence[Mapping[str, Any]]) -> None:
    """Raise :class:`UserError` for a parameter whose pattern selects nothing in any of the
    campaign file's scenarios (checked on the whole file: a part of it, ``--scenario``, may
    leave a parameter out)."""
    targets = _parameter_targets(campaign, fields)
    for i, parameter in enumerate(campaign.parameters):
        if not any(per_scenario[i] for per_scenario in targets):
            expand_pattern(parameter.pattern, fields[0], campaign.source)  # raises: why


def _scenario_runs(campaign: Campaign, path: Path, data: Mapping[str, Any],
                   fields: Mapping[str, Any],
                   targets: Sequence[list[str]]) -> Iterator[tuple[PlannedRun, Scenario]]:
    """The runs of one scenario file, each with its resolved scenario."""
    source = str(path)
    fixed = expand_overrides(campaign.fixed, fields, source)
    active = [(p, paths) for p, paths in zip(campaign.parameters, targets, strict=True) if paths]
    _check_disjoint(fixed, active, source)
    behind = campaign.behind_truck
    for combination in itertools.product(*(p.values for p, _ in active)):
        values = {p.column: v for (p, _), v in zip(active, combination, strict=True)}
        overrides = dict(fixed)
        for (_, paths), value in zip(active, combination, strict=True):
            overrides.update(dict.fromkeys(paths, value))
        truck = fields["parked"].get(TRUCK)
        # a scenario without the truck keeps its pedestrian's start: the axis is not varied
        offsets = behind.values if truck is not None else (None,)
        for offset, seed in itertools.product(offsets, campaign.seeds):
            run_values, run_overrides = dict(values), {**overrides, SEED_PATH: seed}
            if offset is not None:
                truck_front = overrides.get(TRUCK_FRONT_PATH, truck["end_pos_m"])
                run_values[behind.column] = offset
                run_overrides[START_PATH] = round(truck_front - offset, 9)
            key = run_key(path.stem, list(run_values.items()), seed, run_overrides)
            scenario = validate_scenario(apply_overrides(data, run_overrides, source),
                                         f"{source} ({key})")
            yield PlannedRun(key=key, scenario=str(path.resolve()), seed=seed,
                             values=run_values, overrides=run_overrides), scenario


def _check_disjoint(fixed: Mapping[str, Any], active: Sequence[tuple[Parameter, list[str]]],
                    source: str) -> None:
    """Each field is set from one place: ``set``, one parameter, the start offset or seeds."""
    owners = {START_PATH: "start_behind_truck", SEED_PATH: "seeds"}
    claims = [*((path, f"set {path}") for path in fixed),
              *((path, p.pattern) for p, paths in active for path in paths)]
    for path, owner in claims:
        if path in owners and owners[path] != owner:
            raise UserError(source, owner, f"sets {path}, which {owners[path]} sets too",
                            "set each field from one place only")
        owners[path] = owner


# -- running ---------------------------------------------------------------------------------

def plan_document(campaign: Campaign, plan: CampaignPlan, command: str) -> dict[str, Any]:
    """``safety.json.gz``: how the campaign was made, every run and every combination left out
    (what the report reads). Scenario files appear as the campaign file names them."""
    names = dict(zip((p.stem for p in campaign.scenarios), campaign.scenario_names,
                     strict=True))
    step_out, walking = campaign.heat_map_columns

    def entry(run: PlannedRun) -> dict[str, Any]:
        stem = Path(run.scenario).stem
        return {"key": run.key, "scenario": stem, "file": names[stem], "seed": run.seed,
                "values": run.values, "overrides": run.overrides}

    return {
        "command": command,
        "campaign": campaign.source,
        "description": campaign.description,
        "scenarios": list(campaign.scenario_names),
        "seeds": list(campaign.seeds),
        "set": dict(campaign.fixed),
        "axes": [{"column": a.column, "path": a.pattern, "values": list(a.values)}
                 for a in campaign.axes],
        "heat_map": {"x": step_out, "y": walking},
        "runs": [entry(run) for run in plan.runs],
        "not_feasible": [{**entry(n.run), "reason": n.reason} for n in plan.not_feasible],
    }


def run_campaign(
    campaign: Campaign,
    plan: CampaignPlan,
    out_dir: Path,
    command: str,
    execution: Execution,
) -> list[TaskOutcome]:
    """Write ``safety.json.gz``, then run the feasible runs (summaries only) through the sweep's
    execution path; outcomes in plan order."""
    write_json_atomic(out_dir / SAFETY_PLAN, plan_document(campaign, plan, command))
    return run_planned(plan.runs, out_dir, True, execution, "safety")

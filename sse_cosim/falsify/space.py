"""The falsifier's search space: what the assumptions A1-A4 (docs/controller.md) leave free.

A falsify file (``sweeps/falsify.toml``) names the free choices; this module turns them, for
one scenario, into a box of :class:`Dimension` s and decodes a point of the unit cube into
scenario overrides:

- ``[set]``: fixed overrides of every run (a longer horizon for liveness, as the safety
  campaign's).
- ``[[dims]]``: a dotted path pattern (as a sweep's) and the interval its fields range over
  (when the pedestrian steps onto the zebra, how fast it walks); a pattern that selects
  nothing in the scenario is not searched there.
- ``[step_out]``: when a pedestrian steps onto the zebra, as the time it waits at its start
  beyond the earliest its walk allows: it steps out at its walk time (from its start at its
  walking speed, to the zebra it crosses, timed by the project's planner) plus the wait, so
  every candidate can happen (a step-out time searched directly leaves part of the box
  unreachable). A name glob times every pedestrian it selects, each with its own wait (with
  ``[crossing]``, each can then reach whichever zebra the search gives it).
- ``[start_behind_truck]``: the pedestrian's start as an offset behind the parked truck's
  front, as in the safety campaign (so it stays hidden wherever the truck stands).
- ``[noise]``: each selected sensor's error held toward a chosen point of its noise bound
  (A2 allows any error within it): a within-bound bias fault (``faults.sensor``) whose offset
  along each measurement axis is ``2 f r`` with ``f`` in [-1, 1] and ``r`` the bound, clipped
  to the bound. ``f = +-1`` puts every measurement on the bound, ``f = 0`` leaves the noise
  as drawn.
- ``[loss]``: for each node that sends to an automated vehicle, one burst of lost messages
  (A3 allows any loss): its start and its length up to ``longest_s``.
- ``[latency]``: for each such node, one window of late messages (a latency fault: the bus
  predicts each message by its true age, and late views are not used as negative
  information, so A3 holds): its start, its length up to ``longest_s`` and the steps added
  to the link's latency, up to ``most_steps`` (rounded to whole steps; 0: none).
- ``[crossing]``: which zebra each selected pedestrian steps onto, of those over an automated
  vehicle's route that its walk from its start to its end can take (the planner lists them,
  shortest walk first; one value in [0, 1] each, the choices splitting it evenly). A
  pedestrian with one such zebra is not searched.

The box is validated at its corners with the scenario's own ``breaks_assumptions``, so an
interval outside the assumptions (a walking speed above the estimator's bound) is refused
before anything runs; the runs themselves list :data:`COUNTED_BREAKS`, so that the world's
breaks are counted, not fatal.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationInfo, field_validator

from sse_cosim.errors import UserError
from sse_cosim.files import read_toml_model
from sse_cosim.runner.safety import START_PATH, TRUCK
from sse_cosim.scenario.loader import apply_overrides, validate_scenario
from sse_cosim.scenario.model import Scenario
from sse_cosim.scenario.paths import expand_overrides, selected_paths

COUNTED_BREAKS = ("pedestrian_speed", "walkable_ground")
"""The world's breaks of A1 that every search run counts instead of stopping at: SUMO may
move a walker off the model whatever the candidate (after a collision, a walker held on a
walking area can jump), and a run stopped there would hide what came before it. The search
reports every break and counts a failure only if it came before the first break."""
BREAKS_PATH = "breaks_assumptions"
FAULT_PREFIX = "falsify_"
"""Faults the search adds are named ``falsify_<sensor or node>``."""
PRESENT_FROM = 0.5
"""A ``[present]`` pedestrian is in the scene where its value is at least this."""
STEP_OUT_FIELD = "steps_onto_crossing_s"
DECIMALS = 6
"""Decoded values are rounded to this many decimals (1 µs, 1 µm): run keys and the worst
cases' scenario files stay readable and exact."""


class _FileModel(BaseModel):
    model_config = ConfigDict(extra="forbid", populate_by_name=True)


class DimEntry(_FileModel):
    """``[[dims]]``: a path pattern and the interval [low, high] its fields range over."""

    path: str = Field(min_length=1)
    name: str = Field(min_length=1)
    low: float
    high: float

    @field_validator("high")
    @classmethod
    def _above_low(cls, high: float, info: ValidationInfo) -> float:
        low = info.data.get("low")
        if low is not None and not low < high:
            raise ValueError(f"must be above low ({low:g}); widen the interval")
        return high


class StepOut(_FileModel):
    """``[step_out]``: pedestrian ``pedestrian`` waits [low, high] s at its start beyond the
    earliest step-out its walk allows; a glob (``"*"``, ``"w?"``) gives every pedestrian it
    selects a wait of its own, named ``<pedestrian>_<name>``."""

    name: str = Field("wait_s", min_length=1)
    pedestrian: str = Field("pedestrian", min_length=1)
    low: float = Field(0.0, ge=0)
    high: float = Field(gt=0)


class BehindTruck(_FileModel):
    """``[start_behind_truck]``: the pedestrian's start, [low, high] m behind the truck's
    front."""

    name: str = Field("behind_m", min_length=1)
    low: float = Field(ge=0)
    high: float = Field(gt=0)


class NoiseEntry(_FileModel):
    """``[noise]``: the sensors (a name glob) whose error the search holds within the bound."""

    sensors: str = Field("*", min_length=1)


class LossEntry(_FileModel):
    """``[loss]``: one burst of lost messages per sending node, at most ``longest_s`` long."""

    longest_s: float = Field(gt=0)


class LatencyEntry(_FileModel):
    """``[latency]``: one window of late messages per sending node, at most ``longest_s``
    long and ``most_steps`` steps late."""

    longest_s: float = Field(gt=0)
    most_steps: int = Field(ge=1, le=100)


class PresentEntry(_FileModel):
    """``[present]``: the pedestrians (a name glob) of whom the search chooses who is in the
    scene: one value in [0, 1] each, in the scene from 0.5."""

    pedestrians: str = Field("*", min_length=1)


class CrossingEntry(_FileModel):
    """``[crossing]``: the pedestrians (a name glob) whose zebra the search chooses."""

    pedestrians: str = Field("*", min_length=1)


class FalsifyFile(_FileModel):
    """A falsify file: the free choices the search steers."""

    description: str = ""
    overrides: dict[str, Any] = Field(default_factory=dict, alias="set")
    dims: list[DimEntry] = Field(default_factory=list)
    step_out: StepOut | None = None
    start_behind_truck: BehindTruck | None = None
    noise: NoiseEntry | None = None
    loss: LossEntry | None = None
    latency: LatencyEntry | None = None
    present: PresentEntry | None = None
    crossing: CrossingEntry | None = None


def load_falsify_file(path: Path) -> FalsifyFile:
    """The falsify file at ``path``; :class:`UserError` naming the field if it is wrong."""
    return read_toml_model(path, FalsifyFile, "falsify file",
                           "give a falsify file, e.g. sweeps/falsify.toml",
                           "see sweeps/falsify.toml for a complete example")


@dataclass(frozen=True)
class Dimension:
    """One searched value: ``name`` ranging over [low, high]."""

    name: str
    low: float
    high: float

    def value(self, unit: float) -> float:
        """The value at ``unit`` in [0, 1] (clipped), rounded to :data:`DECIMALS`."""
        u = min(max(float(unit), 0.0), 1.0)
        return round(self.low + u * (self.high - self.low), DECIMALS)


@dataclass(frozen=True)
class _Wait:
    pedestrian: str
    name: str  # its dimension's
    derived: str  # the name of the step-out time it makes, among a point's values


@dataclass(frozen=True)
class _Noise:
    sensor: str
    bound_m: tuple[float, float]


@dataclass(frozen=True)
class _Crossings:
    pedestrian: str
    choices: tuple[str, ...]  # shortest walk first

    def chosen(self, value: float) -> str:
        """The crossing at ``value`` in [0, 1]: the choices split it evenly."""
        return self.choices[min(int(value * len(self.choices)), len(self.choices) - 1)]


@dataclass(frozen=True)
class SearchSpace:
    """One scenario's search box and how a point of it becomes scenario overrides.

    ``dims`` in order: the ``[[dims]]`` that select something (``targets``: the concrete
    paths each sets), the waits before the step-outs (``step_outs``: one per pedestrian of
    ``[step_out]`` the scenario has), the start behind the truck (if the scenario has the
    truck), two per noisy sensor (forward, lateral fraction of the bound), two per sender
    (loss start and length), three per late sender (start, length, steps late), one per
    pedestrian of ``[present]`` (in the scene from 0.5), one per pedestrian of
    ``[crossing]`` with a choice.
    """

    dims: tuple[Dimension, ...]
    targets: tuple[tuple[str, ...], ...]
    step_outs: tuple[_Wait, ...]
    truck_front_m: float | None
    noises: tuple[_Noise, ...]
    senders: tuple[str, ...]
    late_senders: tuple[str, ...]
    step_length_s: float
    fixed: Mapping[str, Any]
    present: tuple[str, ...] = ()
    crossings: tuple[_Crossings, ...] = ()

    @property
    def size(self) -> int:
        return len(self.dims)

    def values(self, unit: Sequence[float]) -> dict[str, float]:
        """The named values at ``unit``, shape (size,), in [0, 1]."""
        if len(unit) != self.size:
            raise ValueError(f"a point of this space has {self.size} coordinates, not {len(unit)}")
        return {d.name: d.value(u) for d, u in zip(self.dims, unit, strict=True)}

    def overrides(self, values: Mapping[str, float]) -> dict[str, Any]:
        """The scenario overrides (dotted path -> value) that realise ``values``, but for the
        step-out times (:meth:`step_out_overrides`: they need the walks they make)."""
        names = iter(d.name for d in self.dims)
        out: dict[str, Any] = dict(self.fixed)
        for paths in self.targets:
            out.update(dict.fromkeys(paths, values[next(names)]))
        for _ in self.step_outs:
            next(names)
        if self.truck_front_m is not None:
            out[START_PATH] = round(self.truck_front_m - values[next(names)], DECIMALS)
        for noise in self.noises:
            f = (values[next(names)], values[next(names)])
            bias = [round(2.0 * fi * r, DECIMALS) for fi, r in zip(f, noise.bound_m, strict=True)]
            if any(bias):  # no bias: the noise as drawn (a zero bias fault is refused)
                out[f"faults.sensor.{FAULT_PREFIX}{noise.sensor}"] = {
                    "sensor": noise.sensor, "kind": "bias", "bias_m": bias,
                    "within_bound": True}
        for node in self.senders:
            start, length = values[next(names)], values[next(names)]
            if length >= self.step_length_s:  # shorter than a step: nothing is lost
                out[f"faults.link.{FAULT_PREFIX}{node}"] = {
                    "node": node, "kind": "loss", "start_s": start,
                    "end_s": round(start + length, DECIMALS)}
        for node in self.late_senders:
            start, length = values[next(names)], values[next(names)]
            steps = round(values[next(names)])
            if steps >= 1 and length >= self.step_length_s:
                out[f"faults.link.{FAULT_PREFIX}late_{node}"] = {
                    "node": node, "kind": "latency", "start_s": start,
                    "end_s": round(start + length, DECIMALS), "extra_latency_steps": steps}
        for pid in self.present:
            out[f"pedestrians.{pid}.present"] = values[next(names)] >= PRESENT_FROM
        for choice in self.crossings:
            out[f"pedestrians.{choice.pedestrian}.crossing"] = choice.chosen(values[next(names)])
        return out

    def step_out_overrides(self, values: Mapping[str, float],
                           walk_s: Mapping[str, float]) -> dict[str, float]:
        """The step-out time of each ``[step_out]`` pedestrian: its walk (``walk_s``:
        pedestrian -> s, as the planner times the scenario of :meth:`overrides`) plus its
        wait; none for a pedestrian ``[present]`` left out (the planner times no walk)."""
        return {step_out_path(w.pedestrian): round(walk_s[w.pedestrian] + values[w.name],
                                                   DECIMALS)
                for w in self.step_outs if w.pedestrian in walk_s}


def step_out_path(pedestrian: str) -> str:
    return f"pedestrians.{pedestrian}.{STEP_OUT_FIELD}"


CrossingChoices = Callable[[Scenario, str, str], Sequence[str]]
"""The crossings pedestrian ``pid`` of a scenario (read from a source) can step onto, shortest
walk first (:meth:`sse_cosim.runner.safety.ActorPlanner.crossings`): called as
``(scenario, source, pid)``."""


def build_space(spec: FalsifyFile, data: Mapping[str, Any], source: str,
                spec_source: str, crossings: CrossingChoices | None = None) -> SearchSpace:
    """``spec`` for the scenario ``data`` (its file ``source``): the dims that select
    something there; ``crossings`` lists a pedestrian's zebras (needed by ``[crossing]``).
    Raises :class:`UserError` if nothing is left to search, or if a corner of the box does
    not validate (an interval outside what the schema allows)."""
    fixed = expand_overrides(spec.overrides,
                             validate_scenario(data, source).model_dump(mode="json"), spec_source)
    scenario = validate_scenario(apply_overrides(data, fixed, source), source)
    counted = {**fixed, BREAKS_PATH: sorted({*scenario.breaks_assumptions, *COUNTED_BREAKS})}
    fields = scenario.model_dump(mode="json")
    dims: list[Dimension] = []
    targets: list[tuple[str, ...]] = []
    for entry in spec.dims:
        paths = selected_paths(entry.path, fields, spec_source)
        if paths:
            dims.append(Dimension(entry.name, entry.low, entry.high))
            targets.append(tuple(paths))
    waits = _waits(spec, fields)
    for wait in waits:
        if any(step_out_path(wait.pedestrian) in paths for paths in targets):
            raise UserError(spec_source, "step_out", f"{step_out_path(wait.pedestrian)} "
                            "is searched by [[dims]] too", "search it in one place")
        dims.append(Dimension(wait.name, spec.step_out.low, spec.step_out.high))
    truck = scenario.parked.get(TRUCK)
    truck_front = None
    behind = spec.start_behind_truck
    if behind is not None and truck is not None and START_PATH.split(".")[1] in (
            scenario.pedestrians):
        dims.append(Dimension(behind.name, behind.low, behind.high))
        truck_front = truck.end_pos_m
    noises = _noises(spec, scenario, fields)
    for noise in noises:
        dims += [Dimension(f"noise_{noise.sensor}_fwd", -1.0, 1.0),
                 Dimension(f"noise_{noise.sensor}_lat", -1.0, 1.0)]
    senders = tuple(scenario.sender_ids()) if spec.loss is not None else ()
    duration = scenario.simulation.duration_s
    for node in senders:
        dims += [Dimension(f"loss_{node}_start_s", 0.0, duration),
                 Dimension(f"loss_{node}_length_s", 0.0, spec.loss.longest_s)]
    late = tuple(scenario.sender_ids()) if spec.latency is not None else ()
    for node in late:
        dims += [Dimension(f"late_{node}_start_s", 0.0, duration),
                 Dimension(f"late_{node}_length_s", 0.0, spec.latency.longest_s),
                 Dimension(f"late_{node}_steps", 0.0, float(spec.latency.most_steps))]
    present = _present(spec, scenario, fields)
    dims += [Dimension(f"present_{pid}", 0.0, 1.0) for pid in present]
    choices = _crossings(spec, scenario, fields, source, crossings)
    dims += [Dimension(f"crossing_{c.pedestrian}", 0.0, 1.0) for c in choices]
    if len(dims) < 2:
        raise UserError(spec_source, "dims", f"selects {len(dims)} value(s) in {source}",
                        "a search needs at least two: add dims that name this scenario's "
                        "fields (`sse-cosim fields` lists them)")
    space = SearchSpace(tuple(dims), tuple(targets), waits, truck_front, noises, senders,
                        late, scenario.simulation.step_length_s, counted, present, choices)
    _check_corners(space, data, source, spec_source)
    return space


def _waits(spec: FalsifyFile, fields: Mapping[str, Any]) -> tuple[_Wait, ...]:
    """The pedestrians ``[step_out]`` selects in the scenario (``fields``: its dump), each with
    its wait's name: the file's own for a pedestrian named outright, ``<pedestrian>_<name>``
    for each one a glob selects."""
    if spec.step_out is None:
        return ()
    who, name = spec.step_out.pedestrian, spec.step_out.name
    found = [path.split(".")[1] for path in selected_paths(
        step_out_path(who), fields, "")]
    if found == [who]:
        return (_Wait(who, name, STEP_OUT_FIELD),)
    return tuple(_Wait(pid, f"{pid}_{name}", f"{pid}_{STEP_OUT_FIELD}") for pid in found)


def _noises(spec: FalsifyFile, scenario: Scenario,
            fields: Mapping[str, Any]) -> tuple[_Noise, ...]:
    """The sensors ``[noise]`` selects in ``scenario`` (``fields``: its dump), with their
    bounds."""
    if spec.noise is None:
        return ()
    found = selected_paths(f"sensors.{spec.noise.sensors}.noise_bound_m", fields, "")
    out = []
    for path in found:
        name = path.split(".")[1]
        bound = tuple(float(r) for r in scenario.sensors[name].noise_bound_m)
        out.append(_Noise(name, (bound[0], bound[1])))
    return tuple(out)


def _present(spec: FalsifyFile, scenario: Scenario,
             fields: Mapping[str, Any]) -> tuple[str, ...]:
    """The pedestrians ``[present]`` selects in ``scenario`` (``fields``: its dump) that are in
    its scene."""
    if spec.present is None:
        return ()
    found = selected_paths(f"pedestrians.{spec.present.pedestrians}.present", fields, "")
    return tuple(pid for pid in (path.split(".")[1] for path in found)
                 if scenario.pedestrians[pid].present)


def _crossings(spec: FalsifyFile, scenario: Scenario, fields: Mapping[str, Any], source: str,
               crossings: CrossingChoices | None) -> tuple[_Crossings, ...]:
    """The pedestrians ``[crossing]`` selects in ``scenario`` (``fields``: its dump) that are in
    its scene and have more than one zebra to choose from, with their zebras."""
    if spec.crossing is None:
        return ()
    if crossings is None:
        raise ValueError("a [crossing] search needs the planner's crossing choices")
    found = selected_paths(f"pedestrians.{spec.crossing.pedestrians}.crossing", fields, "")
    out = []
    for pid in (path.split(".")[1] for path in found):
        if scenario.pedestrians[pid].present:
            zebras = tuple(crossings(scenario, source, pid))
            if len(zebras) > 1:
                out.append(_Crossings(pid, zebras))
    return tuple(out)


def _check_corners(space: SearchSpace, data: Mapping[str, Any], source: str,
                   spec_source: str) -> None:
    """The box's lowest and highest corners validate (the schema's bounds hold inside)."""
    for unit in (np.zeros(space.size), np.ones(space.size)):
        overrides = space.overrides(space.values(unit))
        overrides.pop(BREAKS_PATH)  # the corners must keep the assumptions as the scenario does
        try:
            validate_scenario(apply_overrides(data, overrides, source), source)
        except UserError as exc:
            raise UserError(spec_source, exc.field, f"at a corner of the search box {source} "
                            f"is refused: {exc.problem}",
                            "narrow the interval to values the scenario allows") from None


WalkTimes = Callable[[Scenario, str], Mapping[str, float]]
"""The planner's walk of each pedestrian of a scenario (read from a source), in s."""


def scenario_of(space: SearchSpace, data: Mapping[str, Any], unit: Sequence[float],
                source: str, walk_times: WalkTimes) -> tuple[dict[str, float], dict[str, Any],
                                                             Scenario]:
    """The values (with the step-out time they make, under its path's last name), overrides
    and validated scenario at ``unit``; ``walk_times`` times the walk before the step-out."""
    values = space.values(unit)
    overrides = space.overrides(values)
    scenario = validate_scenario(apply_overrides(data, overrides, source), source)
    step_outs = space.step_out_overrides(values, walk_times(scenario, source)
                                         if space.step_outs else {})
    if not step_outs:
        return values, overrides, scenario
    overrides.update(step_outs)
    derived = {w.derived: step_outs[step_out_path(w.pedestrian)] for w in space.step_outs
               if step_out_path(w.pedestrian) in step_outs}
    return ({**values, **derived}, overrides,
            validate_scenario(apply_overrides(data, overrides, source), source))

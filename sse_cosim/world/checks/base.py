"""One checked assumption of the simulated world: a small interface, and the ledger that turns
what a check finds into a stopped run or, in a study that declares it, a count.

A check (:class:`WorldCheck`) looks at each step's snapshot and returns the :class:`Break`
records it finds. :class:`Ledger` runs every check of a run: a break of an assumption the
study does not list in ``breaks_assumptions`` stops the run with
:class:`~sse_cosim.errors.AssumptionBroken` (one line: what happened and the fix); one it
lists is counted, the first :data:`KEPT_BREAKS` kept for ``summary.json``
(:attr:`Ledger.summary`). Pure: the SUMO adapter hands each check what it reads.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, ClassVar

from sse_cosim.control.swept import RoutePath
from sse_cosim.errors import AssumptionBroken
from sse_cosim.scenario.model import Scenario
from sse_cosim.world.roadmap import RoadMap
from sse_cosim.world.snapshot import Snapshot

KEPT_BREAKS = 5
"""The first breaks a study that lists an assumption keeps in its summary (all are counted)."""


@dataclass(frozen=True)
class Break:
    """One break of an assumption: ``problem`` and ``fix`` for the one-line stop, ``record``
    what a declaring study's summary keeps of it (JSON values)."""

    problem: str
    fix: str
    record: dict[str, Any]


@dataclass(frozen=True)
class StepFacts:
    """What the world knows of a step beside its snapshot: each pedestrian's lane at the
    previous and at this step (SUMO lane ids; "" off every lane)."""

    lanes_before: Mapping[str, str] = field(default_factory=dict)
    lanes_now: Mapping[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class CheckSetup:
    """What a check is built from: the ``scenario`` as run (its jitter resolved), the
    ``roadmap`` (its measured ground included) and the estimator's acceleration bound
    (m/s², None for a speed-bounded model)."""

    scenario: Scenario
    roadmap: RoadMap
    accel_mps2: float | None = None

    @cached_property
    def route_paths(self) -> dict[str, RoutePath]:
        """Each automated vehicle's route as SUMO drives it (its lanes, each its ``length``
        along its shape, and its lane changes' detours), by vehicle id: built once for every
        check that reads it."""
        return {vid: RoutePath.of_route(*self.roadmap.route_plan(vehicle.route_edges))
                for vid, vehicle in self.scenario.automated.items()}

    def declares(self, name: str) -> bool:
        """Whether the study lists assumption ``name`` in ``breaks_assumptions``."""
        return name in self.scenario.breaks_assumptions


class WorldCheck(ABC):
    """An assumption the estimator or the controller makes of the world, checked each step.

    ``name`` is what ``breaks_assumptions`` lists for it; ``summary_key`` where a study that
    lists it finds its breaks in ``summary.json``. :meth:`build` makes it for a run (None:
    nothing to check there).
    """

    name: ClassVar[str]
    summary_key: ClassVar[str]

    @classmethod
    @abstractmethod
    def build(cls, setup: CheckSetup) -> WorldCheck | None:
        """This check for the run of ``setup``, or None if the run gives it nothing to check."""

    @abstractmethod
    def check(self, snapshot: Snapshot, facts: StepFacts) -> Sequence[Break]:
        """The breaks of this assumption at the step of ``snapshot``."""


@dataclass
class _Tally:
    count: int = 0
    first: list[dict[str, Any]] = field(default_factory=list)


class Ledger:
    """Runs a run's checks each step (see module docstring); ``declared``: the assumptions
    its study lists in ``breaks_assumptions``; ``source``: the scenario, for the message."""

    def __init__(self, checks: Iterable[WorldCheck], declared: Iterable[str],
                 source: str) -> None:
        self.checks = tuple(checks)
        self.declared = frozenset(declared)
        self.source = source
        self._tallies = {c.name: _Tally() for c in self.checks if c.name in self.declared}

    def step(self, snapshot: Snapshot, facts: StepFacts) -> None:
        """Check ``snapshot``: raise :class:`AssumptionBroken` at the first break of an
        assumption not declared; count the others."""
        for check in self.checks:
            for brk in check.check(snapshot, facts):
                tally = self._tallies.get(check.name)
                if tally is None:
                    raise AssumptionBroken(self.source, check.name, brk.problem, brk.fix)
                tally.count += 1
                if len(tally.first) < KEPT_BREAKS:
                    tally.first.append(brk.record)

    @property
    def summary(self) -> dict[str, dict[str, Any]]:
        """Per declared assumption checked here, under its ``summary_key``: ``{"count",
        "first"}`` (the first :data:`KEPT_BREAKS` records)."""
        return {c.summary_key: {"count": self._tallies[c.name].count,
                                "first": list(self._tallies[c.name].first)}
                for c in self.checks if c.name in self._tallies}

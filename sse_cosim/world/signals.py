"""Traffic lights: what a signal shows now and how soon one of its links can let traffic go.
Pure data, no SUMO.

A SUMO traffic light controls links (a vehicle lane's connection into a junction, a walking
area's entry onto a crossing), each one character of its state string: ``r`` red, ``y``
yellow, ``u`` red-yellow, ``G``/``g`` green (major/minor), ``s`` a green arrow that requires a
stop first, ``o``/``O`` off (blinking/no signal). Its program runs phases in order, each with
a state and a duration; an actuated program may end a phase anywhere between its ``minDur``
and ``maxDur``. SUMO's vehicles stop at ``r`` and ``u`` and, where they still can, at ``y``
(:data:`STOP_FOR`); its walkers do not step onto a crossing whose link is ``r``
(:data:`WALKERS_WAIT`: the assumption :mod:`sse_cosim.world.checks.signals` checks).

:func:`earliest_release_s` bounds from below how long a link keeps showing a state of a set
(red, for a walker): the rest of the current phase at its shortest, then each following phase
at its shortest, until the first that shows another state. The bound needs the phases to run
in order; a program whose phases name their successors (``next``) gets the current phase's
rest alone.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

Signal = tuple[str, int]
"""A traffic light's id and the index of one of its links (into its state string)."""

STOP_FOR = frozenset("ryu")
"""The states at which a vehicle that can still stop before the stop line stops (SUMO)."""
WALKERS_WAIT = frozenset("r")
"""The states at which no walker steps onto a crossing (the declared assumption)."""
WALKERS_GO = frozenset("Gg")
"""The states at which a planned walker may step onto its crossing as planned."""


@dataclass(frozen=True)
class Phase:
    """One phase of a program: its ``state`` string and its shortest duration (s)."""

    state: str
    min_s: float


@dataclass(frozen=True)
class Program:
    """A traffic light's program as the network defines it; ``in_order``: its phases run
    one after the other, cyclically (none names a successor); ``static``: each phase lasts
    its duration (``Phase.min_s``), so the program's state at any time is known in advance;
    ``offset_s``: at SUMO time t a static program is ``(t - offset_s) mod cycle`` into its
    cycle (measured against SUMO 1.28)."""

    id: str
    phases: tuple[Phase, ...]
    in_order: bool = True
    static: bool = True
    offset_s: float = 0.0

    @property
    def cycle_s(self) -> float:
        """The cycle's length (s): its phases' durations."""
        return sum(phase.min_s for phase in self.phases)

    def windows(self, link: int, states: frozenset[str], from_s: float,
                until_s: float) -> list[tuple[float, float]]:
        """The SUMO-time intervals ``[start, end)`` between ``from_s`` and ``until_s`` in which
        a static program shows link ``link`` in one of ``states``, in order."""
        cycle = self.cycle_s
        if not self.static or cycle <= 0.0:
            raise ValueError("only a static program's windows are known in advance")
        first = math.floor((from_s - self.offset_s) / cycle) * cycle + self.offset_s
        windows: list[tuple[float, float]] = []
        start = first
        while start < until_s:
            for phase in self.phases:
                end = start + phase.min_s
                if phase.state[link] in states and end > from_s and start < until_s:
                    if windows and abs(windows[-1][1] - start) < 1e-9:
                        windows[-1] = (windows[-1][0], end)
                    else:
                        windows.append((start, end))
                start = end
        return windows


@dataclass(frozen=True)
class SignalState:
    """One traffic light at one step: the ``program`` running, its ``phase`` index, the
    ``state`` string (one character per link) and how long the phase has been on (s)."""

    program: str
    phase: int
    state: str
    spent_s: float

    def shows(self, link: int) -> str:
        """The state character of link ``link``."""
        return self.state[link]


def earliest_release_s(program: Program, now: SignalState, link: int,
                       held: frozenset[str]) -> float:
    """A lower bound (s) on how long link ``link`` keeps showing a state of ``held`` (0 if it
    shows another now; infinite if every phase holds it): the current phase's shortest rest,
    then (phases in order) each next phase's shortest duration while it holds the link."""
    if now.shows(link) not in held:
        return 0.0
    phases = program.phases
    wait = max(0.0, phases[now.phase].min_s - now.spent_s)
    if not program.in_order:
        return wait
    for k in range(1, len(phases)):
        phase = phases[(now.phase + k) % len(phases)]
        if phase.state[link] not in held:
            return wait
        wait += phase.min_s
    return math.inf


@dataclass(frozen=True)
class CrossingLights:
    """The lights of a signalised crossing: the ``signals`` of the links that let walkers
    onto it, and the network's ``programs`` of their lights, by (light, program id)."""

    signals: tuple[Signal, ...]
    programs: Mapping[tuple[str, str], Program]

    def release_s(self, states: Mapping[str, SignalState]) -> float:
        """A lower bound (s) on how long no walker off the crossing steps onto it: 0 unless
        every light of its links shows red now (:data:`WALKERS_WAIT`), else the least time
        any of them can change (:func:`earliest_release_s`; 0 for a light ``states`` lacks
        or that runs a program the network does not define)."""
        waits = []
        for light, link in self.signals:
            state = states.get(light)
            program = None if state is None else self.programs.get((light, state.program))
            if state is None or program is None or state.phase >= len(program.phases):
                return 0.0
            waits.append(earliest_release_s(program, state, link, WALKERS_WAIT))
        return min(waits, default=0.0)

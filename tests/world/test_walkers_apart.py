"""The jitter measurement's walkers walk alone (world/walker_jitter.py, ``_walk_apart``):
walkers sharing an edge depart in different slots, and walkers that SUMO held up until they
met all the same walk again in a simulation of their own, in longer slots; never a traceback.
Before, a whole town's measurement stopped with ``RuntimeError: walkers w53135 and w53140 met``.
SUMO is replaced by a stand-in that answers the walk it is given (the same in every call), so
that the meeting is under the test's control."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sse_cosim.errors import SimulationError
from sse_cosim.world import walker_jitter
from sse_cosim.world.walk_probe import Walker, WalkTrace


def walkers() -> list[Walker]:
    """w0 and w1 share edge e; w2 walks elsewhere."""
    return [Walker("w0", ("a", "e"), 1.0, 1.0, 1.5), Walker("w1", ("e", "b"), 1.0, 1.0, 1.5),
            Walker("w2", ("c",), 1.0, 1.0, 1.5)]


def trace(start_s: float, length_s: float) -> WalkTrace:
    times = np.arange(start_s, start_s + length_s, 0.1)
    return WalkTrace(times, np.zeros((len(times), 2)), ("x_0",) * len(times))


def stand_in(held_s: dict[str, float], calls: list[list[Walker]]):
    """A walk that lasts 5 s, and ``held_s`` more for the walkers named there, until they have
    been walked ``len(calls)`` times (then they walk in 5 s)."""
    def walk(_net: Path, placed, _step: float, _prefix: str, **_options) -> dict:
        calls.append(list(placed))
        extra = held_s if len(calls) == 1 else {}
        return {w.id: trace(w.depart_s, 5.0 + extra.get(w.id, 0.0)) for w in placed}
    return walk


def test_walkers_that_met_walk_again_alone_in_longer_slots(monkeypatch) -> None:
    calls: list[list[Walker]] = []
    monkeypatch.setattr(walker_jitter, "walk_alone_kept_on_error",
                        stand_in({"w0": 30.0}, calls))
    traces = walker_jitter._walk_apart(Path("net.net.xml"), walkers(), 0.1, 10.0, None)
    first, again = calls
    assert [w.depart_s for w in first] == [0.0, 10.0, 0.0]  # w1 after w0: they share e
    assert [w.id for w in again] == ["w0", "w1"] and [w.depart_s for w in again] == [0.0, 20.0]
    assert traces["w0"].times_s[-1] < 5.0  # the second, unhindered walk
    assert traces["w2"].times_s[0] == 0.0 and set(traces) == {"w0", "w1", "w2"}


def test_walkers_that_keep_meeting_stop_the_measurement_in_one_line(monkeypatch) -> None:
    calls: list[list[Walker]] = []

    def always_held(_net: Path, placed, _step: float, _prefix: str, **_options) -> dict:
        calls.append(list(placed))
        return {w.id: trace(w.depart_s, 1000.0) for w in placed}

    monkeypatch.setattr(walker_jitter, "walk_alone_kept_on_error", always_held)
    with pytest.raises(SimulationError) as info:
        walker_jitter._walk_apart(Path("net.net.xml"), walkers(), 0.1, 10.0, None)
    assert len(calls) == walker_jitter.MEET_RETRIES + 1
    assert "\n" not in str(info.value) and "walkers w0, w1 of the jitter measurement" in \
        str(info.value)

"""A standoff on the real town, in SUMO: the bus stands with its rear on a crossing, and the
walker bound for that crossing waits at its kerb, which SUMO keeps it off while a vehicle
occupies it (eclipse-sumo/sumo#3138); the bus waits for the walker.

The falsifier's second search of the town (CMA-ES's evaluation 27) found it: the bus stands
from 16.8 s inside the junction's overlapping walking areas, the walker stops at the kerb at
29.5 s, and neither moves until SUMO declares the walker jammed at 39.6 s (results/falsify.md).
It is known and not resolved (docs/controller.md, Liveness). This test holds the measure that
sees it, the ``crossing_blocked`` margin and the falsifier's ``blocking`` objective; once the
controller keeps crossings clear, it becomes that fix's regression test.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from sse_cosim.falsify.objectives import OBJECTIVES
from sse_cosim.reporting.recorder import collisions
from sse_cosim.runner.run import run_scenario_file

pytestmark = pytest.mark.sumo

CASE = Path(__file__).with_name("town_standoff.toml")


def test_the_blocking_measure_sees_the_bus_hold_up_the_walker(tmp_path: Path):
    summary = run_scenario_file(CASE, tmp_path, plots=False, summary_only=True,
                                margins=("crossing_blocked",))
    blocked = summary["margins"]["crossing_blocked"]
    assert blocked["vehicle"] == "bus" and blocked["pedestrians"] == ["pedestrian"]
    assert blocked["crossings"] == [":cluster_4161983183_8989139953_c0"]
    assert blocked["t"] == pytest.approx(29.5, abs=0.25)  # the walker stops at the kerb
    assert blocked["longest_s"] == pytest.approx(34.0 - blocked["t"], abs=0.15)  # to the end
    blocking = OBJECTIVES["blocking"]
    assert blocking.failed(summary)
    assert blocking.failed_at(summary) == pytest.approx(blocked["t"] + 3.0)
    assert collisions(summary) == 0  # the walker brushes the standing bus at 28.7 s: a walk-in

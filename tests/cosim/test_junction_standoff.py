"""A standoff on the junction, in SUMO: bus_sn stands inside the junction with its rear over
the south zebra ``:J_c2``, and SUMO holds the walkers that stepped onto that zebra on its lane,
short of the bus (eclipse-sumo/sumo#3138); the bus waits for the pedestrians in view.

The falsifier's search of the junction on the fix (CMA-ES's evaluation 349) found it: the bus
stands from 19.5 s, e1 steps onto the zebra at 23.7 s and stops beside it, s2 from 30.5 s, until
SUMO declares them jammed (33.9 s, 40.2 s) and walks them through the standing bus: 2 walk-ins
(results/falsify.md). The ``crossing_blocked`` margin first counted walkers at the kerb only
(on a walking area with the crossing next) and gave 0 s here. It is known and not resolved
(docs/controller.md, Liveness); once the controller keeps crossings clear, this becomes that
fix's regression test.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from sse_cosim.falsify.objectives import OBJECTIVES
from sse_cosim.reporting.recorder import collisions
from sse_cosim.runner.run import run_scenario_file

pytestmark = pytest.mark.sumo

CASE = Path(__file__).with_name("junction_standoff.toml")


def test_the_blocking_measure_sees_walkers_held_on_the_zebra_the_bus_stands_on(tmp_path: Path):
    summary = run_scenario_file(CASE, tmp_path, plots=False, summary_only=True,
                                margins=("crossing_blocked",))
    blocked = summary["margins"]["crossing_blocked"]
    assert blocked["vehicle"] == "bus_sn" and blocked["crossings"] == [":J_c2"]
    assert blocked["pedestrians"] == ["e1", "s2"]
    assert 23.7 < blocked["t"] < 25.0  # e1 stops on the zebra beside the bus's rear
    assert blocked["longest_s"] == pytest.approx(33.5 - blocked["t"], abs=0.15)  # to the end
    assert OBJECTIVES["blocking"].failed(summary)
    assert collisions(summary) == 0  # SUMO walks them through the bus only after 33.9 s

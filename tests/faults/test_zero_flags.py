"""Without faults nothing is ever flagged: sources that keep their bounds always share a point.

Synthetic trajectories (no SUMO) with full-size jitter, noise uniform or on the bound, random
sensor poses, latencies of 1-3 steps and clear views that miss the pedestrian by as little as
a millimetre. The real-SUMO side is in test_fault_scenarios.py (a fault within the bounds and
frame dropouts raise no flag either).
"""

from __future__ import annotations

import numpy as np
import pytest
from synthetic import PED, Harness, SensorSetup, contains

SEEDS = range(8)
STEPS = 60


def random_sensors(rng: np.random.Generator) -> dict[str, SensorSetup]:
    """The bus with one sensor, a unit with two (paper Fig. 4's case), a unit with one."""
    return {
        "bus_front": SensorSetup("bus", rng.uniform(0, 2 * np.pi), 0.5),
        "rsu1_a": SensorSetup("rsu1", rng.uniform(0, 2 * np.pi), 1.0),
        "rsu1_b": SensorSetup("rsu1", rng.uniform(0, 2 * np.pi), 0.8),
        "rsu2_a": SensorSetup("rsu2", rng.uniform(0, 2 * np.pi), 1.0),
    }


@pytest.mark.parametrize("worst_case", [False, True])
def test_no_fault_no_flag_and_every_set_holds_the_truth(worst_case):
    for seed in SEEDS:
        rng = np.random.default_rng(100 + seed)
        harness = Harness(random_sensors(rng), seed=seed, worst_case=worst_case,
                          latency=1 + seed % 3)
        for record in harness.run(STEPS):
            flags = record.flags
            assert not any(flags.sensors.values()), (seed, record.step, flags)
            assert not any(flags.nodes.values()), (seed, record.step, flags)
            assert not flags.inconsistent, (seed, record.step)
            assert contains(harness.model, record.fused[PED], record.truth), (seed, record.step)

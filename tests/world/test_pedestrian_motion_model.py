"""SUMO's pedestrians obey the estimator's motion model: a speed-bounded path plus jitter.

The estimator assumes p_k = s_k + e_k with ||s_{k+1} - s_k|| <= v_max dt and ||e_k|| <= eps
(``estimation/motion/``). SUMO's striping model jumps at lane transitions, so v_max alone
would not hold; this test asks, as a convex feasibility problem, whether such a path s exists
for SUMO's actual trajectories with the scenarios' bounds.
"""

from __future__ import annotations

from pathlib import Path

import cvxpy as cp
import numpy as np
import pytest

from sse_cosim.scenario.loader import load_scenario
from sse_cosim.world.sumo import SumoWorld

pytestmark = pytest.mark.sumo
SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"


@pytest.fixture(scope="module")
def trajectories(tmp_path_factory) -> dict[str, tuple[np.ndarray, float, float]]:
    """The pedestrian's positions (k, 2) in every scenario with one, and in S3 with a pedestrian
    that waits 6 s at its start before it walks, with the step length and the jitter the run
    took (measured for the network)."""
    result = {}
    runs = {name: (name, {}) for name in ("s1_pedestrian", "s2_pedestrian", "s3_pedestrian")}
    runs["s3_waiting"] = ("s3_pedestrian", {"pedestrians.pedestrian.steps_onto_crossing_s": 20.0})
    for name, (file, overrides) in runs.items():
        scenario = load_scenario(SCENARIOS / f"{file}.toml",
                                 {"simulation.duration_s": 30.0, **overrides})
        steps = round(scenario.simulation.duration_s / scenario.simulation.step_length_s)
        positions = []
        with SumoWorld(scenario, tmp_path_factory.mktemp(name), name) as world:
            jitter = world.scenario.estimator.position_jitter_m
            for _ in range(steps):
                persons = world.step().persons
                if persons:
                    positions.append(next(iter(persons.values())).position)
        result[name] = (np.array(positions), scenario.simulation.step_length_s, jitter)
    return result


def path_exists(positions: np.ndarray, speed: float, step: float, jitter: float) -> bool:
    path = cp.Variable(positions.shape)
    constraints = [
        cp.norm(path - positions, axis=1) <= jitter,
        cp.norm(path[1:] - path[:-1], axis=1) <= speed * step,
    ]
    problem = cp.Problem(cp.Minimize(0), constraints)
    problem.solve(solver=cp.CLARABEL)
    return problem.status == cp.OPTIMAL


def test_sumo_pedestrians_admit_a_speed_bounded_path_within_the_jitter(trajectories):
    estimator = load_scenario(SCENARIOS / "s1_pedestrian.toml").estimator
    for name, (positions, step, jitter) in trajectories.items():
        assert len(positions) > 100, name
        assert path_exists(positions, estimator.max_pedestrian_speed_mps, step,
                           jitter), name


def test_without_the_jitter_sumo_breaks_the_speed_bound(trajectories):
    """The jumps are real: a much smaller jitter has no admissible path."""
    positions, step, _ = trajectories["s1_pedestrian"]
    assert not path_exists(positions, 2.5, step, 0.05)

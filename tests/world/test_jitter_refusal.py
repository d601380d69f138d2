"""The world's choice of the position jitter against what SUMO's lone walkers were measured to
need (``SumoWorld._with_jitter``, no SUMO run): a refusal's advice is a setting the next run
accepts. A network whose walkers need more than a measured jitter may be (2 m) is refused with
the value to set; set to it, or above, the scenario runs with its own jitter (issue: live on
real streets, where the advice "at least that" was refused again)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from sse_cosim.errors import UserError
from sse_cosim.scenario.loader import load_scenario
from sse_cosim.world.sumo import SumoWorld
from sse_cosim.world.walker_jitter import NetworkJitter

S3 = Path(__file__).resolve().parents[2] / "scenarios" / "s3_pedestrian.toml"


def measured(jitter_m: float) -> NetworkJitter:
    return NetworkJitter(jitter_m, None, 1, 2.5, 0.1, {})


def world(overrides: dict) -> SumoWorld:
    return SumoWorld(load_scenario(S3, overrides), "unused", "s3")


def test_a_large_measured_jitter_is_refused_with_a_value_the_next_run_takes() -> None:
    with pytest.raises(UserError) as refused:
        world({})._with_jitter(measured(3.43))
    advice = re.search(r"set estimator.position_jitter_m = ([0-9.]+)", str(refused.value))
    assert advice is not None
    taken = world({"estimator.position_jitter_m": float(advice.group(1))})
    assert taken._with_jitter(measured(3.43)).estimator.position_jitter_m == 3.43


def test_a_jitter_below_the_measured_one_is_refused_and_one_above_it_kept() -> None:
    with pytest.raises(UserError, match=r"is below the 0\.700 m"):
        world({"estimator.position_jitter_m": 0.5})._with_jitter(measured(0.7))
    kept = world({"estimator.position_jitter_m": 0.9})._with_jitter(measured(0.7))
    assert kept.estimator.position_jitter_m == 0.9
    assert world({})._with_jitter(measured(0.7)).estimator.position_jitter_m == 0.7

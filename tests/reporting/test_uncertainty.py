"""The statistics of a sweep's seeds (reporting/uncertainty.py): intervals of the mean,
differences between levels, and the seeds a difference needs, checked against closed forms
and by drawing samples."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from sse_cosim.reporting.uncertainty import (
    detectable,
    differences,
    intervals,
    pooled_std,
    seeds_needed,
)


def table(values: dict[str, list[float]]) -> pd.DataFrame:
    """One scenario, one parameter ``p`` with the given runs per level."""
    return pd.DataFrame([{"scenario": "s", "p": level, "x": v}
                         for level, runs in values.items() for v in runs])


def test_the_interval_is_students_for_the_mean():
    groups = intervals(table({"a": [1.0, 2.0, 3.0]}), ["scenario", "p"], "x")
    row = groups.iloc[0]
    assert (row["n"], row["mean"], row["std"]) == (3, 2.0, 1.0)
    assert row["high"] - row["mean"] == pytest.approx(4.302653 / math.sqrt(3.0), rel=1e-6)
    single = intervals(table({"a": [1.0]}), ["scenario", "p"], "x").iloc[0]
    assert math.isnan(single["low"])


def steps(values: dict[str, list[float]]) -> list:
    groups = intervals(table(values), ["scenario", "p"], "x")
    return differences(groups, "p", list(values), [], "x", {k: k for k in values})


def test_a_difference_beyond_the_seeds_spread_exceeds_it_and_one_within_does_not():
    clear, unclear = steps({"a": [1.0, 1.1, 0.9], "b": [5.0, 5.1, 4.9], "c": [5.05, 4.8, 5.2]})
    assert clear.exceeds and clear.difference == pytest.approx(4.0)
    assert not unclear.exceeds
    assert "from p = b to c" in unclear.line("x") and "within the seeds' spread" in \
        unclear.line("x")


def test_seeds_that_agree_exactly_make_any_difference_the_parameters():
    moved, same = steps({"a": [2.0, 2.0], "b": [3.0, 3.0], "c": [3.0, 3.0]})
    assert moved.exceeds and not same.exceeds
    assert pooled_std(intervals(table({"a": [2.0, 2.0]}), ["scenario", "p"], "x")) == 0.0
    assert seeds_needed(0.0, 0.1) == 2


def test_seeds_needed_and_detectable_are_inverse():
    for sigma, delta in [(1.0, 1.0), (0.3, 0.05), (2.0, 3.0)]:
        n = seeds_needed(sigma, delta)
        assert n is not None and detectable(sigma, n) <= delta < detectable(sigma, n - 1) \
            if n > 2 else detectable(sigma, n) <= delta
    assert seeds_needed(1.0, 1.0) == 17  # 2 (t + t)^2 with t at 2n - 2 degrees of freedom
    assert seeds_needed(math.nan, 1.0) is None


def test_with_the_seeds_needed_a_real_difference_is_found_about_as_often_as_promised():
    """Drawn: normal seeds spread by 1 at two levels 1 apart, 17 seeds each; Welch's interval
    leaves out zero in about 80 % of sweeps (the power the count is made for)."""
    rng = np.random.default_rng(7)
    n, trials = seeds_needed(1.0, 1.0), 600
    found = sum(steps({"a": list(rng.normal(0.0, 1.0, n)),
                       "b": list(rng.normal(1.0, 1.0, n))})[0].exceeds for _ in range(trials))
    assert 0.74 <= found / trials <= 0.87
    false = sum(steps({"a": list(rng.normal(0.0, 1.0, n)),
                       "b": list(rng.normal(0.0, 1.0, n))})[0].exceeds for _ in range(trials))
    assert false / trials <= 0.085  # about 5 % where there is no difference

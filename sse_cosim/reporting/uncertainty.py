"""What a sweep's seeds leave uncertain: intervals of the mean, differences between levels, and
how many seeds a difference needs. Pure statistics on the sweep's table (no SUMO, no files).

Runs of one scenario at one combination of parameter values differ only by their seed, so
their figures are a sample of what the seeds do. For each such group of n runs with mean m
and standard deviation s, the **interval** is Student's 95 % confidence interval of the mean,
m ± t(0.975, n - 1) s / sqrt(n) (none for n < 2; zero width where every seed agrees).

Between two **neighbouring levels** of one parameter (the others held, within one scenario),
the difference of the means has Welch's 95 % interval, d ± t(0.975, nu) sqrt(s1²/n1 + s2²/n2)
with the Welch–Satterthwaite degrees of freedom nu. A difference **exceeds the seeds' spread**
where that interval leaves out zero; where both levels' seeds agree exactly (no spread), a
difference exceeds it when it is not zero.

**Seeds for a stated difference** delta: per level, the least n with
n >= 2 (t(0.975, 2n - 2) + t(0.8, 2n - 2))² sigma² / delta² (a two-sided test at 5 % with 80 %
power), sigma the seeds' standard deviation pooled over the sweep's groups.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import stats

CONFIDENCE = 0.95
POWER = 0.8
MAX_SEEDS = 10_000  # seeds_needed gives up beyond this


def intervals(table: pd.DataFrame, keys: Sequence[str], figure: str) -> pd.DataFrame:
    """Per group of ``keys`` (scenario and parameter columns): ``n``, ``mean``, ``std`` and
    the interval's ``low`` and ``high`` of ``figure`` over the group's finished runs (rows
    with the figure missing are left out; NaN bounds for n < 2)."""
    frame = table[[*keys, figure]].dropna(subset=[figure])
    grouped = frame.groupby(list(keys), sort=False, dropna=False)[figure]
    out = grouped.agg(n="size", mean="mean", std="std").reset_index()
    half = np.where(out["n"] >= 2, stats.t.ppf(0.5 + CONFIDENCE / 2, np.maximum(out["n"] - 1, 1))
                    * out["std"].fillna(0.0) / np.sqrt(out["n"]), np.nan)
    return out.assign(low=out["mean"] - half, high=out["mean"] + half)


@dataclass(frozen=True)
class Difference:
    """The difference of ``figure``'s mean from level ``before`` to level ``after`` of one
    parameter in one scenario (the other parameters at ``held``), its interval, and whether it
    exceeds the seeds' spread."""

    scenario: str
    figure: str
    parameter: str
    before: str
    after: str
    held: str
    difference: float
    low: float
    high: float

    @property
    def exceeds(self) -> bool:
        if math.isnan(self.low):
            return False
        return self.low > 0.0 or self.high < 0.0

    def line(self, label: str) -> str:
        """One line of the report, ``label`` naming the figure in words."""
        where = f" ({self.held})" if self.held else ""
        verdict = "exceeds the seeds' spread" if self.exceeds else "within the seeds' spread"
        interval = "no interval: fewer than 2 seeds" if math.isnan(self.low) else (
            f"95 % interval {self.low:+.3g} to {self.high:+.3g}")
        return (f"{self.scenario}{where}: {label} from {self.parameter} = {self.before} to "
                f"{self.after}: {self.difference:+.3g} ({interval}): {verdict}")


def differences(groups: pd.DataFrame, parameter: str, order: Sequence[object],
                others: Sequence[str], figure: str, labels: dict[object, str]
                ) -> list[Difference]:
    """Each scenario's differences between neighbouring levels of ``parameter`` (in
    ``order``), the ``others`` parameters held, from :func:`intervals`'s ``groups``;
    ``labels``: how each level is named."""
    found = []
    for (scenario, *held), rows in groups.groupby(["scenario", *others], sort=False,
                                                  dropna=False):
        by_level = {row[parameter]: row for _, row in rows.iterrows()}
        present = [level for level in order if level in by_level]
        held_text = ", ".join(f"{name} = {value}" for name, value in zip(others, held,
                                                                          strict=True))
        for a, b in itertools.pairwise(present):
            found.append(_difference(str(scenario), figure, parameter, labels[a], labels[b],
                                     held_text, by_level[a], by_level[b]))
    return found


def _difference(scenario: str, figure: str, parameter: str, before: str, after: str,
                held: str, a: pd.Series, b: pd.Series) -> Difference:
    """Welch's interval of ``b``'s mean less ``a``'s (module docstring)."""
    diff = float(b["mean"] - a["mean"])
    if a["n"] < 2 or b["n"] < 2:
        return Difference(scenario, figure, parameter, before, after, held, diff, math.nan,
                          math.nan)
    va, vb = float(a["std"]) ** 2 / a["n"], float(b["std"]) ** 2 / b["n"]
    if va + vb == 0.0:  # every seed agrees at both levels: the difference is exact
        return Difference(scenario, figure, parameter, before, after, held, diff, diff, diff)
    dof = (va + vb) ** 2 / (va * va / (a["n"] - 1) + vb * vb / (b["n"] - 1))
    half = float(stats.t.ppf(0.5 + CONFIDENCE / 2, dof)) * math.sqrt(va + vb)
    return Difference(scenario, figure, parameter, before, after, held, diff, diff - half,
                      diff + half)


def pooled_std(groups: pd.DataFrame) -> float:
    """The seeds' standard deviation pooled over :func:`intervals`'s ``groups`` of at least
    2 runs; NaN without any."""
    usable = groups[groups["n"] >= 2]
    if usable.empty:
        return math.nan
    dof = float((usable["n"] - 1).sum())
    return math.sqrt(float(((usable["n"] - 1) * usable["std"] ** 2).sum()) / dof)


def seeds_needed(sigma: float, difference: float) -> int | None:
    """Seeds per level to tell a ``difference`` apart at :data:`CONFIDENCE` with
    :data:`POWER` when the seeds spread by ``sigma`` (module docstring); 2 where they do not
    spread at all, None beyond :data:`MAX_SEEDS` or without a spread measured."""
    if math.isnan(sigma) or difference <= 0.0:
        return None
    if sigma == 0.0:
        return 2
    for n in range(2, MAX_SEEDS + 1):
        dof = 2 * n - 2
        quantiles = stats.t.ppf(0.5 + CONFIDENCE / 2, dof) + stats.t.ppf(POWER, dof)
        if n >= 2.0 * quantiles ** 2 * sigma ** 2 / difference ** 2:
            return n
    return None


def detectable(sigma: float, seeds: int) -> float:
    """The least difference ``seeds`` seeds per level tell apart (the inverse of
    :func:`seeds_needed`); NaN without a spread measured or with fewer than 2 seeds."""
    if math.isnan(sigma) or seeds < 2:
        return math.nan
    dof = 2 * seeds - 2
    quantiles = stats.t.ppf(0.5 + CONFIDENCE / 2, dof) + stats.t.ppf(POWER, dof)
    return float(quantiles * sigma * math.sqrt(2.0 / seeds))

"""The sweep's short table (terminal, report): a combination whose runs all failed shows no
count, never "0 collisions, 0 violations" (issue: reports that answer the user's question)."""

from __future__ import annotations

import math

import pandas as pd

from sse_cosim.reporting.sweep_report import summary_table


def test_a_failed_run_counts_nothing() -> None:
    table = pd.DataFrame({
        "key": ["a", "b", "c"], "scenario": ["S1", "S1", "S2"],
        "status": ["ok", "ok", "failed"],
        "collisions": [0, 1, float("nan")], "containment_violations": [2, 0, float("nan")],
        "average_speed_mps": [8.0, 9.0, float("nan")],
    })
    rows = summary_table(table, []).set_index("scenario")
    assert rows.loc["S1", "collisions"] == 1 and rows.loc["S1", "containment_violations"] == 2
    assert rows.loc["S2", "failed"] == 1
    assert math.isnan(rows.loc["S2", "collisions"])
    assert math.isnan(rows.loc["S2", "containment_violations"])

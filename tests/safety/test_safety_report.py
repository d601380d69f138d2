"""The safety report from fake run folders: targets met, missed, not shown; failed runs; files
that do not depend on the machine (no SUMO)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pandas as pd
import pytest
from safety_helpers import campaign_file, slow_walkers_cannot

from sse_cosim.files import write_json_atomic
from sse_cosim.reporting.outputs import ERROR, RUNS_FOLDER, SUMMARY
from sse_cosim.reporting.safety_report import (
    SAFETY_TABLE,
    heat_map_name,
    report_path,
    write_safety_report,
)
from sse_cosim.runner.safety import SAFETY_PLAN, load_campaign, plan_campaign, plan_document
from sse_cosim.runner.sweep import PlannedRun

SAFE = {
    "collisions": 0, "containment_violations": 0, "containment_violations_by_set": {},
    "route_completed": True, "longest_needless_hold_s": 1.0,
    "min_distance_bus_pedestrian_m": 5.0, "average_speed_mps": 12.0, "time_stopped_s": 1.0,
    "pedestrians": {"pedestrian": {"min_distance_m": 5.0}, "other": {"min_distance_m": 6.0}},
}

Summaries = Callable[[int, PlannedRun], dict[str, Any] | None]


def campaign_folder(tmp_path: Path, summaries: Summaries) -> Path:
    """A finished campaign of S1 and S2 (48 runs, 48 not feasible) whose run ``i`` has the
    summary ``summaries(i, run)`` (``None``: the run failed)."""
    campaign = load_campaign(campaign_file(tmp_path))
    plan = plan_campaign(campaign, slow_walkers_cannot)
    out = tmp_path / "safety"
    write_json_atomic(out / SAFETY_PLAN, plan_document(campaign, plan, "sse-cosim safety"))
    for i, run in enumerate(plan.runs):
        summary = summaries(i, run)
        folder = out / RUNS_FOLDER / run.key
        if summary is None:
            write_json_atomic(folder / ERROR, {"key": run.key, "error": "worker died"})
        else:
            write_json_atomic(folder / SUMMARY, {"source": "/somewhere/s.toml", **summary})
    return out


def keys_of(out: Path) -> list[str]:
    table = pd.read_csv(out / SAFETY_TABLE)
    return list(table.loc[table["status"] == "ok", "key"])


def test_targets_met_and_every_file_written(tmp_path):
    out = campaign_folder(tmp_path, lambda i, run: {**SAFE, "average_speed_mps": 10.0 + i})
    report = write_safety_report(out)
    assert [t.verdict for t in report.targets] == ["met"] * 4
    assert (report.runs, report.not_feasible, report.failed) == (48, 48, ())
    table = pd.read_csv(out / SAFETY_TABLE)
    assert len(table) == 96
    assert table["status"].value_counts().to_dict() == {"ok": 48, "not feasible": 48}
    for scenario in ("s1_pedestrian", "s2_pedestrian"):
        for key in ("average_speed_mps", "min_distance_bus_pedestrian_m"):
            assert (out / heat_map_name(scenario, key)).is_file()
    text = report.markdown.read_text(encoding="utf-8")
    assert report.markdown == report_path(out) == tmp_path / "safety.md"
    assert "Made by `sse-cosim safety`" in text
    assert "Combinations: 96; not feasible, not run: 48; runs: 48 (48 finished" in text
    assert "| walk_mps=1 | too slow (1 m/s) | 48 | s1_pedestrian, s2_pedestrian |" in text
    assert "![safety_s2_pedestrian_min_distance.png](safety/" in text
    assert str(out) not in text and "/somewhere" not in text  # the campaign file is as given
    first = keys_of(out)[0]
    assert f"| average speed (m/s) | 10.00 | `{first}` |" in text


def test_a_rerun_writes_the_same_bytes(tmp_path):
    out = campaign_folder(tmp_path, lambda i, run: SAFE)
    write_safety_report(out)
    files = sorted(p for p in tmp_path.rglob("*") if p.is_file() and p.suffix in {
        ".md", ".csv", ".png"})
    before = {p: p.read_bytes() for p in files}
    write_safety_report(out)
    assert {p: p.read_bytes() for p in files} == before


def test_missed_targets_name_the_runs_that_break_them(tmp_path):
    broken = {
        3: {"collisions": 2},
        5: {"collisions": 1, "containment_violations": 4,
            "containment_violations_by_set": {"fused": 3, "region": 1}},
        7: {"route_completed": False, "longest_needless_hold_s": 4.5},
    }
    out = campaign_folder(tmp_path, lambda i, run: {**SAFE, **broken.get(i, {})})
    report = write_safety_report(out)
    keys = keys_of(out)
    targets = {t.label.split(" ")[0]: t for t in report.targets}
    assert all(t.met is False for t in report.targets)
    assert targets["collisions"].offenders == ((keys[3], "2"), (keys[5], "1"))
    assert targets["collisions"].measured == "3 in 2 of 48 runs"
    assert targets["containment"].offenders == ((keys[5], "4"),)
    assert targets["runs"].offenders == ((keys[7], "false"),)
    assert targets["longest"].offenders == ((keys[7], "4.50"),)
    assert targets["collisions"].breaking_lines() == [
        f"MISSED collisions (events) = 0: {keys[3]} (2), {keys[5]} (1)"]
    text = report.markdown.read_text(encoding="utf-8")
    assert "Containment violations per set: `fused` 3, `region` 1." in text
    assert f"| collisions | 2 | `{keys[3]}` |" in text
    assert text.count("| MISSED |") == 4


def test_a_missing_key_is_reported_never_filled_in(tmp_path):
    def summaries(i: int, run: PlannedRun) -> dict[str, Any]:
        summary = dict(SAFE)
        if i in (2, 4):
            del summary["route_completed"]
        return summary

    out = campaign_folder(tmp_path, summaries)
    report = write_safety_report(out)
    keys = keys_of(out)
    route = report.targets[2]
    assert route.verdict == "not shown" and route.missing == (keys[2], keys[4])
    assert route.measured == "0 of 46 runs"
    assert route.breaking_lines() == [
        f"NOT SHOWN runs that never finish the route = 0: 2 summaries lack the key: "
        f"{keys[2]}, {keys[4]}"]
    table = pd.read_csv(out / SAFETY_TABLE)
    assert list(table.loc[table["key"] == keys[2], "missing_keys"]) == ["route_completed"]
    assert table.loc[table["key"] == keys[2], "route_completed"].isna().all()
    text = report.markdown.read_text(encoding="utf-8")
    assert "| 0 (2 missing) |" in text  # route not finished, overall


@pytest.mark.parametrize(("others", "verdict"), [
    (SAFE, "met"), ({}, "not shown"), (None, "not shown")])
def test_failed_runs_are_listed_and_keep_the_others(tmp_path, others, verdict):
    out = campaign_folder(tmp_path, lambda i, run: None if i == 0 else others)
    report = write_safety_report(out)
    failed = pd.read_csv(out / SAFETY_TABLE).query("status == 'failed'")["key"]
    assert [key for key, _ in report.failed] == list(failed)
    assert len(report.failed) == (48 if others is None else 1)
    assert report.failed[0][1] == "worker died"
    assert {t.verdict for t in report.targets} == {verdict}
    assert "worker died" in report.markdown.read_text(encoding="utf-8")


def test_the_campaign_pedestrians_own_distance_is_reported_beside_anyones(tmp_path):
    """Where another pedestrian walks nearer the bus (the junction, the crowd), the least
    distance of all is theirs; the hard case's margin is the campaign pedestrian's own."""
    def summaries(i: int, run: PlannedRun) -> dict[str, Any]:
        own = {"min_distance_m": 4.0 + i}
        return {**SAFE, "min_distance_bus_pedestrian_m": 1.5,
                "pedestrians": {"pedestrian": own, "other": {"min_distance_m": 1.5}}}

    out = campaign_folder(tmp_path, summaries)
    text = write_safety_report(out).markdown.read_text(encoding="utf-8")
    table = pd.read_csv(out / SAFETY_TABLE)
    done = table[table["status"] == "ok"]
    assert list(done["min_distance_campaign_pedestrian_m"]) == [4.0 + i for i in range(48)]
    assert set(done["min_distance_bus_pedestrian_m"]) == {1.5}
    assert "min distance to the campaign's pedestrian, min (m)" in text
    assert f"| min distance to the campaign's pedestrian (m) | 4.00 | `{keys_of(out)[0]}` |" \
        in text

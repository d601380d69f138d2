"""Which finished runs the report treats as single runs (Table I, Fig. 7, run list)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from sse_cosim.reporting.html import single_runs


def finished_run(folder: Path) -> Path:
    folder.mkdir(parents=True)
    (folder / "summary.json").write_text(json.dumps({"scenario": "S1", "pedestrian": True}))
    (folder / "scenario.json").write_text(json.dumps({"name": "S1"}))
    return folder


@pytest.mark.parametrize("plan", ["safety.json.gz", "safety.json"])
def test_runs_of_a_safety_campaign_are_not_single_runs(tmp_path, plan):
    """Whether the campaign is this version's or an older one's, whose plan was plain."""
    plain = finished_run(tmp_path / "runs" / "s1_pedestrian")
    campaign = tmp_path / "safety"
    finished_run(campaign / "runs" / "s1_pedestrian__step_s=9__seed1__abc")
    (campaign / plan).write_text("{}")
    assert [run.path for run in single_runs([tmp_path], [])] == [plain]


def test_runs_and_worst_cases_of_a_falsify_search_are_not_single_runs(tmp_path):
    """A search's runs inject faults (its sensor errors, its losses): counted as single runs
    they would fill the fault table and the run list of every report over results/."""
    plain = finished_run(tmp_path / "runs" / "s1_pedestrian")
    search = tmp_path / "falsify" / "s1_pedestrian"
    finished_run(search / "runs" / "cma-0001__seed1__abc")
    finished_run(search / "worst_cma")
    (search / "falsify.json").write_text("{}")
    assert [run.path for run in single_runs([tmp_path], [])] == [plain]

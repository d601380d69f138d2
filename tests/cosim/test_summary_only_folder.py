"""A summaries-only run (large sweeps, campaigns) keeps ``scenario.json`` and ``summary.json``
alone: SUMO's inputs and log go once the run has finished. A run that fails keeps them, so
the log its error names is there to read."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from sse_cosim.errors import UserError
from sse_cosim.runner.run import run_scenario_file

pytestmark = pytest.mark.sumo
SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "s3_no_pedestrian.toml"


def test_a_finished_run_keeps_its_scenario_and_summary_alone(tmp_path: Path) -> None:
    run_scenario_file(SCENARIO, tmp_path, {"simulation.duration_s": 2.0}, plots=False,
                      summary_only=True)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scenario.json", "summary.json"]


def test_a_failed_run_keeps_the_log_its_error_names(tmp_path: Path) -> None:
    with pytest.raises(UserError, match=r"sumo\.log") as failed:
        run_scenario_file(SCENARIO, tmp_path, {"automated.bus.depart_pos_m": 160.0},
                          plots=False, summary_only=True)
    (log,) = re.findall(r"see (\S+sumo\.log)", str(failed.value))
    assert Path(log).is_file()

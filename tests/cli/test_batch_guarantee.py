"""The batch's last lines: runs that broke the guarantee, declared or not."""

from __future__ import annotations

from pathlib import Path

import pytest

from sse_cosim.cli.commands import _check_guarantee
from sse_cosim.cli.main import EXIT_TARGET_MISSED, TargetsMissed
from sse_cosim.reporting.paper import RunFolder


def run(name: str, collisions: int, violations: int, breaks: list[str]) -> RunFolder:
    summary = {"collisions": collisions, "containment_violations": violations}
    return RunFolder(Path("runs") / name, summary, {"breaks_assumptions": breaks})


def test_declared_breaks_are_named_and_pass(capsys):
    _check_guarantee([run("s1_pedestrian", 0, 0, []),
                      run("s3_stuck_rsu1", 0, 190, ["sensor_bounds"])])
    out = capsys.readouterr().out
    assert "s3_stuck_rsu1: 0 collision(s), 190 containment violation(s) -- expected: the " \
           "study breaks sensor_bounds" in out
    assert "s1_pedestrian" not in out


def test_an_undeclared_break_names_the_run_and_fails_with_status_4(capsys):
    with pytest.raises(TargetsMissed, match="s2_pedestrian") as error:
        _check_guarantee([run("s2_pedestrian", 1, 0, []), run("s3_pedestrian", 0, 0, [])])
    assert error.value.exit_code == EXIT_TARGET_MISSED
    assert "UNEXPECTED" in capsys.readouterr().out

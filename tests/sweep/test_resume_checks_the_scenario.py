"""``--resume`` keeps a finished run only if it ran the scenario its task resolves to today.

A run key names a scenario file, its overrides and its seed, not the file's content, so a
finished run of a file edited since (or of an older schema) has the key of the run it would
be now. No SUMO here: the run folder's ``scenario.json`` is written as a run writes it.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from sse_cosim.reporting.outputs import SCENARIO, SUMMARY, portable_scenario
from sse_cosim.runner.executors import Execution, execute
from sse_cosim.runner.tasks import RunTask, ran_as_planned
from sse_cosim.scenario.loader import load_scenario

ROOT = Path(__file__).resolve().parents[2]
S2 = ROOT / "scenarios" / "s2_pedestrian.toml"
OVERRIDES = {"simulation.duration_s": 3.0, "simulation.seed": 2}


def _finished(folder: Path, overrides: dict, edit=None) -> RunTask:
    """A run folder as a finished run of S2 with ``overrides`` leaves it (``edit`` changes its
    recorded scenario); the task of that run."""
    folder.mkdir(parents=True)
    record = {"source": "scenarios/s2_pedestrian.toml",
              **portable_scenario(load_scenario(S2, overrides), folder)}
    if edit is not None:
        edit(record)
    (folder / SCENARIO).write_text(json.dumps(record), encoding="utf-8")
    (folder / SUMMARY).write_text(json.dumps({"collisions": 0}), encoding="utf-8")
    return RunTask(key=folder.name, scenario=str(S2), out_dir=str(folder),
                   overrides=OVERRIDES, summary_only=True)


def test_a_run_of_the_same_scenario_is_kept_wherever_it_was_read_from(tmp_path):
    def as_run(record: dict) -> None:  # read elsewhere; the jitter the run measured
        record.update(source="elsewhere")
        record["estimator"]["position_jitter_m"] = 0.646

    assert ran_as_planned(_finished(tmp_path / "r", OVERRIDES, edit=as_run))


@pytest.mark.parametrize("edit", [
    lambda r: r["simulation"].update(duration_s=40.0),  # the file said otherwise then
    lambda r: r["estimator"].pop("junction_ground_margin_m"),  # written before the field
    lambda r: r["estimator"].update(extra_field=1.0),  # written after one was dropped
    lambda r: r["sensors"].popitem(),  # a sensor less
])
def test_a_run_of_another_scenario_is_not_kept(tmp_path, edit):
    assert not ran_as_planned(_finished(tmp_path / "r", OVERRIDES, edit=edit))


def test_a_run_without_its_scenario_record_is_not_kept(tmp_path):
    task = _finished(tmp_path / "r", OVERRIDES)
    (tmp_path / "r" / SCENARIO).unlink()
    assert not ran_as_planned(task)


def test_resume_makes_a_stale_run_again_and_says_so(tmp_path, capsys, monkeypatch):
    """execute() keeps the matching run, hands the stale one to the executor, one line."""
    kept = _finished(tmp_path / "kept", OVERRIDES)
    stale = _finished(tmp_path / "stale", OVERRIDES,
                      edit=lambda r: r["simulation"].update(duration_s=40.0))
    ran: list[str] = []

    def runner(executor, workers, scheduler):
        from contextlib import nullcontext

        from sse_cosim.reporting.outputs import TaskOutcome

        return nullcontext(lambda todo: ((ran.append(t.key), TaskOutcome(t.key, {}, None))[1]
                                         for t in todo))

    monkeypatch.setattr("sse_cosim.runner.executors._runner", runner)
    outcomes = execute([kept, stale], Execution(workers=1, resume=True, progress=False),
                       "sweep")
    assert ran == ["stale"] and [o.key for o in outcomes] == ["kept", "stale"]
    assert "sweep: 1 finished run(s) recorded another scenario" in capsys.readouterr().out

"""The one line ``sse-cosim run`` prints: the average speed, the least distance to a
pedestrian (issue: reports that answer the user's question), the guarantee's counts."""

from __future__ import annotations

from pathlib import Path

from sse_cosim.cli.commands import _echo_summary

SUMMARY = {"scenario": "S1", "average_speed_mps": 8.4721, "containment_violations": 0,
           "collisions": 0, "collisions_moving": 0, "min_distance_bus_pedestrian_m": 4.7831}


def test_the_run_line_gives_the_least_distance(capsys) -> None:
    _echo_summary(SUMMARY, Path("runs/s1"))
    assert capsys.readouterr().out.strip() == (
        "S1: average speed 8.47 m/s, least distance 4.78 m, containment violations 0, "
        "collisions 0 -> runs/s1")


def test_without_a_pedestrian_it_says_so(capsys) -> None:
    _echo_summary({**SUMMARY, "min_distance_bus_pedestrian_m": None}, Path("runs/s1"))
    assert "no pedestrian in the scene, containment" in capsys.readouterr().out

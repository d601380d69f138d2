"""Lone walkers in real SUMO (sse_cosim.world.walk_probe) on the paper road."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from sse_cosim.errors import SimulationError
from sse_cosim.world.walk_probe import Walker, WalkTrace, walk_alone, walk_alone_kept_on_error

pytestmark = pytest.mark.sumo

STEP_S = 0.1
SPEED = 1.5
# the scenario pedestrian's walk (south sidewalk, west of the zebra, to the north side), and back
ACROSS = ("WC", ":C_w1", ":C_c0", ":C_w0", "CW")
BACK = tuple(reversed(ACROSS))
# What SUMO's striping model adds to a step of SPEED * STEP_S where the walker enters, crosses
# or leaves a walking area (it re-places the walker sideways onto its next stripe). Measured
# with these walks: 0.5505 m on ACROSS, 1.0188 m on BACK (on :C_w0_0 and :C_w1_0). On
# sidewalks and the crossing a step is the walking distance up to rounding.
JUMP_ACROSS_M = 0.6
JUMP_BACK_M = 1.1
ROUNDING_M = 1e-6


def _edges_in_order(trace: WalkTrace) -> list[str]:
    edges: list[str] = []
    for lane in trace.lanes:
        edge = lane.rpartition("_")[0]
        if not edges or edges[-1] != edge:
            edges.append(edge)
    return edges


def _check_steps(trace: WalkTrace, jump_m: float) -> None:
    steps = np.linalg.norm(np.diff(trace.xy, axis=0), axis=1)
    on_area = np.array([":C_w" in a or ":C_w" in b
                        for a, b in zip(trace.lanes[:-1], trace.lanes[1:], strict=True)])
    assert np.all(steps[~on_area] <= SPEED * STEP_S + ROUNDING_M), steps[~on_area].max()
    assert np.all(steps[on_area] <= SPEED * STEP_S + jump_m), steps[on_area].max()
    assert steps[on_area].max() > SPEED * STEP_S + 0.1  # the jumps the bound is about


def test_lone_walkers_walk_their_paths_in_steps_bounded_by_speed_and_jumps(net_path, tmp_path):
    """Two walkers, one after the other (never near each other): each is seen every step from
    its departure until it arrives, on its edges in order, its steps bounded as measured."""
    back_depart = 40.0  # the first has arrived (23.4 s)
    traces = walk_alone(net_path, [
        Walker("across", ACROSS, depart_pos_m=184.0, arrival_pos_m=4.0, speed_mps=SPEED),
        Walker("back", BACK, depart_pos_m=4.0, arrival_pos_m=184.0, speed_mps=SPEED,
               depart_s=back_depart),
    ], STEP_S, tmp_path)
    assert set(traces) == {"across", "back"}
    for trace, edges, depart, jump in ((traces["across"], ACROSS, 0.0, JUMP_ACROSS_M),
                                       (traces["back"], BACK, back_depart, JUMP_BACK_M)):
        k = len(trace.times_s)
        assert trace.xy.shape == (k, 2) and len(trace.lanes) == k
        assert trace.times_s[0] == pytest.approx(depart)
        assert np.allclose(np.diff(trace.times_s), STEP_S)
        assert _edges_in_order(trace) == list(edges)
        _check_steps(trace, jump)
        # about as long as the walk at its speed (SUMO's walking-area paths are shorter)
        on_crossing = trace.first_time_on({":C_c0"})
        assert on_crossing is not None and depart < on_crossing < trace.times_s[-1]
    assert traces["across"].times_s[-1] < back_depart
    assert (tmp_path / "walkers.rou.xml").is_file() and (tmp_path / "sumo.sumocfg").is_file()


def test_until_stops_early(net_path, tmp_path):
    trace = walk_alone(net_path, [Walker("p", ACROSS, 184.0, 4.0, SPEED)], STEP_S, tmp_path,
                       until_s=2.0)["p"]
    assert trace.times_s[-1] == pytest.approx(2.0)
    assert _edges_in_order(trace) == ["WC"]


def test_an_open_simulation_is_refused_and_the_probe_always_closes(net_path, tmp_path):
    from sse_cosim.world.sumo_setup import libsumo

    walker = Walker("p", ACROSS, 184.0, 4.0, SPEED)
    walk_alone(net_path, [walker], STEP_S, tmp_path / "a", until_s=0.5)
    assert not libsumo.isLoaded()
    libsumo.start(["sumo", "-c", str(tmp_path / "a" / "sumo.sumocfg")])
    try:
        with pytest.raises(SimulationError, match="already open"):
            walk_alone(net_path, [walker], STEP_S, tmp_path / "b")
    finally:
        libsumo.close()
    # a walk SUMO cannot route names the walker, and leaves no simulation open
    with pytest.raises(SimulationError, match="walker 'lost'") as info:
        walk_alone(net_path, [walker, Walker("lost", ("WC", "nowhere"), 184.0, 1.0, SPEED)],
                   STEP_S, tmp_path / "c")
    assert "\n" not in str(info.value)
    assert not libsumo.isLoaded()
    with pytest.raises(SimulationError, match=r"walker 'far'.*depart_pos_m = 500 m"):
        walk_alone(net_path, [Walker("far", ACROSS, 500.0, 4.0, SPEED)], STEP_S, tmp_path / "d")
    assert not libsumo.isLoaded()
    assert len(walk_alone(net_path, [walker], STEP_S, tmp_path / "e",
                          until_s=0.5)["p"].times_s) == 6


def test_a_failed_probe_in_a_temporary_folder_keeps_the_log_its_error_names(net_path):
    """A cut network's border walks (issue: live on real streets) failed with an error that
    named a log in a temporary folder already deleted; the folder now stays on failure, and
    goes once the walkers have walked."""
    import re

    with pytest.raises(SimulationError) as info:
        walk_alone_kept_on_error(net_path, [Walker("lost", ("WC", "nowhere"), 184.0, 1.0,
                                                   SPEED)], STEP_S, "sse-cosim-test-")
    named = re.search(r"see (\S+sumo\.log)", str(info.value))
    assert named is not None and Path(named.group(1)).is_file()
    shutil.rmtree(Path(named.group(1)).parent)
    walked = walk_alone_kept_on_error(net_path, [Walker("p", ACROSS, 184.0, 4.0, SPEED)],
                                      STEP_S, "sse-cosim-test-", until_s=0.5)
    assert len(walked["p"].times_s) == 6

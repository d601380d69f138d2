"""Traffic lights (issue: live on real streets): the road map reads each signalised link and
crossing and the network's programs; the release bound a light gives its walkers; and the
``pedestrian_lights`` check (sse_cosim/world/checks/lights.py) on constructed snapshots of
tests/networks/two_lanes/, whose junction J is signalised: links 0-3 the driving lanes through
J, link 4 the walkers onto its crossing ':J_c0', program 77 s green for the cars, 3 s yellow,
5 s green for the walkers, 5 s all red."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest
from world_helpers import REPO

from sse_cosim.errors import AssumptionBroken
from sse_cosim.scenario.loader import load_scenario_data, validate_scenario
from sse_cosim.world.checks import CheckSetup, Ledger, StepFacts, ledger
from sse_cosim.world.checks.lights import LightsCheck
from sse_cosim.world.network import build_network
from sse_cosim.world.roadmap import RoadMap, load_roadmap
from sse_cosim.world.signals import (
    WALKERS_GO,
    WALKERS_WAIT,
    Phase,
    Program,
    SignalState,
    earliest_release_s,
)
from sse_cosim.world.snapshot import PersonState, Snapshot

PROGRAM = Program("0", (Phase("GGGGr", 77.0), Phase("yyyyr", 3.0), Phase("rrrrG", 5.0),
                        Phase("rrrrr", 5.0)))


def state(phase: int, spent_s: float) -> SignalState:
    return SignalState("0", phase, PROGRAM.phases[phase].state, spent_s)


@pytest.mark.parametrize(("phase", "spent", "link", "release"), [
    (0, 10.0, 4, 70.0),   # the walkers wait out the cars' green and yellow
    (1, 1.0, 4, 2.0),
    (2, 1.0, 4, 0.0),     # their own green
    (3, 2.0, 4, 3.0 + 77.0 + 3.0),  # all red, then a whole cycle until their green
    (2, 4.0, 0, 1.0 + 5.0),  # a car's red: the walkers' green and the all red
])
def test_the_release_bound_walks_the_program_from_the_current_phase(phase, spent, link,
                                                                    release):
    assert earliest_release_s(PROGRAM, state(phase, spent), link, frozenset("ryu")
                              if link < 4 else WALKERS_WAIT) == pytest.approx(release)


def test_a_link_red_in_every_phase_is_never_released_and_an_unordered_program_gives_its_phase():
    always = Program("0", (Phase("r", 5.0), Phase("r", 5.0)))
    assert earliest_release_s(always, SignalState("0", 0, "r", 1.0), 0, WALKERS_WAIT) == \
        math.inf
    skipping = Program("0", PROGRAM.phases, in_order=False)
    assert earliest_release_s(skipping, state(0, 10.0), 4, WALKERS_WAIT) == pytest.approx(67.0)


@pytest.fixture(scope="module")
def roadmap() -> RoadMap:
    return load_roadmap(build_network(REPO / "tests" / "networks" / "two_lanes"))


@pytest.mark.sumo
def test_the_road_map_reads_the_signalised_links_crossings_and_programs(roadmap):
    (crossing,) = roadmap.crossings
    assert crossing.signals == (("J", 4),)
    assert roadmap.link_signals[("WJ_1", "JE_1")] == ("J", 2)
    assert roadmap.programs[("J", "0")] == PROGRAM
    assert roadmap.lights == ("J",)
    assert roadmap.crossing_lights(crossing).release_s({"J": state(0, 10.0)}) == \
        pytest.approx(70.0)


def walker(crossing: str | None, x: float = 0.0, y: float = -7.0) -> PersonState:
    return PersonState("w", (x, y), 1.4, crossing=crossing)


def check(roadmap: RoadMap, *steps: tuple[float, SignalState, PersonState]) -> list[str]:
    """The problems the lights check finds over ``steps`` (time, J's state, the walker)."""
    lights = LightsCheck(roadmap, 0.25)
    return [brk.problem for time, light, person in steps
            for brk in lights.check(Snapshot(time, persons={"w": person},
                                             signals={"J": light}), StepFacts())]


@pytest.mark.sumo
def test_a_walker_stepping_onto_its_crossing_at_red_breaks_the_assumption(roadmap):
    at_red = check(roadmap, (10.0, state(0, 10.0), walker(None, y=-7.0)),
                   (10.1, state(0, 10.1), walker(":J_c0", y=-6.3)))
    assert len(at_red) == 1 and "stepped onto crossing :J_c0 at t=10.10 s while its light " \
        "showed red" in at_red[0]
    at_green = check(roadmap, (80.5, state(2, 0.5), walker(None, y=-7.0)),
                     (80.6, state(2, 0.6), walker(":J_c0", y=-6.3)))
    assert at_green == []
    already_on = check(roadmap, (78.0, state(1, 1.0), walker(":J_c0", y=-3.0)),
                       (78.1, state(1, 1.1), walker(":J_c0", y=-2.9)))
    assert already_on == []


@pytest.mark.sumo
def test_a_light_off_its_program_or_a_walker_off_its_crossing_or_on_it_unseen_breaks_it(
        roadmap):
    other = SignalState("0", 0, "GGGGG", 1.0)
    assert "is not a phase of the programs the network defines" in check(
        roadmap, (1.0, other, walker(None)))[0]
    off = check(roadmap, (80.5, state(2, 0.5), walker(":J_c0", x=2.5, y=0.0)))
    assert len(off) == 1 and "0.500 m outside the crossing's area" in off[0]
    elsewhere = check(roadmap, (80.5, state(2, 0.5), walker(None, x=0.0, y=-3.0)))
    assert len(elsewhere) == 1 and "is on crossing :J_c0's own ground" in elsewhere[0]
    assert check(roadmap, (80.5, state(2, 0.5), walker(None, x=0.0, y=-6.5))) == []


@pytest.mark.sumo
def test_a_light_the_network_defines_no_program_for_gives_no_bound_and_is_not_checked(
        roadmap):
    """A rail signal's states come from the trains (the whole converted town's '1201668353'
    lets walkers onto a crossing and showed 'rO' at t = 0): with no program in the network
    its crossing gets no bound, and its states break nothing; a light with programs still
    must keep to them."""
    rail = SignalState("0", 1, "rO", 0.0)
    lights = LightsCheck(roadmap, 0.25)
    found = lights.check(Snapshot(0.0, persons={"w": walker(None)},
                                  signals={"rail": rail, "J": state(0, 10.0)}), StepFacts())
    assert found == []
    found = lights.check(Snapshot(0.1, persons={"w": walker(None)},
                                  signals={"rail": rail, "J": SignalState("0", 0, "GGGGG", 1.0)}),
                         StepFacts())
    assert [brk.record["light"] for brk in found] == ["J"]
    (crossing,) = roadmap.crossings
    on_rail = replace(crossing, signals=(("rail", 1),))
    assert roadmap.crossing_lights(on_rail).release_s({"rail": rail}) == 0.0


@pytest.mark.sumo
def test_the_ledger_stops_the_run_in_one_line_unless_the_study_declares_it(roadmap, tmp_path):
    steps = [Snapshot(10.0, persons={"w": walker(None)}, signals={"J": state(0, 10.0)}),
             Snapshot(10.1, persons={"w": walker(":J_c0", y=-6.3)},
                      signals={"J": state(0, 10.1)})]
    stopping = Ledger([LightsCheck(roadmap, 0.25)], [], "s.toml")
    stopping.step(steps[0], StepFacts())
    with pytest.raises(AssumptionBroken, match=r"^s\.toml: .*\(pedestrian_lights\): pedestrian "
                       r"'w' stepped onto crossing :J_c0 .* list 'pedestrian_lights' in "
                       r"breaks_assumptions$") as caught:
        stopping.step(steps[1], StepFacts())
    assert "\n" not in str(caught.value)
    data = load_scenario_data(REPO / "scenarios" / "s1_pedestrian.toml")
    data["breaks_assumptions"] = ["pedestrian_lights"]
    data["estimator"] = {**data.get("estimator", {}), "position_jitter_m": 1.0}
    data["automated"] = {"bus": {"route_edges": ["WJ", "JE"]}}  # on this network
    counting = ledger(CheckSetup(validate_scenario(data, "s.toml"), roadmap), "s.toml")
    for snapshot in steps:
        counting.step(snapshot, StepFacts())
    assert counting.summary["light_breaks"]["count"] == 1
    assert counting.summary["light_breaks"]["first"][0]["crossing"] == ":J_c0"


def test_a_static_programs_green_windows_follow_its_offset_as_sumo_runs_it():
    """SUMO 1.28 runs J's program with offset 10 s from rrrrG at t = 0 to 5 s, then rrrrr,
    then GGGGr from 10 s (measured with libsumo on a copy of the network): at SUMO time t
    the program is (t - offset) mod cycle into its cycle."""
    shifted = Program("0", PROGRAM.phases, offset_s=10.0)
    assert shifted.windows(4, WALKERS_GO, 0.0, 200.0) == [(0.0, 5.0), (90.0, 95.0),
                                                          (180.0, 185.0)]
    assert PROGRAM.windows(0, frozenset("G"), 50.0, 200.0) == [(0.0, 77.0), (90.0, 167.0),
                                                               (180.0, 257.0)]

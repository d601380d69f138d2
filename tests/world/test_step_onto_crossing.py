"""A pedestrian steps onto its crossing at steps_onto_crossing_s within one step, in real SUMO,
on the paper road's prioritised zebra and on a copy of the road whose crossing is not
prioritised (tests/networks/unprioritised_zebra, as netconvert's --crossings.guess makes
them), with the bus approaching; a time its walk cannot make is refused; its crossing can be
named; the world stops a run whose pedestrian is off its time."""

from __future__ import annotations

from pathlib import Path

import pytest
import shapely
import sumolib
from world_helpers import REPO, run_world, scenario

from sse_cosim.errors import SimulationError, UserError
from sse_cosim.world import demand
from sse_cosim.world.network import build_network
from sse_cosim.world.roadmap import Crossing, RoadMap, load_roadmap
from sse_cosim.world.snapshot import Footprint, Pose
from sse_cosim.world.walk_probe import ProbeTimer

pytestmark = pytest.mark.sumo

PED = "pedestrians.pedestrian"
NETWORKS = {"prioritised": REPO / "sumo_net",
            "unprioritised": REPO / "tests" / "networks" / "unprioritised_zebra"}
# 8 m behind the junction: SUMO's lone walker at 1.5 m/s reaches the zebra 7.1 s after it
# starts (10.64 m along the network's lengths: 7.09 s), while the bus (20 m/s from x = 0)
# is still some 40 m before the zebra at 8 s
NEAR = {f"{PED}.start_pos_m": 190.0, "simulation.duration_s": 9.0}
WALK_S = 7.1


def _step_on(name: str, tmp_path: Path, **overrides: object) -> tuple[float, float, float]:
    """When the pedestrian first stood on the crossing (s), and the bus's front x (m) and speed
    (m/s) then."""
    sc = scenario("s1_pedestrian", **{"network.sources_dir": str(NETWORKS[name]), **NEAR,
                                      **overrides})
    run = run_world(sc, tmp_path)
    snap = next(s for s in run.snapshots if s.persons["pedestrian"].on_crossing)
    bus = snap.vehicles["bus"]
    return snap.time, bus.footprint.front.x, bus.speed


@pytest.mark.parametrize("name", sorted(NETWORKS))
@pytest.mark.parametrize("wanted", [8.0, 7.15])
def test_it_steps_on_in_time_in_front_of_the_approaching_bus(name: str, wanted: float,
                                                               tmp_path: Path) -> None:
    """Without its type's jmIgnoreFoeProb the walker at the unprioritised crossing waited for
    the bus to pass (it stepped on at 10.8 s instead of 8 s)."""
    on, bus_x, bus_speed = _step_on(name, tmp_path, **{f"{PED}.steps_onto_crossing_s": wanted})
    assert abs(on - wanted) <= 0.1 / 2 + 1e-6  # the nearest step
    assert bus_x < 198.0 - 20.0 and bus_speed > 10.0  # the bus approaches, not yet near


def test_the_crossing_is_unprioritised_in_the_copy() -> None:
    net = sumolib.net.readNet(str(build_network(NETWORKS["unprioritised"])), withInternal=True,
                              withPedestrianConnections=True)
    link = net.getEdge(":C_w0").getOutgoing()[net.getEdge(":C_c0")][0]
    assert link.getState() == "m"  # vehicles do not yield: its walker would wait


def test_the_walk_is_timed_by_sumos_walker_not_by_lengths(net_path: Path) -> None:
    """SUMO's path over the walking area is shorter than its length attribute: the walk takes
    7.1 s, not 10.64 m / 1.5 m/s rounded up (7.1 s as well here, but 11.1 s against 11.3 s
    from the paper's start at 184 m)."""
    sc = scenario("s1_pedestrian", **{f"{PED}.steps_onto_crossing_s": 11.5})
    plan = demand.plan_actors(sc, net_path, load_roadmap(net_path), "test",
                              ProbeTimer(net_path)).pedestrians["pedestrian"]
    assert plan.walk_to_crossing_s == pytest.approx(11.1)
    assert plan.distance_to_crossing_m / 1.5 == pytest.approx(11.21, abs=0.01)
    assert plan.walk_start_s == pytest.approx(0.4) and plan.steps_on_s == pytest.approx(11.5)
    assert plan.crossing == ":C_c0"


def test_a_time_the_walk_cannot_make_is_refused_with_the_earliest(net_path: Path) -> None:
    sc = scenario("s1_pedestrian", **{**NEAR, f"{PED}.steps_onto_crossing_s": WALK_S - 0.1})
    with pytest.raises(UserError) as info:
        demand.plan_actors(sc, net_path, load_roadmap(net_path), "test")
    err = info.value
    assert err.field == f"{PED}.steps_onto_crossing_s"
    assert f"at {WALK_S:g} s at the earliest" in err.problem and ":C_c0" in err.problem
    assert f"use {WALK_S:g} s or later" in err.fix
    # the earliest is taken: it walks from t = 0
    sc = scenario("s1_pedestrian", **{**NEAR, f"{PED}.steps_onto_crossing_s": WALK_S})
    plan = demand.plan_actors(sc, net_path, load_roadmap(net_path), "test")
    assert plan.pedestrians["pedestrian"].walk_start_s == 0.0


TWO_ZEBRAS = REPO / "tests" / "networks" / "two_zebras"


def test_the_pedestrian_crosses_where_its_crossing_says() -> None:
    """On the road with two zebras (C at x = 200, D at x = 260) a walk from CD's sidewalk
    to DC's takes D's zebra unless the pedestrian names C's; a typo names the nearest ids."""
    net_path = build_network(TWO_ZEBRAS)
    roadmap = load_roadmap(net_path)
    base = {"network.sources_dir": str(TWO_ZEBRAS), "automated.bus.route_edges": ["WC", "CD"],
            "parked.truck.present": False, f"{PED}.start_edge": "CD",
            f"{PED}.start_pos_m": 40.0, f"{PED}.end_edge": "DC", f"{PED}.end_pos_m": 30.0,
            f"{PED}.steps_onto_crossing_s": 30.0}

    def plan(**more: object) -> demand.PedestrianPlan:
        sc = scenario("s1_pedestrian", **base, **more)
        return demand.plan_actors(sc, net_path, roadmap, "test").pedestrians["pedestrian"]

    assert plan().crossing == ":D_c0"
    chosen = plan(**{f"{PED}.crossing": ":C_c0"})
    assert chosen.crossing == ":C_c0" and ":D_c0" not in chosen.path
    assert chosen.path[0] == "CD" and chosen.path[-1] == "DC"
    with pytest.raises(UserError) as info:
        plan(**{f"{PED}.crossing": ":C_c1"})
    assert info.value.field == f"{PED}.crossing"
    assert "no crossing ':C_c1'" in info.value.problem
    assert ":C_c0" in info.value.fix and ":D_c0" in info.value.fix


def off_by(shift_s: float, monkeypatch: pytest.MonkeyPatch) -> None:
    """A timer that says every walk takes ``shift_s`` longer than it does: the walker steps
    on that much early."""
    real = ProbeTimer.__call__

    def late(self: ProbeTimer, walks: dict, step_s: float) -> dict[str, float]:
        return {pid: t + shift_s for pid, t in real(self, walks, step_s).items()}

    monkeypatch.setattr(ProbeTimer, "__call__", late)


def test_a_pedestrian_off_its_time_stops_the_run(tmp_path: Path,
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    """2 s early, beyond the default tolerance of 1 s: the world stops the run at that step
    with one line."""
    off_by(2.0, monkeypatch)
    sc = scenario("s1_pedestrian", **{**NEAR, f"{PED}.steps_onto_crossing_s": 10.0})
    with pytest.raises(SimulationError) as info:
        run_world(sc, tmp_path)
    line = str(info.value)
    assert "\n" not in line
    for words in ("pedestrian 'pedestrian'", ":C_c0", "at 10 s", "stepped onto it at 8.00 s",
                  "more than 1 s off", f"{PED}.steps_onto_crossing_s"):
        assert words in line, (words, line)


def test_a_moment_off_its_time_is_within_the_default_tolerance(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """0.5 s early (a car's right of way holds a walker about that long): the run goes on;
    with the tolerance set to one step it stops."""
    off_by(0.5, monkeypatch)
    sc = scenario("s1_pedestrian", **{**NEAR, f"{PED}.steps_onto_crossing_s": 8.5})
    run_world(sc, tmp_path / "default")
    strict = scenario("s1_pedestrian", **{**NEAR, f"{PED}.steps_onto_crossing_s": 8.5,
                                          f"{PED}.crossing_tolerance_s": 0.1})
    with pytest.raises(SimulationError, match=r"stepped onto it at 8\.00 s"):
        run_world(strict, tmp_path / "strict")


def test_a_timer_walks_the_same_walks_once(net_path: Path, monkeypatch) -> None:
    """The safety campaign asks its planner's timer for the same walks at every step-out time,
    noise bound and seed: one SUMO session each, the same times, and a caller's copy."""
    from sse_cosim.world import walk_probe

    sessions: list[int] = []
    real = walk_probe.walk_alone

    def counted(*args, **kwargs):
        sessions.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(walk_probe, "walk_alone", counted)
    timer = ProbeTimer(net_path)
    roadmap = load_roadmap(net_path)

    def walk(**fields: object) -> float:
        sc = scenario("s1_pedestrian", **{f"{PED}.steps_onto_crossing_s": 11.5, **fields})
        return demand.plan_actors(sc, net_path, roadmap, "test",
                                  timer).pedestrians["pedestrian"].walk_to_crossing_s

    first = walk()
    assert walk(**{"simulation.seed": 7, f"{PED}.steps_onto_crossing_s": 13.0}) == first
    assert len(sessions) == 1  # the same walk: timed once
    assert walk(**{f"{PED}.walking_speed_mps": 2.5}) < first and len(sessions) == 2
    walks, step_s = next(iter(timer._timed))
    timer(dict(walks), step_s).clear()  # a copy: the kept times stay
    assert walk() == first and len(sessions) == 2


def test_a_vehicle_knows_the_crossings_its_body_is_on() -> None:
    """SUMO keeps a pedestrian off a crossing a vehicle occupies: the falsifier's town search
    found the bus standing with its rear on the walker's crossing, and the run stopping with
    "had not stepped onto it by 34.40 s (on it: bus)"
    (results/falsify/town_second/standoff_cma_27.toml). The world names the crossings each
    vehicle's body meets (``VehicleState.on_crossings``), from which that stop and the
    ``crossing_blocked`` margin read."""
    zebra = Crossing(":C_c0", "C", shapely.box(196.0, -8.0, 200.0, 8.0))  # across x 196-200
    other = Crossing(":D_c0", "D", shapely.box(300.0, -8.0, 304.0, 8.0))
    roadmap = RoadMap(Path("net.net.xml"), (zebra, other), shapely.Polygon(), {}, {}, {}, {}, {})

    def meets(front_x: float) -> tuple[str, ...]:
        body = Footprint(Pose(front_x, -1.75, 0.0), 12.0, 2.55).polygon()
        return roadmap.crossings_meeting(body)

    assert meets(211.9) == (":C_c0",)  # its rear on it
    assert meets(196.1) == (":C_c0",)  # its front on it
    assert meets(203.0) == (":C_c0",)  # astride it
    assert meets(212.1) == meets(195.9) == ()  # past it, before it
    assert meets(302.0) == (":D_c0",)

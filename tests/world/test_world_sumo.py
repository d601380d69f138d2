"""The paper scenarios in real SUMO through libsumo.

libsumo holds one simulation per process; these tests start and close one after the other in
the pytest process (see world_helpers.py for why that is safe).
"""

from __future__ import annotations

import math
import multiprocessing
from pathlib import Path

import numpy as np
import pytest
import shapely
from world_helpers import PAPER_SCENARIOS, Run, run_world, scenario

from sse_cosim.errors import SimulationError, UserError
from sse_cosim.scenario.model import present
from sse_cosim.world.snapshot import PersonState

pytestmark = pytest.mark.sumo

PARKING_STRIP_Y = (-6.0, -3.5)  # the eastbound parking strip (sumo_net/README.md)
# the walk is timed by SUMO's own walker: the pedestrian steps onto the zebra at the step
# nearest to the configured time
ON_TIME = 0.05 + 1e-6


def truck_corners(end_pos_m: float, length_m: float) -> np.ndarray:
    """The parked truck's corners, counter-clockwise from the rear right, shape (4, 2)."""
    rear, low, high = end_pos_m - length_m, *PARKING_STRIP_Y
    return np.array([[rear, low], [end_pos_m, low], [end_pos_m, high], [rear, high]])

_RUNS: dict[str, Run] = {}


def _run(name: str, tmp_path_factory: pytest.TempPathFactory) -> Run:
    if name not in _RUNS:
        _RUNS[name] = run_world(scenario(name), tmp_path_factory.mktemp(name), name)
    return _RUNS[name]


def test_paper_scenarios_found() -> None:
    assert len(PAPER_SCENARIOS) == 6


@pytest.mark.parametrize("name", PAPER_SCENARIOS)
def test_actors_where_configured(name: str, tmp_path_factory: pytest.TempPathFactory) -> None:
    sc = scenario(name)
    run = _run(name, tmp_path_factory)
    first = run.snapshots[0]
    assert first.time == 0.0
    bus = first.vehicles.get("bus")
    assert bus is not None and bus.id == "bus"
    assert bus.footprint.front.x == pytest.approx(sc.automated["bus"].depart_pos_m, abs=0.01)
    assert bus.footprint.front.y == pytest.approx(-1.75)
    assert bus.footprint.front.heading == pytest.approx(0.0)
    assert bus.speed == pytest.approx(sc.automated["bus"].nominal_speed_mps)
    assert (bus.footprint.length, bus.footprint.width) == (12.0, 2.55)
    truck = first.vehicles.get("truck")
    assert truck is not None
    expected = truck_corners(sc.parked["truck"].end_pos_m, sc.parked["truck"].length_m)
    assert truck.footprint.corners() == pytest.approx(expected, abs=0.05)
    # the truck stays parked: the same footprint at every step
    for snap in run.snapshots:
        assert snap.vehicles["truck"] == truck
    if "car" in sc.vehicles:
        cars = [s.vehicles.get("car") for s in run.snapshots if s.vehicles.get("car") is not None]
        assert cars, "the car never appeared"
        appear = next(s.time for s in run.snapshots if s.vehicles.get("car") is not None)
        assert appear == pytest.approx(sc.vehicles["car"].depart_s)
        for car in cars:
            assert car.footprint.front.y == pytest.approx(1.75)  # westbound driving lane
            assert abs(car.footprint.front.heading) == pytest.approx(math.pi)
        assert cars[0].speed == pytest.approx(sc.vehicles["car"].speed_mps)
        assert max(c.speed for c in cars) <= sc.vehicles["car"].speed_mps + 1e-9
    else:
        assert all(s.vehicles.get("car") is None for s in run.snapshots)
    assert run.teleports == 0
    assert run.route_length == pytest.approx(300.0)


@pytest.mark.parametrize("name", PAPER_SCENARIOS)
def test_pedestrian_walks_over_the_zebra(name: str,
                                         tmp_path_factory: pytest.TempPathFactory) -> None:
    sc = scenario(name)
    run = _run(name, tmp_path_factory)
    if not present(sc.pedestrians):
        assert all(not s.persons for s in run.snapshots)
        assert run.pedestrian_plans == {}
        return
    plan = run.pedestrian_plans["pedestrian"]
    tracks = [(s.time, s.persons["pedestrian"]) for s in run.snapshots if "pedestrian" in s.persons]
    t0, p0 = tracks[0]
    assert t0 == 0.0  # there from the first step
    assert p0.position == plan.standing_xy
    assert p0.position[0] == pytest.approx(sc.pedestrians["pedestrian"].start_pos_m, abs=0.5)
    assert -8.0 < p0.position[1] < -6.0  # on the south sidewalk, behind the truck
    on = [t for t, p in tracks if p.on_crossing]
    assert on, "the pedestrian never stepped onto the crossing"
    ped = sc.pedestrians["pedestrian"]
    assert on[0] == pytest.approx(ped.steps_onto_crossing_s, abs=ON_TIME)
    assert all(run.roadmap.crossing_area.buffer(0.5).contains(_point(p))
               for _, p in tracks if p.on_crossing)
    after = [p for t, p in tracks if t > on[-1]]
    assert after and after[-1].position[1] > 6.0, "the pedestrian did not reach the north side"
    assert max(p.speed for _, p in tracks) == pytest.approx(ped.walking_speed_mps)


@pytest.mark.parametrize("overrides", [
    {},
    # SUMO moves this walker 1.21 m in one step on the walking area :C_w1_0 (t = 19.3 s): the
    # jitter measured for the road covers it (sse_cosim/world/walker_jitter.py)
    {"pedestrians.pedestrian.start_edge": "CE", "pedestrians.pedestrian.start_pos_m": 14.0,
     "pedestrians.pedestrian.end_edge": "EC", "pedestrians.pedestrian.end_pos_m": 90.0,
     "parked.truck.present": False},
], ids=["east along WC", "west along CE"])
def test_pedestrian_waits_at_its_start_until_its_walk_starts(overrides: dict,
                                                             tmp_path: Path) -> None:
    """It exists from t=0, stands still at its start until its walk starts, walks on from
    there without a jump, and steps onto the crossing at the configured time (both walking
    along its start edge and against it)."""
    sc = scenario("s1_pedestrian", **{"pedestrians.pedestrian.start_pos_m": 184.0,
                                      "pedestrians.pedestrian.walking_speed_mps": 1.2,
                                      "pedestrians.pedestrian.steps_onto_crossing_s": 20.0,
                                      "simulation.duration_s": 21.0, **overrides})
    run = run_world(sc, tmp_path)
    plan = run.pedestrian_plans["pedestrian"]
    assert plan.walk_start_s == pytest.approx(20.0 - plan.walk_to_crossing_s)
    assert all("pedestrian" in s.persons for s in run.snapshots)
    track = [(s.time, s.persons["pedestrian"]) for s in run.snapshots]
    waiting = [p for t, p in track if t <= plan.walk_start_s + 1e-9]
    assert len(waiting) == round(plan.walk_start_s / 0.1) + 1  # t = 0.0 ... walk_start_s
    assert {p.position for p in waiting} == {plan.standing_xy}
    assert all(p.speed == 0.0 and not p.on_crossing for p in waiting)
    assert run.roadmap.sidewalks.contains(shapely.Point(plan.standing_xy))
    walking = [p for t, p in track if t > plan.walk_start_s + 1e-9]
    step = sc.pedestrians["pedestrian"].walking_speed_mps * sc.simulation.step_length_s
    # it walks on from where it stood: one step along the sidewalk, no sideways jump
    assert math.dist(plan.standing_xy, walking[0].position) == pytest.approx(step)
    assert walking[0].position[1] == pytest.approx(plan.standing_xy[1])
    on = [t for t, p in track if p.on_crossing]
    assert on[0] == pytest.approx(20.0, abs=ON_TIME)


def test_a_car_without_room_at_its_departure_is_a_user_error(tmp_path: Path) -> None:
    """A connected car placed where a slow bus stands: SUMO keeps it waiting; at its
    departure the world refuses the scenario, naming car.depart_pos_m."""
    from sse_cosim.world.sumo import SumoWorld

    sc = scenario("s2_no_pedestrian", **{"automated.bus.nominal_speed_mps": 0.5,
                                         "vehicles.car.depart_s": 0.5,
                                         "vehicles.car.route_edges": ["WC", "CE"]})
    times = []
    with pytest.raises(UserError) as info, SumoWorld(sc, tmp_path, "blocked.toml") as world:
        for _ in range(50):
            times.append(world.step().time)
    assert times[-1] == pytest.approx(0.4)  # refused at the step of its departure
    assert (info.value.source, info.value.field) == ("blocked.toml", "vehicles.car.depart_pos_m")
    assert "cannot insert 'car'" in info.value.problem
    assert "vehicles.car.depart_s" in info.value.fix


def test_a_car_far_enough_ahead_of_the_bus_starts_where_the_scenario_says(tmp_path: Path) -> None:
    """On the bus's lane, far enough ahead for the bus to brake for it, the car is on the road
    from its departure, at its departure position, ahead of the bus (too close ahead it is
    refused: tests/bad_input/test_sumo_failures.py)."""
    sc = scenario("s2_no_pedestrian", **{"vehicles.car.route_edges": ["WC", "CE"],
                                         "vehicles.car.depart_pos_m": 120.0})
    snapshots = run_world(sc, tmp_path, steps=5).snapshots
    car, bus = snapshots[0].vehicles.get("car"), snapshots[0].vehicles.get("bus")
    assert car is not None and bus is not None
    assert (car.footprint.front.x, car.footprint.front.y) == pytest.approx((120.0, -1.75))
    assert bus.footprint.front.x == pytest.approx(0.0)


@pytest.mark.parametrize("name", ["s1_pedestrian", "s2_pedestrian", "s3_no_pedestrian"])
def test_same_seed_same_snapshots(name: str, tmp_path: Path,
                                  tmp_path_factory: pytest.TempPathFactory) -> None:
    again = run_world(scenario(name), tmp_path, name)
    assert again.snapshots == _run(name, tmp_path_factory).snapshots


def _fresh_process_run(name: str, run_dir: str) -> list:
    return run_world(scenario(name), Path(run_dir), name).snapshots


def test_restart_in_process_matches_fresh_process(tmp_path: Path,
                                                  tmp_path_factory: pytest.TempPathFactory) -> None:
    ctx = multiprocessing.get_context("spawn")
    with ctx.Pool(1) as pool:
        fresh = pool.apply(_fresh_process_run, ("s2_pedestrian", str(tmp_path)))
    assert fresh == _run("s2_pedestrian", tmp_path_factory).snapshots


def test_bus_follows_commands(tmp_path: Path) -> None:
    from sse_cosim.world.sumo import SumoWorld

    sc = scenario("s1_no_pedestrian", **{"simulation.duration_s": 20.0})
    dt = sc.simulation.step_length_s
    with SumoWorld(sc, tmp_path, "cmd") as world:
        assert world.last_commanded_speed("bus") is None
        world.set_speed("bus", 14.0)  # before departure: applies from the departure on
        speeds = [world.step().vehicles["bus"].speed for _ in range(30)]
        assert world.last_commanded_speed("bus") == 14.0
        # comfortable deceleration (3 m/s^2) from 20 m/s down to 14 m/s, then held
        assert np.diff(speeds[:21]) == pytest.approx(-3.0 * dt * np.ones(20))
        assert speeds[25:] == pytest.approx([14.0] * 5)
        world.set_speed("bus", 0.0, emergency=True)
        braking = [world.step().vehicles["bus"].speed for _ in range(5)]
        assert np.diff([speeds[-1], *braking]) == pytest.approx(-7.0 * dt * np.ones(5))
        world.set_speed("bus", 20.0)
        accel = [world.step().vehicles["bus"].speed for _ in range(5)]
        assert np.diff([braking[-1], *accel]) == pytest.approx(1.5 * dt * np.ones(5))
        x0 = world.step().vehicles.get("bus").footprint.front.x
        assert world.route_position("bus") == pytest.approx(x0)
        assert world.time == pytest.approx(40 * dt)  # 41 steps, the first at t=0
        with pytest.raises(ValueError):
            world.set_speed("bus", -1.0)


def test_a_bus_with_an_actuation_delay_acts_on_each_command_that_many_steps_later(
        tmp_path: Path) -> None:
    """A4's delay in the world: commanded at step k, the bus changes speed at step k + 3
    (0.3 s), the emergency brake too; the latest command is reported as given."""
    from sse_cosim.world.sumo import SumoWorld

    sc = scenario("s1_no_pedestrian", **{"simulation.duration_s": 20.0,
                                         "automated.bus.actuation_delay_s": 0.3,
                                         "controller.reaction_time_s": 0.3})
    dt = sc.simulation.step_length_s
    with SumoWorld(sc, tmp_path, "delay") as world:
        speeds = [world.step().vehicles["bus"].speed for _ in range(5)]
        assert speeds == pytest.approx([20.0] * 5)
        for command in (14.0, 14.0, 14.0):  # the first acts once three more have come
            world.set_speed("bus", command)
            speeds.append(world.step().vehicles["bus"].speed)
        assert world.last_commanded_speed("bus") == 14.0
        assert speeds[-3:] == pytest.approx([20.0] * 3)
        world.set_speed("bus", 0.0, emergency=True)
        speeds.append(world.step().vehicles["bus"].speed)  # the first 14 m/s acts now
        assert speeds[-1] == pytest.approx(20.0 - 3.0 * dt)
        for _ in range(3):
            world.set_speed("bus", 0.0, emergency=True)
            speeds.append(world.step().vehicles["bus"].speed)
        # the emergency brake given 3 steps before the last one acts at the last
        assert np.diff(speeds[-3:-1]) == pytest.approx([-3.0 * dt])
        assert speeds[-1] - speeds[-2] == pytest.approx(-7.0 * dt)


def test_bus_arrives(tmp_path: Path) -> None:
    sc = scenario("s1_no_pedestrian", **{"simulation.duration_s": 16.0})
    run = run_world(sc, tmp_path)
    assert run.bus_arrived
    assert run.snapshots[-1].vehicles.get("bus") is None


def test_sumo_yields_to_pedestrian_on_crossing(tmp_path: Path) -> None:
    # The pedestrian is on the crossing when a slow bus arrives: SUMO makes the bus wait.
    sc = scenario("s1_pedestrian", **{"automated.bus.depart_pos_m": 120.0,
                                      "automated.bus.nominal_speed_mps": 5.0,
                                      "pedestrians.pedestrian.walking_speed_mps": 1.2,
                                      "pedestrians.pedestrian.steps_onto_crossing_s": 14.1,
                                      "simulation.duration_s": 25.0})
    snaps = run_world(sc, tmp_path).snapshots
    for s in snaps:
        ped, bus = s.persons.get("pedestrian"), s.vehicles.get("bus")
        if ped is not None and bus is not None and ped.on_crossing and ped.position[1] > -3.5:
            # while the pedestrian is on the bus's half of the crossing, the bus is not on it
            assert not bus.footprint.polygon().intersects(_point(ped).buffer(0.3))
    stopped = [s.time for s in snaps if "bus" in s.vehicles and s.vehicles["bus"].speed < 0.1]
    assert stopped, "the bus never stopped for the pedestrian"


def test_one_simulation_per_process(tmp_path: Path) -> None:
    from sse_cosim.world.sumo import SumoWorld

    sc = scenario("s1_no_pedestrian")
    with SumoWorld(sc, tmp_path / "a", "first") as world:
        world.step()
        second = SumoWorld(sc, tmp_path / "b", "second")
        with pytest.raises(SimulationError, match="already open"), second:
            pass
        world.step()
    with SumoWorld(sc, tmp_path / "c", "third") as world:  # after closing, a new one starts
        assert world.step().time == 0.0
    with pytest.raises(SimulationError, match="not open"):
        world.step()


def test_libsumo_error_becomes_simulation_error(tmp_path: Path,
                                                monkeypatch: pytest.MonkeyPatch) -> None:
    from sse_cosim.world import sumo as sumo_module

    def broken() -> None:
        raise sumo_module.libsumo.TraCIException("boom")

    sc = scenario("s1_no_pedestrian")
    with (pytest.raises(SimulationError, match=r"s1_no_pedestrian: simulation failed: .*boom"),
          sumo_module.SumoWorld(sc, tmp_path, "s1_no_pedestrian") as world):
        world.step()
        monkeypatch.setattr(sumo_module.libsumo, "simulationStep", broken)
        world.step()
    monkeypatch.undo()
    assert not sumo_module.libsumo.isLoaded()  # closed on the way out


def test_bad_actor_is_a_user_error_before_sumo_starts(tmp_path: Path) -> None:
    from sse_cosim.world import sumo as sumo_module

    sc = scenario("s1_pedestrian", **{"pedestrians.pedestrian.start_edge": "XX"})
    world = sumo_module.SumoWorld(sc, tmp_path, "s1_pedestrian.toml")
    with pytest.raises(UserError) as info, world:
        pass
    assert (info.value.source, info.value.field) == \
        ("s1_pedestrian.toml", "pedestrians.pedestrian.start_edge")
    assert not sumo_module.libsumo.isLoaded()
    sc = scenario("s1_pedestrian", **{"parked.truck.end_pos_m": 250.0})
    world = sumo_module.SumoWorld(sc, tmp_path, "x")
    with pytest.raises(UserError, match=r"truck\.end_pos_m"), world:
        pass


def test_sumo_version() -> None:
    from sse_cosim.world.sumo import sumo_version

    assert sumo_version().split(".")[0] == "1"


def _point(person: PersonState) -> shapely.Point:
    return shapely.Point(*person.position)


def test_start_failure_is_a_simulation_error(tmp_path: Path,
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    from sse_cosim.world import sumo as sumo_module

    def refuse(args: list[str]) -> None:
        raise sumo_module.libsumo.TraCIException("cannot load")

    sc = scenario("s1_no_pedestrian")
    monkeypatch.setattr(sumo_module.libsumo, "start", refuse)
    world = sumo_module.SumoWorld(sc, tmp_path, "s1_no_pedestrian")
    with pytest.raises(SimulationError, match="SUMO did not start: cannot load"), world:
        pass
    monkeypatch.undo()
    with sumo_module.SumoWorld(sc, tmp_path, "s1_no_pedestrian") as world:  # nothing left open
        assert world.step().time == 0.0

"""The bounded-acceleration model: its travel-time bound, its earliest arrival on constructed
geometry (against the fastest admissible walks), the velocity a node estimates over time, and
that the truth stays inside."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import shapely
import shapely.ops

from sse_cosim.control.picture import FAN, ConflictZone, Source, _arrivals
from sse_cosim.estimation.motion import Separation, bounded_acceleration, motion_model
from sse_cosim.estimation.observer import NodeObserver
from sse_cosim.estimation.settings import EstimatorSettings
from sse_cosim.regions import PolygonRegion as R
from sse_cosim.regions import kind
from sse_cosim.scenario.model import Estimator
from sse_cosim.sets import Strips, Zonotope

K = kind("polygon")

DT = 0.1
V_MAX, A_MAX = 2.5, 3.2


def model(jitter: float = 0.0):
    return motion_model(Estimator(state_model="bounded-acceleration", position_jitter_m=jitter,
                                  max_pedestrian_speed_mps=V_MAX,
                                  max_pedestrian_accel_mps2=A_MAX), DT)


def state(position, velocity, position_half: float = 0.0, velocity_half: float = 0.0):
    """A box state set around (position, velocity) (4-D)."""
    halves = [position_half] * 2 + [velocity_half] * 2
    return Zonotope(np.array([*position, *velocity], dtype=float), np.diag(halves))


def test_travel_time_is_the_inverse_of_the_farthest_distance():
    m = model()
    rng = np.random.default_rng(1)
    gaps = rng.uniform(0.0, 12.0, 500)
    toward = rng.uniform(-V_MAX, V_MAX, 500)
    times = m.travel_time(gaps, toward)
    assert np.allclose(m.distance_within(times, toward), gaps, rtol=0, atol=1e-9)
    # standing: sqrt(2 d / a) while speeding up; at v_max from the start: d / v_max
    assert m.travel_time(np.array([0.5]), np.array([0.0]))[0] == pytest.approx(
        math.sqrt(2 * 0.5 / A_MAX))
    assert m.travel_time(np.array([3.0]), np.array([V_MAX]))[0] == pytest.approx(3.0 / V_MAX)
    assert m.travel_time(np.array([0.0]), np.array([-2.0]))[0] == 0.0


def fastest_arrival_steps(start, velocity, zone: shapely.Geometry, steps: int = 200) -> int:
    """Steps until a discrete walk of the model (mean velocity per step within v_max, changing
    by at most a_max dt a step, the first one ``velocity``) that steers at full acceleration
    toward the zone's nearest point first puts its path in the zone."""
    s, v = np.array(start, dtype=float), np.array(velocity, dtype=float)
    for k in range(steps):
        if zone.intersects(shapely.Point(s)):
            return k
        s = s + DT * v  # v_k is the mean velocity of step k: it moves first
        target = np.array(shapely.get_coordinates(
            shapely.ops.nearest_points(zone, shapely.Point(s))[0])[0])
        wanted = (target - s) / max(np.linalg.norm(target - s), 1e-12) * V_MAX
        change = wanted - v
        norm = np.linalg.norm(change)
        if norm > A_MAX * DT:
            change *= A_MAX * DT / norm
        v = v + change
    return steps


@pytest.mark.parametrize("seed", range(6))
def test_the_arrival_is_never_later_than_a_fastest_walk(seed):
    """Random zones, positions and velocities: a walk that steers at full acceleration toward
    the zone never gets there before the arrival the model gives from a state set holding it
    (jitter 0, the source the walk's start)."""
    m = model()
    rng = np.random.default_rng(seed)
    for _ in range(40):
        zone = shapely.box(*rng.uniform(0, 5, 2), *rng.uniform(6, 9, 2))
        start = rng.uniform(-8, 15, 2)
        if zone.intersects(shapely.Point(start)):
            continue
        speed, angle = rng.uniform(0, V_MAX), rng.uniform(0, 2 * math.pi)
        velocity = speed * np.array([math.cos(angle), math.sin(angle)])
        source = Source(R(shapely.Point(start).buffer(1e-6)), state(start, velocity, 1e-6, 0.05))
        arrival = _arrivals([source], [ConflictZone(R(zone), 0, 0, math.inf)], m, K)[0]
        assert arrival <= fastest_arrival_steps(start, velocity, zone) * DT + 1e-9


def test_standing_or_walking_along_arrives_later_than_running_at_the_zone():
    """A pedestrian 3 m south of a zone: running north at v_max arrives as the speed bound
    says; standing, walking east along the kerb or walking away south it needs longer, in that
    order; without a state it is the speed bound's worst case."""
    m = model(jitter=0.2)
    zone = ConflictZone(R(shapely.box(-5, 0, 5, 3)), 0, 0, math.inf)
    region = R(shapely.Point(0, -3).buffer(0.3))  # 2.7 m from the zone
    def arrival(velocity):
        known = None if velocity is None else state((0, -3), velocity, 0.3, 0.1)
        return _arrivals([Source(region, known)], [zone], m, K)[0]
    worst = (2.7 - 0.4) / V_MAX
    assert arrival(None) == pytest.approx(worst)
    assert arrival((0, V_MAX)) == pytest.approx(worst, abs=1e-9)
    standing, along, away = arrival((0, 0)), arrival((1.5, 0)), arrival((0, -1.5))
    assert worst < along <= standing < away
    assert standing == pytest.approx(m.travel_time(np.array([2.3]), np.array([0.1]))[0])


def test_every_velocity_in_the_set_is_within_its_largest_speed():
    m = model()
    rng = np.random.default_rng(4)
    for _ in range(100):
        z = Zonotope(rng.normal(0, 1, 4), rng.normal(0, 0.7, (4, 5)))
        points = z.center[:, None] + z.generators @ rng.choice([-1.0, 1.0], (5, 200))
        speeds = np.linalg.norm(points[2:], axis=0)  # vertices and others of the set
        assert np.minimum(speeds, V_MAX).max() <= m.largest_speed(z) + 1e-12


def test_a_separation_fan_never_brings_the_arrival_before_the_speed_bound():
    m = model(jitter=0.3)
    directions = FAN
    gaps = np.array([[2.0] * len(directions), [-1.0] * len(directions)])
    arrival = m.earliest_arrival_s(np.array([2.0, 0.0]), state((0, 0), (0, 0), 0.1, 0.1),
                                   Separation(directions, gaps))
    assert arrival[1] == 0.0
    assert arrival[0] >= (2.0 - 0.6) / V_MAX


def admissible_walk(rng: np.random.Generator, steps: int) -> tuple[np.ndarray, np.ndarray]:
    """A random path of the model: positions s (steps + 1, 2) and mean velocities v (steps, 2),
    v_k = (s_{k+1} - s_k) / dt, ||v|| <= v_max, ||v_{k+1} - v_k|| <= a_max dt."""
    velocity = np.zeros((steps, 2))
    velocity[0] = rng.uniform(-1, 1, 2)
    for k in range(1, steps):
        change = rng.normal(0, 1, 2)
        change *= rng.uniform(0, A_MAX * DT) / np.linalg.norm(change)
        proposed = velocity[k - 1] + change
        velocity[k] = proposed if np.linalg.norm(proposed) <= V_MAX else velocity[k - 1]
    positions = np.vstack([np.zeros(2), np.cumsum(velocity * DT, axis=0)])
    return positions, velocity


def in_disc(rng: np.random.Generator, radius: float) -> np.ndarray:
    angle = rng.uniform(0, 2 * math.pi)
    return radius * math.sqrt(rng.uniform()) * np.array([math.cos(angle), math.sin(angle)])


@pytest.mark.parametrize("seed", range(4))
def test_a_nodes_state_set_holds_the_true_position_and_velocity(seed):
    """Random admissible walks, jitter within eps, two random strips a step within r: at every
    step the node's set (its velocity windows included) holds (s_k, v_k)."""
    rng = np.random.default_rng(seed)
    eps, r = 0.2, 0.15
    m = model(jitter=eps)
    node = NodeObserver("n", m, EstimatorSettings("enclose", "girard", 8))
    positions, velocity = admissible_walk(rng, 80)
    for k in range(80):
        seen = positions[k] + in_disc(rng, eps)
        angle = rng.uniform(0, math.pi)
        normals = np.array([[math.cos(angle), math.sin(angle)],
                            [-math.sin(angle), math.cos(angle)]])
        values = normals @ seen + rng.uniform(-r, r, 2)
        estimate = node.step(k, {"p": {"s": Strips(normals, values, np.full(2, r))}})["p"].estimate
        assert estimate.contains(np.concatenate([positions[k], velocity[k]]), tol=1e-7), k


def test_velocity_windows_bring_the_velocity_below_the_speed_bound():
    """Strips of r = 20 cm, no jitter, walking east at 1.5 m/s: from the third to the sixth
    second the node knows the velocity within 1.8 m/s on average (the windows' best,
    2 sqrt(r a_max), is 1.6 m/s), narrower than each step's correction alone keeps it (2.2),
    and the truth stays inside."""
    m = model()
    windows = NodeObserver("n", m, EstimatorSettings("enclose", "girard", 8))
    alone = NodeObserver("n", dataclasses.replace(m, velocity_windows=()),
                         EstimatorSettings("enclose", "girard", 8))
    rng = np.random.default_rng(0)
    known, plain = [], []
    for k in range(60):
        strips = Strips(np.eye(2), np.array([0.15 * k, 0.0]) + rng.uniform(-0.2, 0.2, 2),
                        np.full(2, 0.2))
        with_windows = windows.step(k, {"p": {"s": strips}})["p"].estimate
        assert with_windows.contains(np.array([0.15 * k, 0.0, 1.5, 0.0]), tol=1e-7)
        if k >= 30:
            known.append(np.abs(with_windows.generators[2:]).sum(axis=1).max())
            plain.append(np.abs(alone.step(k, {"p": {"s": strips}})["p"].estimate
                                .generators[2:]).sum(axis=1).max())
        else:
            alone.step(k, {"p": {"s": strips}})
    assert np.mean(known) < 1.85
    assert np.mean(known) < np.mean(plain) - 0.3


def test_the_reach_from_a_state_set_grows_from_its_speed():
    """From standstill a path moves a_max t² / 2 in t until v_max: 0.4 m in 0.5 s (5 steps),
    against the speed bound's 1.25 m; walking at 1.5 m/s (bounded from above through a fan of
    directions: 1.5 / cos(pi / 32)), it speeds up to v_max and keeps it; unknown, 1.25 m."""
    m = model()
    assert m.reach_m(5, state((0, 0), (0, 0))) == pytest.approx(0.4)
    u = 1.5 / math.cos(math.pi / 32)
    ramp = (V_MAX - u) / A_MAX
    assert m.reach_m(5, state((0, 0), (1.5, 0))) == pytest.approx(
        u * ramp + 0.5 * A_MAX * ramp**2 + V_MAX * (0.5 - ramp))
    assert m.reach_m(5) == pytest.approx(V_MAX * 0.5)


def test_an_unseen_track_grows_in_position_by_the_speed_bound_a_step() -> None:
    """A 4-D track nobody sees, predicted, cut by the speed bound and reduced for 30 steps:
    its position half-width grows by v_max dt a step (2 + 0.25 * 30 = 9.5 m) and its velocity
    stays within the bound. A volume-minimising cut of the whole state gives 24.4 m: it
    narrows the velocity by widening the position (why it never flagged the shrunk car)."""
    model = bounded_acceleration.build(Estimator(state_model="bounded-acceleration"), 0.1, 0.0)
    estimate = Zonotope(np.zeros(4), np.diag([2.0, 2.0, 2.5, 2.5]))
    for _ in range(30):
        estimate = model.bound_state(model.predict(estimate)).reduce(8, "girard")
    half_widths = np.abs(estimate.generators).sum(axis=1)
    assert half_widths[:2] == pytest.approx([9.5, 9.5], rel=1e-9)
    assert half_widths[2:] == pytest.approx([2.5, 2.5], rel=1e-9)

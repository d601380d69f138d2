"""The recorder's soundness check is independent of the estimator: it recomputes each position
set from the state estimate's own arrays and tests the arrays it writes, never the estimator's
memo (``MotionModel.position``). A recorder fed by hand (no SUMO) with a broken memo."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import shapely

from sse_cosim.control.speed import SpeedLevel
from sse_cosim.estimation.motion import MotionModel, motion_model
from sse_cosim.estimation.observer import Track
from sse_cosim.memo import IdentityMemo
from sse_cosim.pipeline.result import StepResult
from sse_cosim.regions import kind
from sse_cosim.reporting.recorder import (
    CONTAINMENT_TOL_M,
    RunRecorder,
    position_arrays,
    zonotope_2d_contains,
)
from sse_cosim.scenario.loader import load_scenario
from sse_cosim.scenario.model import Estimator, Scenario
from sse_cosim.sets import Zonotope
from sse_cosim.world.snapshot import PersonState

K = kind("polygon")

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "s3_pedestrian.toml"
PEDESTRIAN, NODE = "pedestrian", "rsu1"


def scripted_step(step: int, truth: tuple[float, float], estimate: Zonotope,
                  model: MotionModel) -> StepResult:
    """One step in which ``NODE`` tracks the pedestrian (true position ``truth``) with the state
    set ``estimate`` and the bus fuses that set alone; the bus far from it, nothing else."""
    footprint = SimpleNamespace(front=SimpleNamespace(x=100.0, y=-1.75),
                                polygon=lambda: shapely.box(88.0, -3.0, 100.0, -0.5))
    bus = SimpleNamespace(id="bus", kind="bus", speed=10.0, footprint=footprint)
    person = PersonState(PEDESTRIAN, tuple(truth), speed=1.0, heading=0.0)
    snapshot = SimpleNamespace(time=0.1 * step, persons={PEDESTRIAN: person},
                               vehicles={"bus": bus})
    flags = SimpleNamespace(sensors={}, nodes={}, inconsistent=False)
    ego = SimpleNamespace(
        vehicle="bus", shared=SimpleNamespace(ages={}),
        estimate=SimpleNamespace(fused={PEDESTRIAN: estimate},
                                 inputs={PEDESTRIAN: {NODE: estimate}}, flags=flags),
        possible={}, unobserved=K.empty(), window=K.empty(),
        picture=SimpleNamespace(path_clear=True, zones=(), unresolved_occluded_m2=0.0,
                                own_occluded_m2=0.0, distance_to_crossing=90.0, light=None),
        decision=SimpleNamespace(command_mps=10.0, level=SpeedLevel.NOMINAL))
    track = Track(PEDESTRIAN, estimate, step, detected=True)
    return StepResult(step=step, snapshot=snapshot, observations={},  # type: ignore[arg-type]
                      tracks={NODE: {PEDESTRIAN: track}}, model=model, faults={},
                      vehicles={"bus": ego})  # type: ignore[dict-item]


def run_recorder(scenario: Scenario, model: MotionModel,
                 steps: list[tuple[tuple[float, float], Zonotope]]) -> RunRecorder:
    """A recorder after ``steps`` (truth, estimate), one every 0.1 s."""
    recorder = RunRecorder(scenario)
    for i, (truth, estimate) in enumerate(steps):
        recorder(scripted_step(i, truth, estimate, model))
    return recorder


def break_memo(monkeypatch: pytest.MonkeyPatch, memo: IdentityMemo,
               wrong: Callable[[Zonotope, list[Zonotope]], Zonotope]) -> None:
    """Make ``memo`` serve ``wrong(right result, results computed so far)``."""
    computed: list[Zonotope] = []

    def get(key: object, inputs: tuple[object, ...], compute: Callable[[], Zonotope]):
        computed.append(compute())
        return wrong(computed[-1], computed)

    monkeypatch.setattr(memo, "get", get)


@pytest.fixture
def scenario_and_model() -> tuple[Scenario, MotionModel]:
    scenario = load_scenario(SCENARIO, {"estimator.position_jitter_m": 0.646})  # the road's
    return scenario, motion_model(scenario.estimator,
                                  scenario.simulation.step_length_s)


SEEN = Zonotope(np.array([183.0, -7.0]), 0.5 * np.eye(2))
LOST = SEEN.translate([30.0, 0.0])  # the estimator lost the pedestrian: its set is 30 m off


def test_a_stale_memo_entry_does_not_hide_a_set_that_lost_its_pedestrian(
        monkeypatch, scenario_and_model):
    """The memo serves the first position set it computed for every estimate (a stale entry):
    the lost set at the second step would pass as the first one, which still holds the
    pedestrian. The recorder reads the lost estimate's own arrays: two violations."""
    scenario, model = scenario_and_model
    break_memo(monkeypatch, model._positions, lambda right, computed: computed[0])
    model.position(SEEN)  # as the estimator asks at the first step
    assert model.position(LOST).center.tolist() == [183.0, -7.0]  # the memo is broken
    recorder = run_recorder(scenario, model, [((183.0, -7.0), SEEN), ((183.1, -7.0), LOST)])
    summary = recorder.summary()
    assert summary["containment_violations"] == 2
    assert summary["containment_violations_by_set"] == {NODE: 1, "fused": 1}
    assert {(v["t"], v["node"]) for v in summary["violations"]} == {(0.1, NODE), (0.1, "fused")}
    written = [line for line in recorder.set_lines if line["t"] == 0.1]
    assert [line["kind"] for line in written] == ["local", "fused"]
    jitter = scenario.estimator.position_jitter_m
    for line in written:  # what is written is what was checked: the lost set, with its box
        assert line["center"] == [213.0, -7.0]
        assert line["generators"] == [[0.5, 0.0, jitter, 0.0], [0.0, 0.5, 0.0, jitter]]
        assert not Zonotope.from_json(line).contains(np.array([183.1, -7.0]), tol=1e-7)


def test_a_memo_serving_sets_far_away_finds_no_violation_in_sound_sets(
        monkeypatch, scenario_and_model):
    """The memo shifts every position set 50 m: the estimates still hold the pedestrian, and
    the recorder, reading them, reports no violation and writes their true sets."""
    scenario, model = scenario_and_model
    break_memo(monkeypatch, model._positions, lambda right, _: right.translate([50.0, 0.0]))
    recorder = run_recorder(scenario, model, [((183.0, -7.0), SEEN), ((183.1, -7.0), SEEN)])
    assert recorder.summary()["containment_violations"] == 0
    assert {tuple(line["center"]) for line in recorder.set_lines} == {(183.0, -7.0)}


def test_without_a_broken_memo_the_lost_set_is_a_violation_all_the_same(scenario_and_model):
    scenario, model = scenario_and_model
    recorder = run_recorder(scenario, model, [((183.0, -7.0), SEEN), ((183.1, -7.0), LOST)])
    assert recorder.summary()["containment_violations_by_set"] == {NODE: 1, "fused": 1}


@pytest.mark.parametrize("state_model", ["position", "constant-velocity"])
@pytest.mark.parametrize("jitter", [0.0, 0.3])
def test_the_checked_arrays_are_the_estimators_claim(state_model, jitter):
    """C Z ⊕ box(jitter) from the estimate's arrays: the values of ``MotionModel.position``,
    for either state layout, with every zero written as 0.0."""
    model = motion_model(Estimator(state_model=state_model, position_jitter_m=jitter),
                         0.1)
    rng = np.random.default_rng(7)
    for _ in range(20):
        generators = rng.normal(size=(model.dim, 5))
        generators[rng.random(generators.shape) < 0.3] = -0.0
        estimate = model.predict(Zonotope(rng.normal(size=model.dim) * 100, generators))
        claimed = model.position(estimate)
        center, generators = position_arrays(estimate.center, estimate.generators, jitter)
        assert center.shape == (2,) and generators.shape == claimed.generators.shape
        assert np.array_equal(center, claimed.center)
        assert np.array_equal(generators, claimed.generators)
        assert not np.signbit(generators[generators == 0.0]).any()


def test_the_recorders_containment_test_agrees_with_the_sets_library_on_sets_with_an_area():
    rng = np.random.default_rng(11)
    for _ in range(200):
        center = rng.normal(size=2) * 100
        generators = rng.normal(size=(2, int(rng.integers(2, 8))))
        zonotope = Zonotope(center, generators)
        points = center + (generators @ rng.uniform(-1.1, 1.1, size=(generators.shape[1], 8))).T
        expected = zonotope.contains(points, tol=CONTAINMENT_TOL_M)
        got = [zonotope_2d_contains(center, generators, p, CONTAINMENT_TOL_M) for p in points]
        assert got == expected.tolist()


def test_the_recorders_containment_test_bounds_flat_sets_and_points():
    center = np.array([10.0, 5.0])

    def inside(generators: list[list[float]], dx: float, dy: float) -> bool:
        shape = (2, len(generators[0])) if generators else (2, 0)
        return zonotope_2d_contains(center, np.array(generators).reshape(shape),
                                    center + np.array([dx, dy]), CONTAINMENT_TOL_M)

    segment = [[1.0], [1.0]]
    assert inside(segment, 0.5, 0.5)
    assert not inside(segment, 2.0, 2.0) and not inside(segment, 0.5, 0.6)
    thin = [[1.0, 1.0], [0.0, 1e-12]]  # nearly a segment along x, 4 m long
    assert inside(thin, 1.9, 0.0) and not inside(thin, 5.0, 0.0)
    assert inside([[0.0], [0.0]], 5e-8, -5e-8)  # a point
    tiny = [[1.0, 0.0, 5.6e-163, -6.2e-179], [0.0, 1.0, 2.2e-162, -2.5e-178]]  # squares underflow
    assert inside(tiny, 0.9, -0.9) and not inside(tiny, 1.1, 0.0)
    assert not inside([[0.0], [0.0]], 1e-6, 0.0) and not inside([], 0.0, 1e-6)

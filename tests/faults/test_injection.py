"""Fault injection, the fault log, the controller's fallback and the faults schema."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import shapely

from sse_cosim.control.speed import SpeedLevel, fallback_floor
from sse_cosim.errors import UserError
from sse_cosim.estimation.motion import motion_model
from sse_cosim.regions import PolygonRegion as R
from sse_cosim.regions import kind as region_kind
from sse_cosim.scenario.loader import load_scenario
from sse_cosim.scenario.model import Controller
from sse_cosim.sensors import SensorObservation, measure, specs_from_scenario
from sse_cosim.sensors.faults import FaultInjector, FaultLog, FaultStatus, is_active
from sse_cosim.sets import Zonotope
from sse_cosim.world.snapshot import PersonState, Pose, Snapshot

K = region_kind("polygon")

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"
TRUTH = np.array([200.0, -5.0])
POSE = Pose(212.0, -9.5, np.radians(165.0))


def scenario(**faults):
    """S3 with dotted fault overrides, e.g. ``{"faults.sensor.f.kind": "stuck"}``; a fault study
    that declares the assumptions its faults break."""
    declared = {"breaks_assumptions": ["sensor_bounds", "shared_estimates"]}
    return load_scenario(SCENARIOS / "s3_pedestrian.toml", declared | faults)


def sensor_fault(kind: str, **fields) -> dict:
    base = {"faults.sensor.f.sensor": "rsu1_cam", "faults.sensor.f.kind": kind,
            "faults.sensor.f.start_s": 1.0, "faults.sensor.f.end_s": 3.0}
    return base | {f"faults.sensor.f.{k}": v for k, v in fields.items()}


def observe_at(time: float, truth=TRUTH, seed: int = 0):
    """(snapshot, observations): only rsu1's camera, seeing the pedestrian at ``truth``."""
    snap = Snapshot(time, {}, {"pedestrian": PersonState("pedestrian", tuple(truth), 1.2)})
    strips = measure(POSE, truth[np.newaxis], np.array([1.0, 1.0]), "uniform",
                     np.random.default_rng(seed))[0]
    from sse_cosim.sensors.measurement import Detection

    detection = Detection("rsu1_cam", "rsu1", time, "pedestrian", strips)
    view = R(shapely.box(190, -15, 215, 0))
    obs = SensorObservation("rsu1_cam", "rsu1", time, POSE, {"pedestrian": detection}, view,
                            K.empty())
    return snap, {"rsu1_cam": obs}


def injector(sc, seed: int = 0) -> FaultInjector:
    return FaultInjector(sc, specs_from_scenario(sc), np.random.default_rng(seed))


def corrupt(inj: FaultInjector, time: float, truth=TRUTH):
    """(observation before, after the faults, the fault's status) at ``time``."""
    inj.begin_step(time)
    snap, obs = observe_at(time, truth)
    after = inj.corrupt_observations(snap, obs, K)["rsu1_cam"]
    return obs["rsu1_cam"], after, inj.statuses()["sensor.f"]


def test_window_is_start_inclusive_end_exclusive():
    fault = scenario(**sensor_fault("stuck")).faults.sensor["f"]
    assert [is_active(fault, t) for t in (0.9, 1.0, 2.9, 3.0)] == [False, True, True, False]


def test_bias_moves_the_strips_along_the_sensor_axes_and_breaks_the_bound():
    inj = injector(scenario(**sensor_fault("bias", bias_m=[3.0, -1.0])))
    before, after, status = corrupt(inj, 1.5)
    shift = (after.detections["pedestrian"].strips.values
             - before.detections["pedestrian"].strips.values)
    assert np.allclose(shift, [3.0, -1.0]) and status == FaultStatus(True, True)
    plain, untouched, idle = corrupt(inj, 3.5)
    assert untouched is plain and not idle.active


def test_a_bias_within_the_bound_keeps_the_truth_in_every_strip():
    inj = injector(scenario(**sensor_fault("bias", bias_m=[0.9, 0.9], within_bound=True)))
    for t in np.arange(1.0, 3.0, 0.1):
        _, after, status = corrupt(inj, t, TRUTH + np.array([t, 0.0]))
        assert after.detections["pedestrian"].strips.contains(TRUTH + np.array([t, 0.0]))
        assert status == FaultStatus(True, False)


def test_stuck_repeats_the_first_detection_while_the_pedestrian_walks_away():
    inj = injector(scenario(**sensor_fault("stuck")))
    _, first, _ = corrupt(inj, 1.0)
    _, later, status = corrupt(inj, 2.5, TRUTH + np.array([3.0, 0.0]))
    assert np.array_equal(later.detections["pedestrian"].strips.values,
                          first.detections["pedestrian"].strips.values)
    assert status.beyond_bounds  # 3 m away from a 1 m strip


def test_dropout_loses_whole_frames_at_the_given_rate_reproducibly():
    sc = scenario(**sensor_fault("dropout", dropout_probability=0.5, end_s=100.0))
    runs = []
    for _ in range(2):
        inj = injector(sc, seed=3)
        runs.append([not corrupt(inj, 1.0 + k * 0.1)[1].detections for k in range(400)])
    assert runs[0] == runs[1] and 0.4 < np.mean(runs[0]) < 0.6
    inj = injector(sc, seed=3)
    while (lost := corrupt(inj, 1.0)[1]).detections:
        pass
    assert lost.visible.is_empty and lost.occluded.area > 0  # nothing seen, nothing claimed


def test_phantom_follows_its_track_under_its_own_id():
    fault = sensor_fault("phantom", phantom_xy_m=[201.0, -3.0], phantom_velocity_mps=[0.0, 1.0])
    inj = injector(scenario(**fault))
    _, after, status = corrupt(inj, 2.0)
    ghost = after.detections["phantom"].strips
    assert ghost.contains(np.array([201.0, -2.0])) and "pedestrian" in after.detections
    assert status.beyond_bounds


def test_node_faults_shift_or_shrink_what_the_node_sends():
    model = motion_model(
        scenario().estimator.model_copy(update={"position_jitter_m": 0.646}), 0.1)  # the road's
    estimate = {"pedestrian": Zonotope(TRUTH, np.eye(2))}
    snap, _ = observe_at(4.0)
    for kind, field, value in (("shift", "shift_m", [4.0, 0.0]), ("shrink", "scale", 0.5)):
        sc = scenario(**{"faults.node.n.node": "rsu2", "faults.node.n.kind": kind,
                         f"faults.node.n.{field}": value})
        inj = injector(sc)
        inj.begin_step(4.0)
        sent = inj.corrupt_estimates("rsu2", estimate, snap, model)["pedestrian"]
        expected = (Zonotope(TRUTH + np.array([4.0, 0.0]), np.eye(2)) if kind == "shift"
                    else Zonotope(TRUTH, 0.5 * np.eye(2)))
        assert np.allclose(sent.center, expected.center)
        assert np.allclose(sent.generators, expected.generators)
        assert inj.corrupt_estimates("rsu1", estimate, snap, model) == estimate
        assert inj.statuses()["node.n"].beyond_bounds == (kind == "shift")


def test_link_faults_lose_or_delay_messages_in_their_window():
    sc = scenario(**{"faults.link.a.node": "rsu1", "faults.link.a.kind": "loss",
                     "faults.link.a.start_s": 1.0, "faults.link.a.end_s": 2.0,
                     "faults.link.b.node": "rsu2", "faults.link.b.kind": "latency",
                     "faults.link.b.extra_latency_steps": 4})
    inj = injector(sc)
    inj.begin_step(1.5)
    assert inj.link_lost("rsu1") and not inj.link_lost("rsu2")
    assert inj.extra_latency("rsu2") == 4 and inj.extra_latency("rsu1") == 0
    inj.begin_step(2.0)
    assert not inj.link_lost("rsu1")


def test_fault_log_measures_the_delay_from_the_first_active_step():
    log = FaultLog(scenario(**sensor_fault("bias", bias_m=[5.0, 0.0])))
    for step in range(40):
        t = step * 0.1
        active = is_active(log.scenario.faults.sensor["f"], t)
        status = {"sensor.f": FaultStatus(active, active)}
        log.update(step, t, status, {"rsu1_cam": step >= 12}, {"rsu1": ""}, {})
    entry = log.summary()[0]
    assert entry["first_active_step"] == 10 and entry["detected_step"] == 12
    assert entry["detection_delay_steps"] == 2 and entry["flagged_steps"] == 18


def test_fallback_floor_applies_only_while_inconsistent():
    config = Controller()
    assert fallback_floor(False, config) is SpeedLevel.NOMINAL
    assert fallback_floor(True, config) is SpeedLevel.SLOW
    assert fallback_floor(True, Controller(inconsistent_level="very slow")) is SpeedLevel.VERY_SLOW


@pytest.mark.parametrize(("overrides", "field", "words"), [
    ({"faults.sensor.f.sensor": "radar", "faults.sensor.f.kind": "stuck"},
     "faults.sensor.f.sensor", "no sensor 'radar'"),
    ({"faults.sensor.f.sensor": "rsu1_cam", "faults.sensor.f.kind": "bias"},
     "faults.sensor.f.bias_m", "non-zero"),
    ({"faults.sensor.f.sensor": "rsu1_cam", "faults.sensor.f.kind": "stuck",
      "faults.sensor.f.bias_m": [1.0, 0.0]}, "faults.sensor.f.bias_m", "only used with"),
    ({"faults.node.n.node": "bus", "faults.node.n.kind": "shrink"}, "faults.node.n.node",
     "sends to an automated vehicle"),
    ({"faults.link.l.node": "rsu1", "faults.link.l.kind": "loss", "faults.link.l.start_s": 5.0,
      "faults.link.l.end_s": 4.0}, "faults.link.l.end_s", "later than start_s"),
])
def test_bad_faults_are_one_line_errors_naming_the_field(overrides, field, words):
    with pytest.raises(UserError) as info:
        scenario(**overrides)
    assert field in str(info.value) and words in str(info.value)

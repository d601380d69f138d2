"""Sensor kinds: the registry, the camera behind the interface, the range sensor's sound strips,
its field of view and occlusion, the schema's kind fields, and faults on a range sensor."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sensors_scene import RSU1, SETTINGS, bus, snapshot, truck

from sse_cosim.cli.main import main
from sse_cosim.errors import UserError
from sse_cosim.regions import kind
from sse_cosim.scenario.loader import load_scenario, validate_scenario
from sse_cosim.scenario.model import Scenario
from sse_cosim.sensors import Camera, RangeBearing, SensorSpec, measure, observe
from sse_cosim.sensors.faults import FaultInjector
from sse_cosim.sensors.kinds import CONFIGS, CameraConfig, RangeConfig
from sse_cosim.sensors.kinds.range_bearing import range_bearing_strips
from sse_cosim.world.snapshot import Pose

K = kind("polygon")

ROOT = Path(__file__).resolve().parents[2]
TOL = 1e-9  # m: the strips hold the truth up to rounding
S1 = ROOT / "scenarios" / "s1_pedestrian.toml"
LIDAR = {"kind": "range", "node": "bus", "range_m": 40.0, "range_bound_m": 0.2,
         "bearing_bound_deg": 2.0}


def test_every_registered_kind_builds_a_sensor_kind():
    assert list(CONFIGS) == ["camera", "range"]
    for name, config in CONFIGS.items():
        fields = {"kind": name, "node": "bus"}
        kind = config.model_validate(fields).build()
        assert kind.fov_rad > 0 and kind.range_m > 0
        strips = kind.measure(Pose(0.0, 0.0, 0.3), np.array([[5.0, 1.0]]), np.random.default_rng(1))
        assert len(strips) == 1 and strips[0].contains(np.array([5.0, 1.0]), tol=TOL)


@pytest.mark.parametrize("noise", ["uniform", "worst-case"])
def test_the_camera_draws_what_the_sector_measurement_drew(noise):
    """Same strips from the same generator: the camera kind is the former sector sensor."""
    pose, truth = Pose(3.0, -2.0, 0.7), np.array([[10.0, 1.0], [4.0, 5.0]])
    camera = Camera(math.radians(90), 60.0, (0.4, 0.9), noise)
    got = camera.measure(pose, truth, np.random.default_rng(5))
    want = measure(pose, truth, np.array([0.4, 0.9]), noise, np.random.default_rng(5))
    for a, b in zip(got, want, strict=True):
        assert np.array_equal(a.normals, b.normals) and np.array_equal(a.values, b.values)
        assert np.array_equal(a.radii, b.radii)


unit = st.floats(-1.0, 1.0)
extreme = st.sampled_from([-1.0, 1.0])


@pytest.mark.kernels
@settings(SETTINGS, max_examples=600)
@given(
    origin=st.tuples(st.floats(-300, 300), st.floats(-300, 300)),
    rho=st.floats(0.0, 120.0),
    theta=st.floats(-math.pi, math.pi),
    r=st.floats(0.01, 3.0),
    delta_deg=st.floats(0.01, 89.0),
    noise=st.tuples(unit | extreme, unit | extreme),
)
def test_range_strips_hold_the_truth(origin, rho, theta, r, delta_deg, noise):
    """For any position and any noise within the bounds, the extremes included, the true
    position lies in both strips."""
    delta = math.radians(delta_deg)
    s = np.array(origin)
    truth = s + rho * np.array([math.cos(theta), math.sin(theta)])
    measured_rho = rho + noise[0] * r
    measured_theta = theta + noise[1] * delta
    strips = range_bearing_strips(s, np.array([measured_rho]), np.array([measured_theta]), r,
                                  delta)[0]
    assert np.all(strips.radii > 0)
    assert strips.contains(truth, tol=TOL * (1.0 + float(np.abs(s).max()) + rho))


@pytest.mark.kernels
def test_range_strips_are_tight():
    """The ring sector's extreme points lie on the strips' edges (r = 0.5 m, δ = 10°)."""
    r, delta, rho_m = 0.5, math.radians(10.0), 20.0
    strips = range_bearing_strips(np.zeros(2), np.array([rho_m]), np.array([0.0]), r, delta)[0]
    lo, hi = strips.values - strips.radii, strips.values + strips.radii
    assert lo[0] == pytest.approx((rho_m - r) * math.cos(delta))
    assert hi[0] == pytest.approx(rho_m + r)
    assert hi[1] == pytest.approx((rho_m + r) * math.sin(delta)) and lo[1] == -hi[1]


@pytest.mark.kernels
@pytest.mark.parametrize("noise", ["uniform", "worst-case"])
def test_range_measurements_hold_the_truth_and_repeat_with_the_seed(noise):
    lidar = RangeBearing(30.0, 0.3, math.radians(3.0), noise)
    pose = Pose(5.0, 5.0, 1.0)
    rng = np.random.default_rng(9)
    truth = pose.position + rng.uniform(-20, 20, (200, 2))  # (200, 2), all around
    strips = lidar.measure(pose, truth, np.random.default_rng(2))
    again = lidar.measure(pose, truth, np.random.default_rng(2))
    assert all(s.contains(p, tol=TOL * 100) for s, p in zip(strips, truth, strict=True))
    assert all(np.array_equal(a.values, b.values) for a, b in zip(strips, again, strict=True))
    assert lidar.measure(pose, np.zeros((0, 2)), rng) == []


@pytest.mark.kernels
def test_a_range_sensor_sees_all_around_but_not_behind_the_truck():
    """On a unit beside the road: the pedestrian behind it (west) is seen, the one hidden by
    the parked truck is not, and one beyond its reach is not."""
    lidar = SensorSpec("lidar", "rsu1", RangeBearing(range_m=40.0), static_pose=RSU1)
    persons = {"west": (200.0, -9.5), "hidden": (182.0, -3.0), "far": (255.0, -9.5)}
    obs = observe(snapshot([truck(), bus(100.0)], persons), {"lidar": lidar},
                  np.random.default_rng(0), regions=K)["lidar"]
    assert set(obs.detections) == {"west"}
    disc = math.pi * 40.0**2
    assert obs.visible.area + obs.occluded.area == pytest.approx(disc, rel=2e-3)
    assert obs.occluded.area > 1.0


def scenario_with(sensor: dict) -> Scenario:
    data = {"name": "t", "automated": {"bus": {}}, "sensors": {"s": sensor}}
    return validate_scenario(data, "t.toml")


def test_kind_defaults_to_camera_and_range_fields_are_validated():
    assert isinstance(scenario_with({"node": "bus"}).sensors["s"], CameraConfig)
    lidar = scenario_with(LIDAR).sensors["s"]
    assert isinstance(lidar, RangeConfig)
    assert lidar.build() == RangeBearing(40.0, 0.2, math.radians(2.0), "uniform")


@pytest.mark.parametrize(("sensor", "words"), [
    ({"node": "bus", "range_bound_m": 0.2},
     "sensors.s.range_bound_m: only used with kind = 'range'"),
    ({**LIDAR, "fov_deg": 90.0}, "sensors.s.fov_deg: only used with kind = 'camera'"),
    ({**LIDAR, "noise_bound_m": [1.0, 1.0]}, "sensors.s.noise_bound_m: only used with kind"),
    ({"node": "bus", "kind": "sonar"}, "sensors.s.kind: unknown sensor kind 'sonar'; use one"),
    ({**LIDAR, "bearing_bound_deg": 90.0}, "sensors.s.bearing_bound_deg: Input should be less"),
    ({**LIDAR, "range_bound_m": 0.0}, "sensors.s.range_bound_m: Input should be greater"),
])
def test_fields_of_another_kind_are_refused_in_one_line(sensor, words):
    with pytest.raises(UserError) as error:
        scenario_with(sensor)
    line = str(error.value)
    assert line.startswith("t.toml: sensors.s.") and words in line and "\n" not in line


@pytest.mark.parametrize(("kind", "fields"), [
    ("bias", {"bias_m": [3.0, 0.0]}),
    ("phantom", {"phantom_xy_m": [190.0, -9.0]}),
    ("stuck", {}),
])
def test_sensor_faults_act_on_a_range_sensor(kind, fields):
    """Bias moves the range strips off the truth, a phantom is measured by the range kind,
    stuck repeats the first frame; each breaks the bounds, which the injector reports."""
    overrides = {f"sensors.lidar.{k}": v for k, v in LIDAR.items()} | {
        "breaks_assumptions": ["sensor_bounds"], "faults.sensor.f.sensor": "lidar",
        "faults.sensor.f.kind": kind} | {f"faults.sensor.f.{k}": v for k, v in fields.items()}
    sc = load_scenario(S1, overrides)
    specs = {"lidar": SensorSpec.from_config("lidar", sc.sensors["lidar"])}
    inj = FaultInjector(sc, specs, np.random.default_rng(0))
    broke = []
    for step, x in enumerate((185.0, 188.0)):  # the pedestrian walks; a stuck frame stays
        snap = snapshot([bus(150.0)], {"pedestrian": (x, -5.0)}, time=0.1 * step)
        inj.begin_step(snap.time)
        seen = observe(snap, specs, np.random.default_rng(step))
        out = inj.corrupt_observations(snap, seen)["lidar"].detections
        assert set(out) == {"pedestrian"} | ({"phantom"} if kind == "phantom" else set())
        broke.append(inj.statuses()["sensor.f"].beyond_bounds)
    assert broke[-1]


@pytest.mark.sumo
def test_the_lidar_example_runs_sound_and_safe(tmp_path):
    """examples/s1_lidar.toml in SUMO, up to the pedestrian's first steps on the zebra: the
    pole's lidar sees it from the start, every set holds it, no collision."""
    out = tmp_path / "lidar"
    main(["run", str(ROOT / "examples" / "s1_lidar.toml"), "--out", str(out),
          "--set", "simulation.duration_s=13"])
    summary = json.loads((out / "summary.json").read_text())
    assert summary["first_detection"]["pole"]["t"] == 0.0
    assert summary["containment_violations"] == 0 and summary["collisions"] == 0

"""Scenario files: inheritance, overrides, and one-line errors naming file, field and fix."""

from __future__ import annotations

from pathlib import Path

import pytest

from sse_cosim.errors import UserError
from sse_cosim.scenario.loader import apply_overrides, deep_merge, load_scenario, load_scenario_data
from sse_cosim.scenario.model import present

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"
PAPER_FILES = sorted(p for p in SCENARIOS.glob("s[123]_*.toml"))


def test_six_paper_scenarios_exist_and_validate():
    assert [p.stem for p in PAPER_FILES] == [
        "s1_no_pedestrian", "s1_pedestrian", "s2_no_pedestrian", "s2_pedestrian",
        "s3_no_pedestrian", "s3_pedestrian",
    ]
    for path in PAPER_FILES:
        scenario = load_scenario(path)
        assert scenario.name == path.stem[:2].upper()
        assert bool(present(scenario.pedestrians)) == ("no_pedestrian" not in path.stem)


def test_scenarios_differ_only_in_what_their_files_say():
    s1, s2, s3 = (load_scenario(SCENARIOS / f"s{i}_pedestrian.toml") for i in (1, 2, 3))
    assert s1.node_ids() == ["bus"]
    assert s2.node_ids() == ["bus", "car"]
    assert s3.node_ids() == ["bus", "rsu1", "rsu2"]
    assert s1.automated["bus"] == s2.automated["bus"] == s3.automated["bus"]
    assert s1.sensors["bus_front"] == s3.sensors["bus_front"]


def test_relative_network_folder_is_resolved_from_the_file_that_sets_it():
    scenario = load_scenario(SCENARIOS / "s1_pedestrian.toml")
    assert Path(scenario.network.sources_dir) == (SCENARIOS.parent / "sumo_net").resolve()


def test_deep_merge_merges_tables_and_replaces_values():
    merged = deep_merge({"a": {"x": 1, "y": 2}, "b": [1]}, {"a": {"y": 3}, "b": [2]})
    assert merged == {"a": {"x": 1, "y": 3}, "b": [2]}


def test_overrides_set_dotted_fields():
    data = load_scenario_data(SCENARIOS / "s2_pedestrian.toml")
    data = apply_overrides(data, {"sensors.car_front.noise_bound_m": [2.0, 0.5],
                                  "v2x.latency_steps": 3}, source="test")
    scenario = load_scenario(SCENARIOS / "s2_pedestrian.toml",
                             {"sensors.car_front.noise_bound_m": [2.0, 0.5]})
    assert scenario.sensors["car_front"].noise_bound_m == (2.0, 0.5)
    assert data["v2x"]["latency_steps"] == 3


def _write(tmp_path: Path, text: str, name: str = "bad.toml") -> Path:
    (tmp_path / "base.toml").write_text(
        'name = "B"\n[automated.bus]\n[sensors.front]\nnode = "bus"\n')
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("text", "field", "words"),
    [
        ('name = "x"\n[bus\n', "syntax", "TOML"),
        ('extends = "base.toml"\n[automated.bus]\nnominal_speed = 3\n',
         "automated.bus.nominal_speed", "spelling"),
        ('extends = "base.toml"\n[automated.bus]\nnominal_speed_mps = "fast"\n',
         "automated.bus.nominal_speed_mps", "number"),
        ('extends = "base.toml"\n[sensors.front]\nnoise_bound_m = [0.0, 1.0]\n',
         "sensors.front.noise_bound_m.0", "greater than 0"),
        ('extends = "base.toml"\n[sensors.front]\nfov_deg = 400\n', "sensors.front.fov_deg",
         "360"),
        ('extends = "base.toml"\n[sensors.front]\nrange_m = 0\n', "sensors.front.range_m",
         "greater than 0"),
        ('extends = "base.toml"\n[sensors.side]\nnode = "drone"\n', "sensors.side.node",
         "drone"),
        ('extends = "base.toml"\n[estimator]\ngain_method = "magic"\n',
         "estimator.gain_method", "frobenius"),
        ('extends = "base.toml"\n[estimator]\nposition_jitter_m = inf\n',
         "estimator.position_jitter_m", "finite"),
        ('extends = "base.toml"\n[sensors.front]\nnoise_bound_m = [nan, 1.0]\n',
         "sensors.front.noise_bound_m.0", "finite"),
        ('extends = "missing.toml"\n', "extends", "not found"),
        ('extends = "bad.toml"\n', "extends", "cycle"),
    ],
)
def test_bad_files_give_one_line_errors(tmp_path, text, field, words):
    path = _write(tmp_path, text)
    with pytest.raises(UserError) as info:
        load_scenario(path)
    message = info.value.one_line()
    assert "\n" not in message
    assert str(path.name) in message
    assert field in message
    assert words in message


def test_override_of_an_unknown_table_is_an_error():
    with pytest.raises(UserError, match="no table 'sensor'"):
        load_scenario(SCENARIOS / "s1_pedestrian.toml", {"sensor.bus_front.range_m": 3})


def test_override_of_an_unknown_field_is_an_error():
    with pytest.raises(UserError, match=r"bus\.top_speed"):
        load_scenario(SCENARIOS / "s1_pedestrian.toml", {"automated.bus.top_speed": 3})


# --- breaks_assumptions: a study that breaks an assumption of the estimator says so -------------

S3_FILE = SCENARIOS / "s3_pedestrian.toml"


def _sensor_fault(kind: str, **fields: object) -> dict:
    """Dotted overrides of S3 that add sensor fault ``f`` on rsu1's camera."""
    base = {"faults.sensor.f.sensor": "rsu1_cam", "faults.sensor.f.kind": kind}
    return base | {f"faults.sensor.f.{k}": v for k, v in fields.items()}


NODE_SHRINK = {"faults.node.n.node": "rsu2", "faults.node.n.kind": "shrink"}
NODE_SHIFT = {"faults.node.n.node": "rsu2", "faults.node.n.kind": "shift",
              "faults.node.n.shift_m": [4.0, 0.0]}
BREAKING = [  # overrides, the field refused, the assumption it breaks
    pytest.param({"pedestrians.pedestrian.walking_speed_mps": 2.6},
                 "pedestrians.pedestrian.walking_speed_mps",
                 "pedestrian_speed", id="fast pedestrian"),
    pytest.param(_sensor_fault("bias", bias_m=[3.0, 0.0]), "faults.sensor.f.kind",
                 "sensor_bounds", id="bias"),
    pytest.param(_sensor_fault("stuck"), "faults.sensor.f.kind", "sensor_bounds", id="stuck"),
    pytest.param(_sensor_fault("phantom", phantom_xy_m=[200.0, 0.0]), "faults.sensor.f.kind",
                 "sensor_bounds", id="phantom"),
    pytest.param(NODE_SHRINK, "faults.node.n.kind", "shared_estimates", id="shrink"),
    pytest.param(NODE_SHIFT, "faults.node.n.kind", "shared_estimates", id="shift"),
]


@pytest.mark.parametrize(("overrides", "field", "assumption"), BREAKING)
def test_an_undeclared_broken_assumption_is_refused(overrides, field, assumption):
    with pytest.raises(UserError) as info:
        load_scenario(S3_FILE, overrides)
    assert (info.value.source, info.value.field) == (str(S3_FILE), field)
    assert f'add "{assumption}" to breaks_assumptions' in info.value.problem


@pytest.mark.parametrize(("overrides", "field", "assumption"), BREAKING)
def test_a_declared_broken_assumption_is_accepted(overrides, field, assumption):
    scenario = load_scenario(S3_FILE, {**overrides, "breaks_assumptions": [assumption]})
    assert scenario.breaks_assumptions == [assumption]


def test_the_wrong_declaration_does_not_cover_a_break():
    with pytest.raises(UserError, match="sensor_bounds"):
        load_scenario(S3_FILE, {**_sensor_fault("stuck"),
                                "breaks_assumptions": ["shared_estimates", "pedestrian_speed"]})


@pytest.mark.parametrize("overrides", [
    _sensor_fault("dropout"),
    _sensor_fault("bias", bias_m=[0.8, 0.8], within_bound=True),
    {"faults.link.l.node": "rsu1", "faults.link.l.kind": "loss"},
    {"faults.link.l.node": "rsu1", "faults.link.l.kind": "latency"},
    {"pedestrians.pedestrian.walking_speed_mps": 2.5},  # at the bound
    {"pedestrians.pedestrian.walking_speed_mps": 2.8,
     "pedestrians.pedestrian.present": False},  # nobody walks
], ids=["dropout", "bias within bound", "loss", "latency", "speed at the bound", "no pedestrian"])
def test_what_breaks_nothing_needs_no_declaration(overrides):
    assert load_scenario(S3_FILE, overrides).breaks_assumptions == []


def test_an_unknown_assumption_is_refused():
    with pytest.raises(UserError, match=r"breaks_assumptions\.0: .*'sensor_bounds'"):
        load_scenario(S3_FILE, {"breaks_assumptions": ["sensor_bias"]})


def test_fault_scenarios_declare_what_they_break():
    """Each fault scenario loads, and declares exactly what its faults break."""
    declared = {p.stem: load_scenario(p).breaks_assumptions
                for p in sorted((SCENARIOS / "faults").glob("[!_]*.toml"))}
    assert declared == {
        "s1_bias_bus": ["sensor_bounds"], "s2_shrink_car": ["shared_estimates"],
        "s3_bias_rsu1_second_camera": ["sensor_bounds"], "s3_bias_within_bound": [],
        "s3_dropout_rsu2": [], "s3_latency_rsu1": [], "s3_loss_rsu1": [],
        "s3_phantom_rsu1": ["sensor_bounds"], "s3_shift_rsu2": ["shared_estimates"],
        "s3_stuck_rsu1": ["sensor_bounds"],
    }

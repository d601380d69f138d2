"""The motion model's seam: every registered model's reach and earliest arrival, the schema's
names, and a model registered by one entry in ``MODELS`` reaching every layer."""

from __future__ import annotations

import dataclasses
import typing

import numpy as np
import pytest
import shapely
from pydantic import ValidationError

from sse_cosim.control.picture import ConflictZone, Source, _arrivals
from sse_cosim.estimation.motion import MODELS, LinearModel, Separation, motion_model
from sse_cosim.estimation.occupancy import UnobservedArea
from sse_cosim.regions import PolygonRegion as R
from sse_cosim.regions import kind
from sse_cosim.scenario.model import Estimator
from sse_cosim.sets import Zonotope

K = kind("polygon")

DT = 0.1
SPEED, JITTER = 2.5, 0.3


def config(state_model: str) -> Estimator:
    """Settings naming ``state_model`` (not validated: a model registered by a test is not in
    the schema, which reads the registry once, at import)."""
    return Estimator(max_pedestrian_speed_mps=SPEED, position_jitter_m=JITTER).model_copy(
        update={"state_model": state_model})


@pytest.mark.parametrize("name", list(MODELS))
def test_every_registered_model_reaches_as_far_and_arrives_as_soon_as_the_position_model(name):
    """Without a state set (an undetected pedestrian: any velocity within v_max) every model's
    reach is v_max dt per step and its arrival max(0, d - 2 eps) / v_max; the speed-bounded
    models ignore a state set (the bounded-acceleration one uses it:
    test_bounded_acceleration.py)."""
    model = motion_model(config(name), DT)
    state = Zonotope(np.zeros(model.dim), np.eye(model.dim))
    distances = np.array([0.0, 0.5, 2 * JITTER, 1.0, 7.25, 40.0])
    expected = np.array([max(0.0, d - 2 * JITTER) / SPEED for d in distances])
    for given in (None, state) if model.acceleration_bound_mps2 is None else (None,):
        for steps in (0, 1, 3, 17):
            assert model.reach_m(steps, given) == pytest.approx(SPEED * DT * steps, abs=1e-12)
        assert model.reach_m(state=given) == pytest.approx(SPEED * DT, abs=1e-12)
        assert model.reach_during_m(30.0, 8.0, given) == pytest.approx(SPEED * 30.0 / 8.0)
        assert np.allclose(model.earliest_arrival_s(distances, given), expected, rtol=0,
                           atol=1e-12)


def test_the_schema_accepts_exactly_the_registered_names():
    field = Estimator.model_fields["state_model"]
    assert typing.get_args(field.annotation) == tuple(MODELS)
    assert field.default in MODELS
    for name in MODELS:
        assert Estimator(state_model=name).state_model == name
    with pytest.raises(ValidationError, match="unknown state model 'cv'; use one of "
                       + ", ".join(MODELS)):
        Estimator(state_model="cv")


@dataclasses.dataclass(frozen=True)
class Slow(LinearModel):
    """A test model: the position model's prediction, but a path that moves at most half as
    far (and so arrives twice as late)."""

    def reach_m(self, steps: int = 1, state: Zonotope | None = None) -> float:
        return 0.5 * super().reach_m(steps, state)

    def earliest_arrival_s(self, distance_m: np.ndarray, state: Zonotope | None = None,
                           separation: Separation | None = None,
                           of_path: bool = False) -> np.ndarray:
        return 2.0 * super().earliest_arrival_s(distance_m, state, separation, of_path)


def build_slow(settings: Estimator, step_length: float, jitter: float) -> Slow:
    position = MODELS["position"](settings, step_length, jitter)
    return Slow(position.transition, position.process_noise, position.position_matrix,
                position.state_bounds, position.max_speed, position.step_length, jitter)


def regrown(model: LinearModel) -> float:
    """The unobserved area (m²) of a 40 m sidewalk 3 steps after its first half was seen."""
    walkable = shapely.box(0, 0, 40, 2)
    area = UnobservedArea(R(walkable), model, latency_steps=0, kind=K)
    area.update(0, R(shapely.box(0, -1, 20, 3)), [])
    return area.update(3, K.empty(), []).area


def test_a_registry_entry_is_all_a_new_model_needs(monkeypatch):
    """Registered under a name, a model is what ``motion_model`` builds for it, and the layers
    grow their regions and time their arrivals by its reach and arrival, not their own: the
    slow model's unobserved area is the position model's at half the speed bound."""
    monkeypatch.setitem(MODELS, "slow", build_slow)
    slow, position = motion_model(config("slow"), DT), motion_model(config("position"), DT)
    half = motion_model(config("position").model_copy(
        update={"max_pedestrian_speed_mps": SPEED / 2}), DT)
    assert isinstance(slow, Slow)
    assert regrown(slow) == pytest.approx(regrown(half), abs=1e-9)
    # 3 steps: it regrows 0.375 m less into the seen half (x 2 m of sidewalk, 0.81 m²)
    assert regrown(slow) < regrown(position) - 0.7
    zone = ConflictZone(R(shapely.box(10, 0, 12, 2)), 0.0, 0.0, np.inf)
    source = Source(R(shapely.box(0, 0, 1, 2)))
    assert _arrivals([source], [zone], slow, K)[0] == pytest.approx(
        2.0 * _arrivals([source], [zone], position, K)[0])

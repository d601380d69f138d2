"""The pedestrian's motion models by name; ``estimator.state_model`` picks one.

A model is one module here with a ``NAME`` and a ``build(config, step_length, jitter)`` that
returns a :class:`MotionModel` (most reuse :class:`LinearModel`'s prediction, sets and reach;
one whose reach depends on the state overrides :meth:`MotionModel.reach_m` and
:meth:`MotionModel.earliest_arrival_s`). Registering it is one entry in :data:`MODELS`; the
scenario schema's accepted names and its error message follow.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

from sse_cosim.estimation.motion import bounded_acceleration, constant_velocity, position
from sse_cosim.estimation.motion.base import (
    POSITION_MEMO,
    LinearModel,
    MotionModel,
    Separation,
    unit_fan,
)

if TYPE_CHECKING:
    from sse_cosim.scenario.model import Estimator

Builder = Callable[["Estimator", float, float], MotionModel]
"""(estimator settings, step length (s), jitter (m)) -> the model."""

MODELS: dict[str, Builder] = {
    module.NAME: module.build
    # the registration: one entry per model
    for module in (position, constant_velocity, bounded_acceleration)
}


def motion_model(config: Estimator, step_length: float) -> MotionModel:
    """The model named by ``config.state_model`` for steps of ``step_length`` seconds;
    ``config`` with its jitter set (a run's world measures it where a scenario leaves it out,
    :mod:`sse_cosim.world.walker_jitter`)."""
    if config.position_jitter_m is None:
        raise ValueError("estimator.position_jitter_m is not set: the world resolves it "
                         "before the estimator starts")
    return MODELS[config.state_model](config, step_length, config.position_jitter_m)


def acceleration_bound(config: Estimator, step_length: float) -> float | None:
    """a_max (m/s²) of the model ``config`` names, None if it does not bound the acceleration:
    what the world must keep (it ramps its walkers' speeds within it and checks it), asked
    before the jitter is measured."""
    return MODELS[config.state_model](config, step_length, 0.0).acceleration_bound_mps2


__all__ = ["MODELS", "POSITION_MEMO", "LinearModel", "MotionModel", "Separation",
           "acceleration_bound", "motion_model", "unit_fan"]

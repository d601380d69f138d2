"""The ``constant-velocity`` state model: x = (p, v) with v_k := (p_{k+1} - p_k) / dt.

v is the displacement over the next step, so the position row of F is exact:
F = [[I, dt I], [0, I]], and the velocity change per step is bounded by
``max_velocity_change_mps`` per axis. The speed bound |v| <= v_max is applied every step as
pseudo-measurement strips (always true, so sound). Its reach and earliest arrivals are
:class:`~.base.LinearModel`'s (the state set is not used: a disc of v_max dt per step).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from sse_cosim.estimation.motion.base import LinearModel
from sse_cosim.sets import Strips, Zonotope

if TYPE_CHECKING:
    from sse_cosim.scenario.model import Estimator

NAME = "constant-velocity"


def linear_parts(step_length: float, velocity_change: float) -> dict[str, object]:
    """F = [[I, dt I], [0, I]], the process noise <0, [0; velocity_change I]> and C = [I 0] of a
    (position, velocity) model: :class:`LinearModel`'s fields every such model shares."""
    noise = np.zeros((4, 2))
    noise[2:, :] = np.eye(2) * velocity_change
    return {
        "transition": np.block([[np.eye(2), step_length * np.eye(2)],
                                [np.zeros((2, 2)), np.eye(2)]]),
        "process_noise": Zonotope(np.zeros(4), noise),
        "position_matrix": np.hstack([np.eye(2), np.zeros((2, 2))]),
    }


def build(config: Estimator, step_length: float, jitter: float) -> LinearModel:
    """The constant-velocity model of ``config`` for steps of ``step_length`` seconds."""
    v_max = config.max_pedestrian_speed_mps
    velocity_rows = np.hstack([np.zeros((2, 2)), np.eye(2)])
    return LinearModel(
        **linear_parts(step_length, config.max_velocity_change_mps),
        state_bounds=Strips(velocity_rows, np.zeros(2), np.full(2, v_max)),
        max_speed=v_max,
        step_length=step_length,
        jitter=jitter,
    )

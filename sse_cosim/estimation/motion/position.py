"""The ``position`` state model: x = (p_x, p_y), F = I, n_k in the box |n_i| <= v_max * dt.

Sound whenever the pedestrian's path moves at most v_max * dt in one step (the box holds that
disc). Its reach and earliest arrivals are :class:`~.base.LinearModel`'s: a disc of v_max dt
per step, whatever the pedestrian is doing.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from sse_cosim.estimation.motion.base import LinearModel
from sse_cosim.sets import Zonotope

if TYPE_CHECKING:
    from sse_cosim.scenario.model import Estimator

NAME = "position"


def build(config: Estimator, step_length: float, jitter: float) -> LinearModel:
    """The position model of ``config`` for steps of ``step_length`` seconds."""
    v_max = config.max_pedestrian_speed_mps
    return LinearModel(
        transition=np.eye(2),
        process_noise=Zonotope(np.zeros(2), np.eye(2) * v_max * step_length),
        position_matrix=np.eye(2),
        state_bounds=None,
        max_speed=v_max,
        step_length=step_length,
        jitter=jitter,
    )

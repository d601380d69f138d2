"""A node's estimator settings and the two steps every kept set ends with.

:func:`bounded` is how a track ends its step (the observers, the anonymous association, the
V2X link's coasting); :func:`coast` is one step of a set nobody sees. Both live here, below
the observers and the association, so that each layer uses the one definition.
"""

from __future__ import annotations

from dataclasses import dataclass

from sse_cosim.estimation.motion import MotionModel
from sse_cosim.sets import Zonotope


@dataclass(frozen=True)
class EstimatorSettings:
    """The named methods a node uses (scenario ``[estimator]``)."""

    gain_method: str
    reduction_method: str
    max_generators: int

    def reduce(self, estimate: Zonotope) -> Zonotope:
        """``estimate`` reduced to the node's generator budget (an over-approximation)."""
        return estimate.reduce(self.max_generators, self.reduction_method)


def bounded(model: MotionModel, settings: EstimatorSettings, estimate: Zonotope) -> Zonotope:
    """``estimate`` cut by the model's state bounds (A3) and reduced to the node's generator
    budget (each an over-approximation: sound), as every track ends its step."""
    return settings.reduce(model.bound_state(estimate))


def coast(model: MotionModel, settings: EstimatorSettings, estimate: Zonotope) -> Zonotope:
    """One step of a set nobody sees: predicted (Definition 1), then :func:`bounded`, as a node
    carries a track it does not see (without the velocity windows only its own strips give)."""
    return bounded(model, settings, model.predict(estimate))

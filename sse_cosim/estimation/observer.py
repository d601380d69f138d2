"""One node's local observer: predict, correct with its own strips (Proposition 1), reduce.

Every node (bus, connected car, road-side unit) runs one. A track starts from the strips of
its first detection; when the node loses sight it keeps predicting, so the set grows by the
process noise each step and still contains the pedestrian. Detections are associated with
tracks by the pedestrian's id (the simulation knows who is who; the paper has one pedestrian).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from sse_cosim.estimation.motion import MotionModel
from sse_cosim.sets import Strips, Zonotope, intersect_strips


@dataclass(frozen=True)
class EstimatorSettings:
    """The named methods a node uses (scenario ``[estimator]``)."""

    gain_method: str
    reduction_method: str
    max_generators: int


@dataclass(frozen=True)
class Track:
    """A node's state set for one pedestrian at ``step``; ``detected`` if corrected this step."""

    person_id: str
    estimate: Zonotope
    step: int
    detected: bool


class NodeObserver:
    """Local set-membership observer of one node (paper Fig. 3, first fusion level)."""

    def __init__(self, node: str, model: MotionModel, settings: EstimatorSettings) -> None:
        self.node = node
        self.model = model
        self.settings = settings
        self.tracks: dict[str, Track] = {}

    def step(self, step: int, detections: Mapping[str, Sequence[Strips]]) -> dict[str, Track]:
        """Advance every track to ``step`` and correct those detected now.

        ``detections`` maps a pedestrian id to the position strips of this node's sensors
        that see it at this step.
        """
        updated: dict[str, Track] = {}
        for person_id in self.tracks.keys() | detections.keys():
            strips = list(detections.get(person_id, ()))
            path = self.model.path_strips(Strips.stack(strips)) if strips else None
            previous = self.tracks.get(person_id)
            if previous is None:
                estimate = self.model.initial_set(path, self.settings.gain_method)
            else:
                estimate = self.model.predict(previous.estimate, step - previous.step)
                if path is not None:
                    measured = path.pullback(self.model.position_matrix)
                    estimate = intersect_strips(estimate, measured, self.settings.gain_method)
            if self.model.state_bounds is not None:
                estimate = intersect_strips(
                    estimate, self.model.state_bounds, self.settings.gain_method
                )
            estimate = estimate.reduce(self.settings.max_generators, self.settings.reduction_method)
            updated[person_id] = Track(person_id, estimate, step, bool(strips))
        self.tracks = updated
        return updated

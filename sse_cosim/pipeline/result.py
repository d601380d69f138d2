"""What one simulation step produced: the input of the recorder and of step callbacks."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from sse_cosim.estimation.motion import MotionModel
from sse_cosim.estimation.observer import LocalTracks
from sse_cosim.pipeline.ego import EgoStep
from sse_cosim.sensors import SensorObservation
from sse_cosim.sensors.faults import FaultStatus
from sse_cosim.world.snapshot import Snapshot


@dataclass(frozen=True)
class StepResult:
    """Everything one step produced, handed to the recorder: the world, every node's
    observations and tracks, and what each automated vehicle made of them (``vehicles``: its
    id -> its :class:`~sse_cosim.pipeline.ego.EgoStep`, in the scenario's order; a vehicle not
    in the scene at this step is missing)."""

    step: int
    snapshot: Snapshot
    observations: dict[str, SensorObservation]
    tracks: dict[str, LocalTracks]  # node -> pedestrian id (or track key) -> track
    model: MotionModel
    faults: dict[str, FaultStatus]  # injected fault -> status
    vehicles: dict[str, EgoStep]


StepCallback = Callable[[StepResult], None]

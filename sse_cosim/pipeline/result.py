"""What one simulation step produced: the input of the recorder and of step callbacks."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import shapely

from sse_cosim.control.picture import Picture
from sse_cosim.control.speed import SpeedLevel
from sse_cosim.estimation.bus_screen import BusScreen
from sse_cosim.estimation.flags import StepFlags
from sse_cosim.estimation.motion import MotionModel
from sse_cosim.estimation.observer import Track
from sse_cosim.estimation.v2x import SharedPicture
from sse_cosim.sensors import SensorObservation
from sse_cosim.sensors.faults import FaultStatus
from sse_cosim.sets import Zonotope
from sse_cosim.world.snapshot import Snapshot


@dataclass(frozen=True)
class StepResult:
    """Everything one step produced, handed to the recorder."""

    step: int
    snapshot: Snapshot
    observations: dict[str, SensorObservation]
    tracks: dict[str, dict[str, Track]]  # node -> pedestrian id -> track
    shared: SharedPicture
    unobserved: shapely.Geometry  # walkable area where an undetected pedestrian may be
    window: shapely.Geometry  # where hidden ground is tracked; outside, all counts as occupied
    fused: dict[str, Zonotope]  # pedestrian id -> fused state set
    possible: dict[str, shapely.Geometry]  # pedestrian id -> fused position set minus clear areas
    picture: Picture
    level: SpeedLevel
    commanded_speed: float
    model: MotionModel
    screen: BusScreen  # what the bus fused, whom it flagged
    flags: StepFlags  # per sensor and node
    faults: dict[str, FaultStatus]  # injected fault -> status


StepCallback = Callable[[StepResult], None]

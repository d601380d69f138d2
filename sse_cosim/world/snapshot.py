"""What the world looks like at one step: pure data, no SUMO.

Headings are mathematical (radians, counter-clockwise from east); the SUMO adapter converts
SUMO's navigational angle and front-bumper reference into these.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import shapely

from sse_cosim.sets import portable
from sse_cosim.world.signals import SignalState


@dataclass(frozen=True)
class Pose:
    """A position (m) and a heading (rad, CCW from east)."""

    x: float
    y: float
    heading: float

    @property
    def position(self) -> np.ndarray:
        """Shape (2,)."""
        return np.array([self.x, self.y])

    @property
    def forward(self) -> np.ndarray:
        """Unit vector along the heading, shape (2,)."""
        return np.array([portable.cos(self.heading), portable.sin(self.heading)])

    @property
    def left(self) -> np.ndarray:
        """Unit vector to the left of the heading, shape (2,)."""
        return np.array([-portable.sin(self.heading), portable.cos(self.heading)])

    def compose(self, forward_m: float, left_m: float, yaw: float) -> Pose:
        """The pose offset by ``forward_m``/``left_m`` in this frame and turned by ``yaw`` (rad)."""
        p = self.position + forward_m * self.forward + left_m * self.left
        return Pose(float(p[0]), float(p[1]), self.heading + yaw)


@dataclass(frozen=True)
class Footprint:
    """A vehicle's oriented rectangle; ``front`` is the front bumper's centre (SUMO's reference)."""

    front: Pose
    length: float
    width: float

    @property
    def center(self) -> np.ndarray:
        """Centre of the rectangle, shape (2,)."""
        return self.front.position - 0.5 * self.length * self.front.forward

    def corners(self) -> np.ndarray:
        """Corners counter-clockwise from the rear right, shape (4, 2)."""
        f, l_ = self.front.forward, self.front.left
        rear = self.front.position - self.length * f
        half = 0.5 * self.width * l_
        front = self.front.position
        return np.array([rear - half, front - half, front + half, rear + half])

    def polygon(self) -> shapely.Polygon:
        """The footprint as a shapely polygon."""
        return shapely.Polygon(self.corners())


@dataclass(frozen=True)
class VehicleState:
    """One vehicle at one step."""

    id: str
    kind: str  # "automated", "vehicle" (moving), "parked" or "other" (not in the scenario)
    footprint: Footprint
    speed: float  # m/s
    type_id: str = ""  # its SUMO vehicle type (route-file vehicles carry sensors by type)
    on_crossings: tuple[str, ...] = ()  # the crossings its body meets, sorted ids
    # an automated vehicle's front along its route as SUMO counts it (m: its departure
    # position plus its odometer, from the start of the route's first lane); None for others
    route_m: float | None = None


@dataclass(frozen=True)
class PersonState:
    """One pedestrian at one step; ``position`` is its centre, shape (2,); ``heading`` the
    direction it walks (rad, CCW from east) as SUMO gives it, None while it waits beside the
    sidewalk before its walk (on no lane); ``crossing`` the crossing it is on (None: on none
    of the network's crossings); ``next_crossing`` the crossing its walk enters next from the
    walking area it is on (None: on no walking area, or not bound for a crossing)."""

    id: str
    position: tuple[float, float]
    speed: float  # m/s
    crossing: str | None = None
    heading: float | None = None
    next_crossing: str | None = None

    @property
    def on_crossing(self) -> bool:
        """Whether it is on any of the network's crossings."""
        return self.crossing is not None


@dataclass(frozen=True)
class Snapshot:
    """The world at time ``time`` (s): every vehicle and person by id, and every traffic light
    of the scene (those of the road map's signalised links and crossings) by id."""

    time: float
    vehicles: dict[str, VehicleState] = field(default_factory=dict)
    persons: dict[str, PersonState] = field(default_factory=dict)
    signals: dict[str, SignalState] = field(default_factory=dict)

"""What every sensor kind provides: a schema for its scenario table and a :class:`SensorKind`.

A sensor is its mounting (carrier and offsets, common to all kinds) plus its kind: what the
kind sees and how it measures. Occlusion is the same for every kind (:mod:`..observe`): a
position in the kind's field of view is seen unless the segment to it touches a vehicle
footprint other than the carrier's.
"""

from __future__ import annotations

from abc import abstractmethod
from typing import Protocol

import numpy as np
from pydantic import Field, model_validator

from sse_cosim.scenario.base import StrictModel
from sse_cosim.sensors.measurement import NoiseKind
from sse_cosim.sets import Strips
from sse_cosim.world.snapshot import Pose


class SensorKind(Protocol):
    """What one kind of sensor sees and how it measures a position it sees.

    It sees a closed circular sector centred on its boresight (the sensor pose's heading):
    opening ``fov_rad`` (>= 2 pi: all around) and reach ``range_m`` (m). A sector is what the
    vectorized visibility pass and the visible/occluded regions are built from.
    """

    @property
    def fov_rad(self) -> float: ...

    @property
    def range_m(self) -> float: ...

    def measure(
        self, pose: Pose, positions: np.ndarray, rng: np.random.Generator
    ) -> list[Strips]:
        """One :class:`Strips` per true position (row of ``positions``, shape (k, 2)) seen
        from ``pose``: normals H (m, 2), values y (m,), radii r (m,) with |H p - y| <= r for
        the true position p. Noise is drawn from ``rng``, position by position, so a seeded
        generator reproduces the strips."""
        ...


class SensorMount(StrictModel):
    forward_m: float = Field(
        0.0, description="Offset along the carrier's heading from its reference point (m); "
        "a vehicle's reference point is its front bumper's centre, a unit's its position."
    )
    left_m: float = Field(0.0, description="Offset to the carrier's left (m).")
    yaw_deg: float = Field(
        0.0, description="Boresight relative to the carrier's heading (deg, CCW)."
    )


class SensorConfig(StrictModel):
    """The scenario fields every kind has; a kind's schema adds ``kind`` and its own.

    The carrier is one node (``node``) or every vehicle of a route-file type
    (``carrier_type``), exactly one of the two.
    """

    node: str | None = Field(
        None, description="Carrier: 'bus', 'car' or a road-side unit id (or carrier_type)."
    )
    carrier_type: str | None = Field(
        None, description="Instead of node: every vehicle of this type from network.route_files "
        "carries the sensor, as a connected node named by its vehicle id while it is in the "
        "scene; the instance on vehicle v is named '<sensor>@v'."
    )
    mount: SensorMount = Field(default_factory=SensorMount)
    noise: NoiseKind = Field(
        "uniform", description="'uniform': uniform within the kind's noise bounds; "
        "'worst-case': on the bounds (either sign)."
    )

    @model_validator(mode="after")
    def _one_carrier(self) -> SensorConfig:
        if (self.node is None) == (self.carrier_type is None):
            raise ValueError("node: set exactly one of node (one carrier) and carrier_type "
                             "(every vehicle of a route-file type)")
        return self

    @abstractmethod
    def build(self) -> SensorKind:
        """The kind this table describes, in SI units (radians)."""

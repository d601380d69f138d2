"""``camera``: a sector sensor measuring a position along its own forward and lateral axes
(paper eq. senmodel: y = H p + v, |v_i| <= r_i, H the sensor's axes)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from pydantic import Field

from sse_cosim.scenario.base import PositiveFloat
from sse_cosim.sensors.kinds.base import SensorConfig
from sse_cosim.sensors.measurement import NoiseKind, measure
from sse_cosim.sets import Strips
from sse_cosim.world.snapshot import Pose


@dataclass(frozen=True)
class Camera:
    """A sector of opening ``fov_rad`` and reach ``range_m``; ``noise_bound_m`` is r
    (forward, lateral) in the sensor's frame, ``noise`` how v is drawn within it."""

    fov_rad: float = 0.5 * math.pi
    range_m: float = 60.0
    noise_bound_m: tuple[float, float] = (0.5, 0.5)
    noise: NoiseKind = "uniform"

    @property
    def bounds(self) -> np.ndarray:
        """Noise bounds r (forward, lateral), shape (2,)."""
        return np.asarray(self.noise_bound_m, dtype=float)

    def measure(
        self, pose: Pose, positions: np.ndarray, rng: np.random.Generator
    ) -> list[Strips]:
        """``Strips(H, H p + v, r)`` per row of ``positions`` (k, 2); H (2, 2) the sensor's
        axes (:func:`~sse_cosim.sensors.measurement.measure`)."""
        return measure(pose, positions, self.bounds, self.noise, rng)


class CameraConfig(SensorConfig):
    kind: Literal["camera"] = Field(
        "camera", description="Sensor kind (docs/sensors.md); a field marked [kind] belongs to "
        "that kind alone. 'camera', the default: a sector, measuring along its own axes."
    )
    fov_deg: float = Field(90.0, gt=0, le=360, description="Opening angle of the sector (deg).")
    range_m: PositiveFloat = Field(60.0, description="Range of the sector (m).")
    noise_bound_m: tuple[PositiveFloat, PositiveFloat] = Field(
        (0.5, 0.5), description="Noise bounds r (m) along the sensor's forward and lateral axes."
    )

    def build(self) -> Camera:
        return Camera(
            fov_rad=math.radians(self.fov_deg),
            range_m=float(self.range_m),
            noise_bound_m=(float(self.noise_bound_m[0]), float(self.noise_bound_m[1])),
            noise=self.noise,
        )

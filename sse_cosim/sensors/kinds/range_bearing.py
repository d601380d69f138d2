"""``range``: a 360° range–bearing sensor (lidar, radar) with bounded range and bearing noise.

It measures the range ρ and bearing θ of a position d relative to it (d = p - s, s the
sensor's position) with |ρ_m - ρ| <= r (``range_bound_m``) and |θ_m - θ| <= δ
(``bearing_bound_deg``), 0 < δ < 90°. Those two intervals bound a ring sector, not a strip;
its sound strips, along u_r = (cos θ_m, sin θ_m) and u_t = (-sin θ_m, cos θ_m), are derived
as follows. Write d = ρ (cos θ, sin θ) and φ = θ - θ_m, so |φ| <= δ and

    u_r · d = ρ cos φ,    u_t · d = ρ sin φ.

A range is never negative: ρ >= 0, and ρ_m is reported as max(ρ_m, 0), which keeps
|ρ_m - ρ| <= r (if ρ_m < 0 <= ρ then ρ <= ρ_m + r < r). Hence ρ ∈ [max(ρ_m - r, 0), ρ_m + r].
As δ < 90°, cos φ ∈ [cos δ, 1] with cos δ > 0 and |sin φ| <= sin δ, so

    max(ρ_m - r, 0) cos δ  <=  u_r · d  <=  ρ_m + r,
    |u_t · d|  <=  (ρ_m + r) sin δ.

Both bounds are attained (ρ = ρ_m ∓ r with φ = ±δ, resp. φ = 0), so they are the tightest
strips along these two normals. As strips centre ± half-width, with lo and hi the first
interval's ends: y_r = u_r · s + (lo + hi) / 2, r_r = (hi - lo) / 2; y_t = u_t · s,
r_t = (ρ_m + r) sin δ; both half-widths are > 0 since ρ_m + r >= r > 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from pydantic import Field

from sse_cosim.scenario.base import PositiveFloat
from sse_cosim.sensors.geometry import FULL_TURN
from sse_cosim.sensors.kinds.base import SensorConfig
from sse_cosim.sensors.measurement import NoiseKind, draw_noise
from sse_cosim.sets import Strips, portable
from sse_cosim.world.snapshot import Pose


@dataclass(frozen=True)
class RangeBearing:
    """Sees all around up to ``range_m``; measures range within ``range_bound_m`` (m) and
    bearing within ``bearing_bound_rad`` (< pi / 2), drawn as ``noise`` says."""

    range_m: float = 30.0
    range_bound_m: float = 0.3
    bearing_bound_rad: float = math.radians(1.0)
    noise: NoiseKind = "uniform"

    @property
    def fov_rad(self) -> float:
        """All around: a full turn."""
        return FULL_TURN

    def measure(
        self, pose: Pose, positions: np.ndarray, rng: np.random.Generator
    ) -> list[Strips]:
        """Two strips per row of ``positions`` (k, 2) (:func:`range_bearing_strips`); the
        noise (range, bearing), shape (k, 2), is drawn from ``rng`` as ``noise`` says."""
        d = np.asarray(positions, dtype=float).reshape(-1, 2) - pose.position  # (k, 2)
        if d.shape[0] == 0:
            return []
        bounds = np.array([self.range_bound_m, self.bearing_bound_rad])
        v = draw_noise(bounds, self.noise, rng, d.shape[0])  # (k, 2)
        rho = portable.hypot(d[:, 0], d[:, 1]) + v[:, 0]
        theta = portable.arctan2(d[:, 1], d[:, 0]) + v[:, 1]
        return range_bearing_strips(pose.position, rho, theta, *bounds)


def range_bearing_strips(
    origin: np.ndarray, rho: np.ndarray, theta: np.ndarray, range_bound: float,
    bearing_bound: float,
) -> list[Strips]:
    """The strips of measured ranges ``rho`` and bearings ``theta`` (k,) taken at ``origin``
    (2,) with bounds r = ``range_bound`` (m) and δ = ``bearing_bound`` (rad, < pi / 2).

    One :class:`Strips` per measurement: normals (2, 2) rows u_r, u_t; values (2,); radii
    (2,), as derived in the module docstring.
    """
    r, delta = range_bound, bearing_bound
    rho = np.maximum(np.asarray(rho, dtype=float), 0.0)  # (k,): a range is never negative
    theta = np.asarray(theta, dtype=float)
    c, s = portable.cos(theta), portable.sin(theta)
    normals = np.stack([np.stack([c, s], axis=1), np.stack([-s, c], axis=1)], axis=1)  # (k,2,2)
    lo, hi = np.maximum(rho - r, 0.0) * math.cos(delta), rho + r  # (k,) each
    values = portable.matmul(normals, np.asarray(origin, dtype=float))  # (k, 2): u_r · s, u_t · s
    values[:, 0] += 0.5 * (lo + hi)
    radii = np.stack([0.5 * (hi - lo), hi * math.sin(delta)], axis=1)  # (k, 2)
    return [Strips(h, y, w) for h, y, w in zip(normals, values, radii, strict=True)]


class RangeConfig(SensorConfig):
    kind: Literal["range"] = Field(
        description="'range': all around, measuring range and bearing (docs/sensors.md)."
    )
    range_m: PositiveFloat = Field(30.0, description="Reach all around (m).")
    range_bound_m: PositiveFloat = Field(
        0.3, description="Bound on the range error |ρ_meas - ρ| (m)."
    )
    bearing_bound_deg: float = Field(
        1.0, gt=0, lt=90, description="Bound on the bearing error |θ_meas - θ| (deg); below 90, "
        "where the strips' derivation holds."
    )

    def build(self) -> RangeBearing:
        return RangeBearing(
            range_m=float(self.range_m),
            range_bound_m=float(self.range_bound_m),
            bearing_bound_rad=math.radians(self.bearing_bound_deg),
            noise=self.noise,
        )

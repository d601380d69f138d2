"""Measurements of eq. (senmodel): y = H p + v, |v_i| <= r_i, as strips (eq. strip)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, get_args

import numpy as np

from sse_cosim.sets import Strips, portable
from sse_cosim.world.snapshot import Pose

NoiseKind = Literal["uniform", "worst-case"]
NOISE_KINDS = get_args(NoiseKind)


def measurement_matrix(pose: Pose) -> np.ndarray:
    """H, shape (2, 2): rows are the sensor's forward and left (lateral) unit axes."""
    c, s = math.cos(pose.heading), math.sin(pose.heading)
    return np.array([[c, s], [-s, c]])


def draw_noise(bounds: np.ndarray, kind: str, rng: np.random.Generator, count: int) -> np.ndarray:
    """Noise v for ``count`` measurements, shape (count, 2), with |v[:, i]| <= bounds[i].

    ``uniform``: uniform in [-r, r]; ``worst-case``: on the bound, ±r with a random sign.
    """
    r = np.asarray(bounds, dtype=float).reshape(2)
    if kind == "uniform":
        return (2.0 * rng.random((count, 2)) - 1.0) * r
    if kind == "worst-case":
        return (2.0 * rng.integers(0, 2, size=(count, 2)) - 1.0) * r
    raise ValueError(f"unknown noise kind {kind!r}; use one of {', '.join(NOISE_KINDS)}")


def measure(
    pose: Pose,
    positions: np.ndarray,
    bounds: np.ndarray,
    kind: str,
    rng: np.random.Generator,
) -> list[Strips]:
    """One strip pair per true position ``positions`` (k, 2): ``Strips(H, H p + v, r)``.

    H (2, 2) from :func:`measurement_matrix`, r = ``bounds`` (2,); every strip contains its
    true position up to rounding (|H p - y| = |v| <= r).
    """
    p = np.asarray(positions, dtype=float).reshape(-1, 2)
    if p.shape[0] == 0:
        return []
    h = measurement_matrix(pose)
    r = np.asarray(bounds, dtype=float).reshape(2)
    y = portable.matmul(p, h.T) + draw_noise(r, kind, rng, p.shape[0])  # (k, 2)
    return Strips.rows(h, y, r)  # copies (read-only)


@dataclass(frozen=True)
class Detection:
    """One pedestrian measured by one sensor at one time: the measurement strips."""

    sensor: str
    node: str
    time: float
    person_id: str
    strips: Strips

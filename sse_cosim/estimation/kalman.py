"""A Kalman-filter baseline fed the same measurements as the zonotopes (benchmarks, item 7).

The bounded quantities of the set-membership model become Gaussian with sigma = bound / 3:
each path strip |h·s - y| <= r (the sensor's bound widened by the jitter, exactly what the
observers use) is a scalar measurement y = h·s + v with v ~ N(0, (r/3)²), and the process
noise box |n_i| <= v_max·dt becomes N(0, (v_max·dt/3)² I). The filter runs at the bus on every
node's measurements at the step they are taken (no V2X delay: an advantage over the
zonotopes). Its 3-sigma ellipse {x : (x - μ)ᵀ P⁻¹ (x - μ) <= 9} is the pedestrian region the
controller gets with ``estimator.filter = "kalman"``. Nothing guarantees that the ellipse holds
the pedestrian: the benchmarks count how often it does not.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from sse_cosim.estimation.motion import MotionModel
from sse_cosim.regions import Region, RegionKind
from sse_cosim.sets import Strips

SIGMAS = 3.0  # a bound is 3 standard deviations
ELLIPSE_POINTS = 32


@dataclass
class Gaussian:
    """Mean (2,) and covariance (2, 2) of one pedestrian's path position at ``step``."""

    mean: np.ndarray
    cov: np.ndarray
    step: int

    def mahalanobis2(self, point: np.ndarray) -> float:
        """(x - μ)ᵀ P⁻¹ (x - μ)."""
        d = np.asarray(point, dtype=float) - self.mean
        return float(d @ np.linalg.solve(self.cov, d))

    def contains(self, point: np.ndarray, sigmas: float = SIGMAS) -> bool:
        """Whether ``point`` lies in the ``sigmas``-sigma ellipse."""
        return self.mahalanobis2(point) <= sigmas * sigmas

    def ellipse(self, sigmas: float = SIGMAS, extra: float = 0.0) -> np.ndarray:
        """The corners (k, 2) of a polygon circumscribing the ``sigmas``-sigma ellipse grown
        by ``extra`` metres."""
        values, vectors = np.linalg.eigh(0.5 * (self.cov + self.cov.T))
        axes = sigmas * np.sqrt(np.maximum(values, 0.0)) + extra
        angles = np.linspace(0.0, 2.0 * np.pi, ELLIPSE_POINTS, endpoint=False)
        circumscribe = 1.0 / np.cos(np.pi / ELLIPSE_POINTS)
        unit = np.stack([np.cos(angles), np.sin(angles)], axis=1) * circumscribe
        return self.mean + (unit * axes) @ vectors.T


def update(state: Gaussian, strips: Strips) -> Gaussian:
    """Sequential scalar updates with every strip (Joseph form)."""
    x, p = state.mean.copy(), state.cov.copy()
    for h, y, r in zip(strips.normals, strips.values, strips.radii, strict=True):
        variance = (r / SIGMAS) ** 2
        s = h @ p @ h + variance
        k = p @ h / s
        x = x + k * (y - h @ x)
        a = np.eye(2) - np.outer(k, h)
        p = a @ p @ a.T + variance * np.outer(k, k)
    return Gaussian(x, p, state.step)


def initial(strips: Strips, step: int) -> Gaussian:
    """From the first two independent strips (x = H⁻¹y, P = H⁻¹ R H⁻ᵀ), then the others."""
    normals = strips.normals
    pair = None
    for i in range(len(normals)):
        for j in range(i + 1, len(normals)):
            if abs(np.linalg.det(normals[[i, j]])) > 1e-6:
                pair = (i, j)
                break
        if pair is not None:
            break
    if pair is None:
        raise ValueError("a Kalman track needs two strips with independent normals")
    h = normals[list(pair)]
    inverse = np.linalg.inv(h)
    r = np.diag((strips.radii[list(pair)] / SIGMAS) ** 2)
    state = Gaussian(inverse @ strips.values[list(pair)], inverse @ r @ inverse.T, step)
    rest = np.ones(len(normals), dtype=bool)
    rest[list(pair)] = False
    return update(state, strips.select(rest)) if rest.any() else state


class KalmanTracker:
    """The bus's Kalman filter over every node's measurements, one track per pedestrian."""

    def __init__(self, model: MotionModel) -> None:
        if model.dim != 2:
            raise ValueError("the Kalman baseline supports the 'position' state model only")
        self.model = model
        half_widths = np.abs(model.process_noise.generators).sum(axis=1)
        self.process = np.diag((half_widths / SIGMAS) ** 2)
        self.tracks: dict[str, Gaussian] = {}

    def step(self, step: int, detections: Mapping[str, Sequence[Strips]]) -> dict[str, Gaussian]:
        """Predict every track to ``step`` and update it with the position strips of
        ``detections`` (pedestrian id -> strips of every sensor that sees it now)."""
        for person_id, state in list(self.tracks.items()):
            steps = step - state.step
            self.tracks[person_id] = Gaussian(state.mean, state.cov + steps * self.process, step)
        for person_id, strips in detections.items():
            if not strips:
                continue
            path = self.model.path_strips(Strips.stack(list(strips)))
            state = self.tracks.get(person_id)
            self.tracks[person_id] = initial(path, step) if state is None else update(state, path)
        return dict(self.tracks)

    def regions(self, kind: RegionKind) -> dict[str, Region]:
        """Each pedestrian's 3-sigma ellipse of the path, grown by the jitter (its position)."""
        return {pid: kind.convex_outer(g.ellipse(extra=self.model.jitter))
                for pid, g in self.tracks.items()}


def all_detections(observations: Iterable) -> dict[str, list[Strips]]:
    """Pedestrian id -> the strips of every sensor (any node) that sees it."""
    result: dict[str, list[Strips]] = {}
    for obs in observations:
        for person_id, detection in obs.detections.items():
            result.setdefault(person_id, []).append(detection.strips)
    return result

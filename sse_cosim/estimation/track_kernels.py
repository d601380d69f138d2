"""A node's usual track updates in one compiled call (numba, cached on disk).

Most of a node's tracks, most steps, take the plain path of :meth:`NodeObserver.step`
(:mod:`sse_cosim.estimation.observer`): predict (Definition 1), and either nothing more (no
sensor sees the pedestrian) or one sensor's two position strips, consistent with the
prediction, intersected by Proposition 1; then Girard's reduction. For a 2-D position model
(transition I) :func:`plain_updates` does that for every such track of the node at once,
calling the same compiled set kernels as the per-track path on the same arrays, so the
estimates are the same bits. The per-track path (``NodeObserver._track``, with
:func:`~sse_cosim.estimation.correction.correct`) stays the reference, and the fallback: a
track the kernel does not settle (a sensor inconsistent with the prediction, a
rank-deficient test, a non-finite value) goes through it unchanged.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from sse_cosim.sets import kernels
from sse_cosim.sets.enclosure_kernels import enclose_or_volume

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

GAIN_CODES = {"enclose": 0, "volume": 1, "frobenius": 2}
"""The gain methods (``estimator.gain_method``) whose 2-D correction is one compiled kernel."""

INDEPENDENT_TOL = 1e-6  # |det| of two strip normals above which they are independent
                        # (motion._independent_pair's tolerance)


@njit(cache=True)
def _predicted(center: FloatArray, generators: FloatArray, count: int, steps: int,
               noise: FloatArray) -> tuple[FloatArray, FloatArray]:
    """⟨c, G[:, :count]⟩ predicted ``steps`` steps with transition I and process noise
    generators Q (2, q): ⟨c, [G, Q, ..., Q]⟩ (Definition 1)."""
    q = noise.shape[1]
    predicted = np.empty((2, count + steps * q))
    predicted[:, :count] = generators[:, :count]
    for s in range(steps):
        predicted[:, count + s * q:count + (s + 1) * q] = noise
    return center.copy(), predicted


@njit(cache=True)
def _measurement_set(normals: FloatArray, values: FloatArray, radii: FloatArray
                     ) -> tuple[bool, FloatArray, FloatArray]:
    """The parallelogram of two path strips (H (2, 2), y, r (2,)): ⟨H⁻¹y, H⁻¹ diag(r)⟩, or
    False when the normals are dependent or the result is not finite."""
    a, b, c, d = normals[0, 0], normals[0, 1], normals[1, 0], normals[1, 1]
    det = a * d - b * c
    if not abs(det) > INDEPENDENT_TOL:
        return False, np.empty(2), np.empty((2, 2))
    inverse = np.array([[d, -b], [-c, a]]) / det
    center = np.array([inverse[0, 0] * values[0] + inverse[0, 1] * values[1],
                       inverse[1, 0] * values[0] + inverse[1, 1] * values[1]])
    generators = inverse * radii.reshape(1, 2)
    ok = np.isfinite(center).all() and np.isfinite(generators).all()
    return ok, center, generators


@njit(cache=True)
def _corrected(center: FloatArray, generators: FloatArray, normals: FloatArray,
               values: FloatArray, radii: FloatArray, gain: int) -> tuple[FloatArray, FloatArray]:
    """Proposition 1 (or the enclosure) with the kernel of ``gain`` (:data:`GAIN_CODES`), the
    strips rescaled to unit normals first, as ``gains.intersect_strips`` does."""
    if gain == 0:
        return enclose_or_volume(center, generators, normals, values, radii)
    _, unit_normals, unit_values, unit_radii = kernels.unit_strips(normals, values, radii)
    if gain == 1:
        return kernels.volume_correction_2d(center, generators, unit_normals, unit_values,
                                            unit_radii)
    return kernels.intersect_frobenius(center, generators, unit_normals, unit_values, unit_radii)


@njit(cache=True)
def plain_updates(centers: FloatArray, generators: FloatArray, counts: IntArray,
                  steps: IntArray, noise: FloatArray, normals: FloatArray, values: FloatArray,
                  radii: FloatArray, detected: NDArray[np.bool_], jitter: float, gain: int,
                  max_generators: int, tol: float
                  ) -> tuple[NDArray[np.bool_], FloatArray, FloatArray, IntArray]:
    """k tracks' plain updates: ``centers`` (k, 2) and ``generators`` (k, 2, e) with
    ``counts`` (k,) columns used are the previous estimates, predicted ``steps`` (k,) steps
    with noise generators (2, q); a ``detected`` (k,) track is corrected with one sensor's
    position strips ``normals`` (k, 2, 2), ``values`` and ``radii`` (k, 2), first widened by
    ``jitter`` ‖h‖ into path strips (``MotionModel.path_strips``), if their parallelogram
    meets the prediction (``vote.vote`` of two sets, tolerance ``tol``); then reduced to
    ``max_generators`` (Girard).

    -> (settled (k,), centers (k, 2), generators (k, 2, max_generators), counts (k,)); a
    track not settled is left to the per-track path.
    """
    k = centers.shape[0]
    settled = np.zeros(k, dtype=np.bool_)
    out_centers = np.zeros((k, 2))
    out_generators = np.zeros((k, 2, max_generators))
    out_counts = np.zeros(k, dtype=np.int64)
    for t in range(k):
        center, predicted = _predicted(centers[t], generators[t], counts[t], steps[t], noise)
        if detected[t]:
            widened = np.empty(2)
            for j in range(2):
                h0, h1 = normals[t, j, 0], normals[t, j, 1]
                widened[j] = radii[t, j] + jitter * np.sqrt(h0 * h0 + h1 * h1)
            if not np.isfinite(widened).all():
                continue
            ok, measured_center, measured = _measurement_set(normals[t], values[t], widened)
            if not ok or kernels.meet_2d(center, predicted, measured_center, measured,
                                         tol) != 1:
                continue
            center, predicted = _corrected(center, predicted, normals[t].copy(),
                                           values[t].copy(), widened, gain)
        reduced = kernels.girard_reduce(predicted, max_generators)
        settled[t] = True
        out_centers[t] = center
        out_generators[t, :, :reduced.shape[1]] = reduced
        out_counts[t] = reduced.shape[1]
    return settled, out_centers, out_generators, out_counts

"""A node's plain track updates in one compiled call (``track_kernels.plain_updates``) give the
same tracks, bit for bit, as the per-track path (the reference), and leave every other case
to it: faulty sensors, two sensors, new tracks, held-out sensors."""

from __future__ import annotations

import numpy as np
import pytest

from sse_cosim.estimation import track_kernels
from sse_cosim.estimation.motion import motion_model
from sse_cosim.estimation.observer import NodeObserver
from sse_cosim.estimation.settings import EstimatorSettings
from sse_cosim.scenario.model import Estimator
from sse_cosim.sets import Strips

pytestmark = pytest.mark.kernels

DT = 0.1
PEOPLE = 12


class PerTrackObserver(NodeObserver):
    """The reference: every track by the per-track path."""

    _compiled_path = False


def detections(rng: np.random.Generator, truth: np.ndarray, step: int) -> dict[str, dict]:
    """Pedestrian id -> sensor -> strips: mostly one sensor, sometimes two, some unseen; now
    and then a faulty sensor whose strips miss the truth by metres (outvoted, then on
    probation)."""
    found: dict[str, dict[str, Strips]] = {}
    for i, p in enumerate(truth):
        draw = rng.random()
        if draw < 0.25 or (i == 0 and step % 9 < 3):
            continue  # unseen (pedestrian 0: blind spells of 3 steps)
        sensors = ("front", "side") if draw > 0.85 else ("front",)
        found[f"p{i}"] = {}
        for name in sensors:
            angle = rng.uniform(0, 2 * np.pi)
            h = rng.uniform(0.5, 2.0) * np.array([[np.cos(angle), np.sin(angle)],
                                                  [-np.sin(angle), np.cos(angle)]])
            bound = rng.uniform(0.2, 0.8)
            offset = 4.0 if (name == "side" and rng.random() < 0.5) else 0.0  # a fault
            y = h @ p + rng.uniform(-bound, bound, 2) * np.linalg.norm(h, axis=1) + offset
            found[f"p{i}"][name] = Strips(h, y, bound * np.linalg.norm(h, axis=1))
    return found


def run(observer_type: type[NodeObserver], gain: str, seed: int) -> list[dict]:
    model = motion_model(Estimator(position_jitter_m=0.3, gain_method=gain), DT)
    observer = observer_type("node", model, EstimatorSettings(gain, "girard", 8))
    rng = np.random.default_rng(seed)
    truth = rng.uniform(-5, 5, (PEOPLE, 2))
    history = []
    for step in range(40):
        truth = truth + rng.uniform(-0.2, 0.2, truth.shape)
        found = detections(rng, truth, step)
        if step % 13 == 12:
            continue  # a step the node skips: the next predicts two steps
        history.append(observer.step(step, found))
    return history


@pytest.mark.parametrize("gain", sorted(track_kernels.GAIN_CODES))
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_compiled_tracks_equal_the_per_track_path_bit_for_bit(gain, seed):
    # Exact, though one side is numba and the other NumPy: both run the same compiled set
    # kernels (meet_2d, the correction, girard_reduce) on the same arrays, and what each does
    # around them (widening the radii, the strips' parallelogram by its adjugate, predicting
    # with the identity) is the same IEEE products, sums, roots and quotients in the same
    # order, with no library function (no sin, no BLAS) whose last bits depend on the CPU.
    compiled, reference = run(NodeObserver, gain, seed), run(PerTrackObserver, gain, seed)
    for ours, theirs in zip(compiled, reference, strict=True):
        assert list(ours) == list(theirs)  # the same tracks, in the same order
        for pid, track in ours.items():
            expected = theirs[pid]
            assert np.array_equal(track.estimate.center, expected.estimate.center)
            assert np.array_equal(track.estimate.generators, expected.estimate.generators)
            assert (track.step, track.detected, track.flagged, track.conflict) == \
                (expected.step, expected.detected, expected.flagged, expected.conflict)


def test_the_compiled_call_settles_the_plain_tracks_and_leaves_the_rest(monkeypatch):
    """Every track update goes through exactly one of the two paths, and both are used."""
    settled_counts, per_track = [], []
    plain_updates = track_kernels.plain_updates

    def counting(*args):
        result = plain_updates(*args)
        settled_counts.append(int(result[0].sum()))
        return result

    monkeypatch.setattr(track_kernels, "plain_updates", counting)
    original = NodeObserver._track
    monkeypatch.setattr(NodeObserver, "_track",
                        lambda self, *a: per_track.append(a[1]) or original(self, *a))
    history = run(NodeObserver, "enclose", 0)
    assert sum(settled_counts) + len(per_track) == sum(len(tracks) for tracks in history)
    assert sum(settled_counts) > 0 and len(per_track) > 0


def test_a_prediction_the_sensor_contradicts_is_left_to_the_vote():
    """One sensor's strips far from the prediction: not settled by the kernel."""
    noise = 0.25 * np.eye(2)
    normals = np.array([np.eye(2)])
    settled, *_ = track_kernels.plain_updates(
        np.zeros((1, 2)), np.array([0.5 * np.eye(2)]), np.array([2]), np.array([1]), noise,
        normals, np.array([[10.0, 0.0]]), np.array([[0.3, 0.3]]), np.array([True]), 0.3, 0,
        8, 1e-6)
    assert not settled[0]

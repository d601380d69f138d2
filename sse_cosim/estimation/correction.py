"""A node's correction step (Proposition 1) that leaves out sensors inconsistent with the rest.

The voters are the node's predicted set and each detecting sensor's measurement set
(:func:`sse_cosim.estimation.vote.vote`). A sensor outside the consistent majority is left
out (paper Fig. 4). A sensor in an unattributable conflict with the prediction is *latched*:
its strips are never intersected again (an intersection with a faulty strip would drop the
truth), but its set is kept in a hull beside the prediction until a sensor that was never
suspect vouches for it. A single-sensor node therefore stays sound, and flags itself, until
the end.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from sse_cosim.estimation.motion import MotionModel
from sse_cosim.estimation.vote import CONSISTENCY_TOL, Probation, interval_hull, vote
from sse_cosim.sets import Strips, Zonotope, intersect_strips


@dataclass(frozen=True)
class Suspicion:
    """A track's sensors that are not used now.

    ``latched``: in an unattributable conflict with the prediction; they return only when a
    sensor that is neither latched nor on probation agrees with them. ``probation``:
    outvoted by a majority of the prediction and the other sensors.
    """

    latched: frozenset[str] = frozenset()
    probation: Probation = field(default_factory=Probation)


@dataclass(frozen=True)
class TrackCorrection:
    """One track's update at one step.

    ``flagged``: detecting sensors left out (inconsistent now, latched or on probation);
    ``conflict``: the estimate keeps a latched sensor's hypothesis in a hull (the node cannot
    attribute a disagreement).
    """

    estimate: Zonotope
    suspicion: Suspicion = Suspicion()
    flagged: frozenset[str] = frozenset()

    @property
    def conflict(self) -> bool:
        return bool(self.suspicion.latched)


def correct(
    model: MotionModel,
    gain_method: str,
    predicted: Zonotope | None,
    strips: Mapping[str, Strips],
    suspicion: Suspicion = Suspicion(),
    tol: float = CONSISTENCY_TOL,
) -> TrackCorrection:
    """The corrected set of one track from its prediction and its sensors' position strips.

    ``predicted`` is None for a new track; ``strips`` (by sensor, in a fixed order) are the
    strips about the true position, widened here by the jitter. Without any inconsistency
    the result is exactly Proposition 1 with every strip (or the first set from them).
    """
    if not strips:
        if predicted is None:
            raise ValueError("a new track needs at least one detection")
        return TrackCorrection(predicted, suspicion)
    names = list(strips)
    paths = {name: model.path_strips(s) for name, s in strips.items()}
    measured = {name: model.initial_set(paths[name], gain_method) for name in names}
    voters = ([] if predicted is None else [predicted]) + [measured[n] for n in names]
    first = 0 if predicted is None else 1  # index of the first sensor among the voters
    outvoted = suspicion.probation.proven
    proven = frozenset(i + first for i, n in enumerate(names) if n in outvoted)
    result = vote([model.path_set(z) for z in voters], tol, proven)
    accepted = [names[i - first] for i in sorted(result.accepted) if i >= first]
    trusted = [n for n in accepted if n not in suspicion.latched and n not in suspicion.probation]
    used = [n for n in accepted if n not in suspicion.probation] if trusted else []
    keeps_prediction = predicted is not None and 0 in result.accepted
    if result.conflict or not (used or keeps_prediction):
        suspects = frozenset(names[i - first] for i in result.suspects if i >= first) \
            or frozenset(names)
        latched = Suspicion(suspicion.latched | suspects, suspicion.probation)
        return TrackCorrection(interval_hull(voters), latched, suspects)
    if keeps_prediction or len(used) > 1:
        stacked = Strips.stack([paths[name] for name in used]) if used else None
        # Without the prediction, two or more sensors agreed against it: start again from them.
        estimate = _combine(model, gain_method, predicted if keeps_prediction else None, stacked)
    else:  # one sensor without the prediction (a new track): its first set, made above
        estimate = measured[used[0]]
    held = [n for n in accepted if n in suspicion.latched and n not in used]
    if held:  # keep the hypothesis "the latched sensor is right" beside the estimate
        estimate = interval_hull([estimate, *(measured[name] for name in held)])
    # Beside a trusted sensor every latched one that voted is settled: vouched for (used) or
    # outvoted (on probation from now on).
    settled = frozenset(names) if trusted else frozenset()
    updated = Suspicion(suspicion.latched - settled, suspicion.probation.update(names, accepted))
    return TrackCorrection(estimate, updated, frozenset(names) - frozenset(used))


def _combine(model: MotionModel, gain_method: str, base: Zonotope | None,
             strips: Strips | None) -> Zonotope:
    """``base`` corrected with the path ``strips`` (Proposition 1); without a base, the first
    set from the strips; without strips, ``base``."""
    if base is None:
        return model.initial_set(strips, gain_method)
    if strips is None:
        return base
    return intersect_strips(base, model.state_strips(strips), gain_method)

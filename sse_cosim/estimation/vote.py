"""The consistency vote among sets of one pedestrian, and probation for outvoted sources.

Paper Section III, "Robust Decision Making". Every set the estimation handles -- a predicted
set, the measurement set of one sensor (the parallelogram of its two widened strips), a node's
estimate, a received estimate brought to the current step -- holds the pedestrian's admissible
path point s_k while the bounds hold (motion model, noise bounds, jitter eps;
:mod:`sse_cosim.estimation.motion`). So sources that obey their bounds always share a point,
and two sets that are *disjoint* prove that one of their sources broke its bounds (paper
Fig. 4: the strips S^3 that meet neither the predicted set nor S^1, S^2). The tests are exact
(:mod:`sse_cosim.sets.overlap`) with a tolerance of :data:`CONSISTENCY_TOL` metres, far below
any fault worth the name and far above rounding, so consistent sources are never flagged.

Attribution is a vote (:func:`vote`): the largest groups of sets with a common point. A
unique largest group that leaves out at most one set is the consistent majority: the sets
outside it are flagged and left out. Anything else (two sources that disagree, a tie) cannot
be attributed, and the result is the interval hull of all the sets -- sound as long as one of
them holds the truth -- with the sources flagged as in *conflict*. A node's observer votes
among its prediction and its sensors (:mod:`sse_cosim.estimation.correction`), the bus among
its own and the received estimates (:mod:`sse_cosim.estimation.bus_screen`).

A source that a majority outvoted -- proven to have broken its bounds -- returns only after
agreeing for :data:`READMIT_STEPS` steps in a row (:class:`Probation`), since a fault that
shrinks below the width of the consistent set can no longer be seen but still drops the truth.
"""

from __future__ import annotations

import itertools
from collections.abc import Collection, Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from sse_cosim.sets import Zonotope, have_common_point, zonotopes_disjoint

CONSISTENCY_TOL = 1e-6  # m: sets closer than this count as meeting
READMIT_STEPS = 10  # steps in a row a left-out source must agree before it is fused again


def largest_consistent_groups(
    sets: Sequence[Zonotope], tol: float = CONSISTENCY_TOL
) -> list[frozenset[int]]:
    """Every largest group of indices whose sets share a point (at least one set given)."""
    n = len(sets)
    meets = {
        pair: not zonotopes_disjoint(sets[pair[0]], sets[pair[1]], tol)
        for pair in itertools.combinations(range(n), 2)
    }
    for size in range(n, 0, -1):
        groups = [
            frozenset(group)
            for group in itertools.combinations(range(n), size)
            if all(meets[pair] for pair in itertools.combinations(group, 2))
            and (size < 3 or have_common_point([sets[i] for i in group], tol))
        ]
        if groups:
            return groups
    raise ValueError("a vote needs at least one set")


@dataclass(frozen=True)
class Vote:
    """Which sets to combine, which to leave out, and whether the disagreement is resolved.

    ``conflict``: no attributable majority; combine nothing, keep the hull of all sets.
    ``suspects`` are then the sets outside some largest consistent group.
    """

    accepted: frozenset[int]
    suspects: frozenset[int]
    conflict: bool


def vote(
    sets: Sequence[Zonotope], tol: float = CONSISTENCY_TOL, proven: frozenset[int] = frozenset()
) -> Vote:
    """The consistent majority of ``sets``: a unique largest group missing at most one set.

    With at most one faulty source among n, the n - 1 correct ones share the truth, so such a
    group is exactly the correct sources. A tie between largest groups is broken for the one
    group without a ``proven`` source (one a majority outvoted before: under the same
    assumption it is the faulty one). Anything else -- two sets that disagree, a tie, or a
    group smaller than n - 1 (more than one fault) -- is a conflict.
    """
    everyone = frozenset(range(len(sets)))
    if len(sets) <= 1:
        return Vote(everyone, frozenset(), False)
    groups = largest_consistent_groups(sets, tol)
    untainted = [group for group in groups if not group & proven]
    if len(groups) > 1 and len(untainted) == 1:
        groups = untainted
    if len(groups) == 1 and len(groups[0]) >= len(sets) - 1:
        return Vote(groups[0], everyone - groups[0], False)
    return Vote(frozenset(), everyone - frozenset.intersection(*groups), True)


def interval_hull(sets: Iterable[Zonotope]) -> Zonotope:
    """The smallest axis-aligned box holding every set: sound for their union."""
    boxes = [z.interval_hull() for z in sets]
    lo = np.min([b[0] for b in boxes], axis=0)
    hi = np.max([b[1] for b in boxes], axis=0)
    return Zonotope.from_interval(lo, hi)


@dataclass(frozen=True)
class Probation:
    """Sources not fused for now, with the steps of agreement each still needs to return.

    A source a majority outvoted is *proven* to have broken its bounds; it may break them
    again by less than the width of the consistent set -- too little to be seen, enough to
    drop the truth -- so it comes back only after :data:`READMIT_STEPS` steps in a row in
    the consistent majority. The bus also puts the suspects of an unattributable conflict
    on probation (not proven: one of them is faulty, nobody knows which).
    """

    remaining: tuple[tuple[str, int, bool], ...] = ()  # (source, steps left, proven)

    def __contains__(self, source: object) -> bool:
        return any(name == source for name, _, _ in self.remaining)

    @property
    def proven(self) -> frozenset[str]:
        """Sources on probation because a majority outvoted them."""
        return frozenset(name for name, _, proven in self.remaining if proven)

    def update(self, voted: Collection[str], accepted: Iterable[str]) -> Probation:
        """After a vote among ``voted``: the outvoted start (again), the others count down."""
        agreed = set(accepted)
        if not self.remaining and agreed.issuperset(voted):
            return self  # nobody waits, nobody outvoted (the usual step)
        left = {name: (steps, proven) for name, steps, proven in self.remaining}
        for source in voted:
            if source not in agreed:
                left[source] = (READMIT_STEPS, True)
            elif source in left:
                steps, proven = left[source]
                left[source] = (steps - 1, proven)
        return Probation(tuple(sorted((n, k, p) for n, (k, p) in left.items() if k > 0)))

    def suspect(self, sources: Iterable[str]) -> Probation:
        """After an unattributable conflict: every suspect waits (again)."""
        left = {name: (steps, proven) for name, steps, proven in self.remaining}
        for source in sources:
            left[source] = (READMIT_STEPS, left.get(source, (0, False))[1])
        return Probation(tuple(sorted((n, k, p) for n, (k, p) in left.items())))

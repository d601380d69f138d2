"""Fault detection and exclusion by set consistency (paper Section III, "Robust Decision Making").

Every set the estimation handles -- a predicted set, the measurement set of one sensor (the
parallelogram of its two widened strips), a node's estimate, a received estimate brought to
the current step -- holds the pedestrian's admissible path point s_k while the bounds hold
(motion model, noise bounds, jitter eps; :mod:`sse_cosim.estimation.motion`). So sources
that obey their bounds always share a point, and two sets that are *disjoint* prove that one
of their sources broke its bounds (paper Fig. 4: the strips S^3 that meet neither the
predicted set nor S^1, S^2). The tests are exact (:mod:`sse_cosim.sets.overlap`, with an
LP for three or more sets) with a tolerance of :data:`CONSISTENCY_TOL` metres, far below any
fault worth the name and far above rounding, so consistent sources are never flagged.

Attribution is a vote (:func:`vote`): the largest groups of sets with a common point. A
unique largest group that leaves out at most one set is the consistent majority: the sets
outside it are flagged and left out. Anything else (two sources that disagree, a tie) cannot
be attributed, and the result is the interval hull of all the sets -- sound as long as one of
them holds the truth -- with the sources flagged as in *conflict*.

Two places use it:

- :func:`correct` -- a node's observer: its predicted set and each of its sensors' sets vote.
  A sensor in an unattributable conflict with the prediction is *latched*: its strips are
  never intersected again (an intersection with a faulty strip would drop the truth), but its
  set is kept in a hull beside the prediction until a sensor that was never suspect vouches
  for it. A single-sensor node therefore stays sound, and flags itself, until the end.
- :class:`BusScreener` -- the bus: its own estimate and the received ones vote per
  pedestrian, after dropping any estimate that lies wholly where some node looked and saw
  nobody (negative information: a phantom). If that leaves nobody, the claims are kept in
  conflict: a phantom cannot be told from a real pedestrian reported in the wrong place.

A source that a majority outvoted -- proven to have broken its bounds -- returns only after
agreeing for :data:`READMIT_STEPS` steps in a row (:class:`Probation`), since a fault that
shrinks below the width of the consistent set can no longer be seen but still drops the truth.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from sse_cosim.estimation.motion import MotionModel
from sse_cosim.estimation.occupancy import ARC_SAFETY, QUAD_SEGMENTS, ClearRegion
from sse_cosim.scenario.model import BUS_NODE
from sse_cosim.sets import (
    Strips,
    Zonotope,
    have_common_point,
    intersect_strips,
    zonotopes_disjoint,
)
from sse_cosim.sets.exact import zonotope_polygon

CONSISTENCY_TOL = 1e-6  # m: sets closer than this count as meeting
HULL_SOURCE = "conflict hull"  # the bus's single fusion input when its sources cannot agree
EXCLUDED = "excluded"
CONFLICT = "conflict"


# --- exact tests and the vote -----------------------------------------------------------


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


# --- who waits, and for how long ------------------------------------------------------

READMIT_STEPS = 10  # steps in a row a left-out source must agree before it is fused again


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

    def update(self, voted: Iterable[str], accepted: Iterable[str]) -> Probation:
        """After a vote among ``voted``: the outvoted start (again), the others count down."""
        left = {name: (steps, proven) for name, steps, proven in self.remaining}
        agreed = set(accepted)
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


# --- a node's observer -----------------------------------------------------------------


@dataclass(frozen=True)
class Suspicion:
    """A track's sensors that are not used now.

    ``latched``: in an unattributable conflict with the prediction; they return only when a
    sensor that is neither latched nor on probation agrees with them. ``probation``:
    outvoted by a majority of the prediction and the other sensors.
    """

    latched: frozenset[str] = frozenset()
    probation: Probation = Probation()


@dataclass(frozen=True)
class Correction:
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
) -> Correction:
    """The corrected set of one track from its prediction and its sensors' position strips.

    ``predicted`` is None for a new track; ``strips`` (by sensor, in a fixed order) are the
    strips about the true position, widened here by the jitter. Without any inconsistency
    the result is exactly Proposition 1 with every strip (or the first set from them).
    """
    if not strips:
        if predicted is None:
            raise ValueError("a new track needs at least one detection")
        return Correction(predicted, suspicion)
    names = list(strips)
    paths = {name: model.path_strips(s) for name, s in strips.items()}
    measured = {name: model.initial_set(paths[name], gain_method) for name in names}
    voters = ([] if predicted is None else [predicted]) + [measured[n] for n in names]
    first = 0 if predicted is None else 1  # index of the first sensor among the voters
    proven = frozenset(i + first for i, n in enumerate(names) if n in suspicion.probation.proven)
    result = vote([model.position_matrix @ z for z in voters], tol, proven)
    accepted = [names[i - first] for i in sorted(result.accepted) if i >= first]
    trusted = [n for n in accepted if n not in suspicion.latched and n not in suspicion.probation]
    used = [n for n in accepted if n not in suspicion.probation] if trusted else []
    keeps_prediction = predicted is not None and 0 in result.accepted
    if result.conflict or not (used or keeps_prediction):
        suspects = frozenset(names[i - first] for i in result.suspects if i >= first) \
            or frozenset(names)
        latched = Suspicion(suspicion.latched | suspects, suspicion.probation)
        return Correction(interval_hull(voters), latched, suspects)
    stacked = Strips.stack([paths[name] for name in used]) if used else None
    # Without the prediction, two or more sensors agreed against it: start again from them.
    estimate = _combine(model, gain_method, predicted if keeps_prediction else None, stacked)
    held = [n for n in accepted if n in suspicion.latched and n not in used]
    if held:  # keep the hypothesis "the latched sensor is right" beside the estimate
        estimate = interval_hull([estimate, *(measured[name] for name in held)])
    # Beside a trusted sensor every latched one that voted is settled: vouched for (used) or
    # outvoted (on probation from now on).
    settled = frozenset(names) if trusted else frozenset()
    updated = Suspicion(suspicion.latched - settled, suspicion.probation.update(names, accepted))
    return Correction(estimate, updated, frozenset(names) - frozenset(used))


def _combine(model: MotionModel, gain_method: str, base: Zonotope | None,
             strips: Strips | None) -> Zonotope:
    """``base`` corrected with the path ``strips`` (Proposition 1); without a base, the first
    set from the strips; without strips, ``base``."""
    if base is None:
        return model.initial_set(strips, gain_method)
    if strips is None:
        return base
    return intersect_strips(base, strips.pullback(model.position_matrix), gain_method)


# --- the bus ---------------------------------------------------------------------------


def contradicted(
    position: Zonotope, clear: Sequence[ClearRegion], jitter: float, reach: float,
    tol: float = CONSISTENCY_TOL,
) -> bool:
    """Whether a path set (2-D, about s_k) lies wholly where a node looked and saw nobody.

    A region R seen ``age`` steps ago without the pedestrian proves p_{k-age} is outside R,
    and p_{k-age} is within jitter + reach * age of s_k. If the whole set lies in R shrunk by
    that slack, no point of it can be s_k: the source that reported the set is wrong (or the
    viewer missed a pedestrian it could see, which the sensor model rules out). The erosion
    uses polygons inscribed in the true one (radius scaled by ARC_SAFETY).
    """
    lo, hi = position.interval_hull()
    shape = None
    for item in clear:
        slack = jitter + reach * item.age + tol
        x0, y0, x1, y1 = item.region.bounds if not item.region.is_empty else (0, 0, -1, -1)
        if not (x0 + slack <= lo[0] and y0 + slack <= lo[1] and hi[0] <= x1 - slack
                and hi[1] <= y1 - slack):
            continue  # the set pokes out of the region's box: it cannot lie in the region
        shape = zonotope_polygon(position) if shape is None else shape
        inner = item.region.buffer(-ARC_SAFETY * slack, quad_segs=QUAD_SEGMENTS)
        if not inner.is_empty and inner.covers(shape):
            return True
    return False


@dataclass(frozen=True)
class BusScreen:
    """What the bus fuses per pedestrian after the vote, and whom it flagged.

    ``own``: pedestrian ids whose own estimate is fused; ``received``: pedestrian id ->
    sender -> the estimates fused (a conflict leaves only their hull, under
    :data:`HULL_SOURCE`); ``excluded`` / ``conflicts``: pedestrian id -> flagged sources;
    ``gone``: pedestrians that left the scene (nobody detects them, and every set of them lies
    where some node looked and saw nobody).
    """

    own: frozenset[str] = frozenset()
    received: dict[str, dict[str, Zonotope]] = field(default_factory=dict)
    excluded: dict[str, frozenset[str]] = field(default_factory=dict)
    conflicts: dict[str, frozenset[str]] = field(default_factory=dict)
    gone: frozenset[str] = frozenset()

    def inputs(self, person_id: str, own_estimate: Zonotope | None) -> dict[str, Zonotope]:
        """The sets fused for ``person_id`` by source, given the bus's own estimate of it."""
        mine = {BUS_NODE: own_estimate} \
            if person_id in self.own and own_estimate is not None else {}
        return mine | self.received.get(person_id, {})

    def flags(self) -> dict[str, str]:
        """Source -> ``excluded`` or ``conflict`` for every source flagged at this step."""
        result = {s: CONFLICT for sources in self.conflicts.values() for s in sources}
        result |= {s: EXCLUDED for sources in self.excluded.values() for s in sources}
        return result


class BusScreener:
    """The bus's screen of its fusion inputs, with each pedestrian's sources on probation."""

    def __init__(self, model: MotionModel, reach: float, tol: float = CONSISTENCY_TOL) -> None:
        self.model = model
        self.reach = reach  # how far a path moves in one step (m)
        self.tol = tol
        self._probation: dict[str, Probation] = {}

    def screen(
        self,
        own: Mapping[str, Zonotope],
        received: Mapping[str, Mapping[str, Zonotope]],
        clear: Mapping[str, Sequence[ClearRegion]],
        detected: frozenset[str] = frozenset(),
    ) -> BusScreen:
        """Drop contradicted estimates, then keep each pedestrian's consistent majority.

        ``own``: the bus's estimates by pedestrian id; ``received``: pedestrian id -> sender
        -> estimate at the current step; ``clear``: pedestrian id -> regions seen without it;
        ``detected``: pedestrians some node (the bus, or a sender in its newest message)
        detects now.

        A pedestrian nobody detects whose every estimate is contradicted has left the scene
        (SUMO removes pedestrians at their destination): under the sensor model it is in
        none of the places its motion allows, so it is dropped, not flagged. A *detected*
        pedestrian whose every estimate is contradicted stays, in conflict (a phantom).
        """
        gone: set[str] = set()
        kept_own: set[str] = set()
        kept: dict[str, dict[str, Zonotope]] = {}
        excluded: dict[str, frozenset[str]] = {}
        conflicts: dict[str, frozenset[str]] = {}
        for person_id in sorted(own.keys() | received.keys()):
            sources = ({BUS_NODE: own[person_id]} if person_id in own else {}) | {
                s: received[person_id][s] for s in sorted(received.get(person_id, {}))}
            names = [s for s, z in sources.items() if not self._contradicted(
                z, clear.get(person_id, ()))]
            if not names and person_id not in detected:
                gone.add(person_id)
                continue
            if not names:  # a phantom, or a real pedestrian placed wrong: keep it, in conflict
                names, suspects = list(sources), frozenset(sources)
                chosen = []
            else:
                chosen, suspects = self._vote(person_id, [sources[s] for s in names], names)
            if suspects:  # keep every claim that is not contradicted, in one hull
                conflicts[person_id] = suspects
                kept[person_id] = {HULL_SOURCE: interval_hull(sources[s] for s in names)}
                left_out = frozenset(sources) - frozenset(names)
            else:
                left_out = frozenset(sources) - frozenset(chosen)
                if chosen:
                    kept_own |= {person_id} if BUS_NODE in chosen else set()
                    kept[person_id] = {s: sources[s] for s in chosen if s != BUS_NODE}
            if left_out:
                excluded[person_id] = left_out
        return BusScreen(frozenset(kept_own), kept, excluded, conflicts, frozenset(gone))

    def _contradicted(self, estimate: Zonotope, clear: Sequence[ClearRegion]) -> bool:
        return contradicted(self.model.position_matrix @ estimate, clear, self.model.jitter,
                            self.reach, self.tol)

    def _vote(self, person_id: str, sets: Sequence[Zonotope],
              names: Sequence[str]) -> tuple[list[str], frozenset[str]]:
        """(sources to fuse, suspects of a conflict): a majority minus those on probation."""
        probation = self._probation.get(person_id, Probation())
        proven = frozenset(i for i, name in enumerate(names) if name in probation.proven)
        result = vote([self.model.position_matrix @ z for z in sets], self.tol, proven)
        if result.conflict:
            suspects = frozenset(names[i] for i in result.suspects)
            self._probation[person_id] = probation.suspect(suspects)
            return [], suspects
        chosen = [names[i] for i in sorted(result.accepted)]
        self._probation[person_id] = probation.update(names, chosen)
        trusted = [s for s in chosen if s not in probation]
        if trusted:
            return trusted, frozenset()
        return [], frozenset(chosen)  # only sources on probation agree: more than one fault


# --- what the trace shows ----------------------------------------------------------------


class ScreenedTrack(Protocol):
    """The part of an observer's track the flags need."""

    flagged: frozenset[str]
    conflict: bool


@dataclass(frozen=True)
class StepFlags:
    """One step's flags: per sensor (left out), per node (``excluded``/``conflict``/""),
    and whether the bus's own picture is inconsistent (the controller's fallback)."""

    sensors: dict[str, bool] = field(default_factory=dict)
    nodes: dict[str, str] = field(default_factory=dict)
    inconsistent: bool = False


def step_flags(
    sensors: Iterable[str],
    tracks: Mapping[str, Mapping[str, ScreenedTrack]],
    screen: BusScreen,
    remote_inconsistency: bool,
) -> StepFlags:
    """Flags of every sensor and node; ``remote_inconsistency``: a sender reported that its
    own sources disagreed (the newest message of some sender says so).

    A node is ``excluded`` when the bus left one of its estimates out, in ``conflict`` when
    its own sensors and prediction disagree unattributably or it is a suspect of such a
    disagreement at the bus. The bus's picture is inconsistent when anything the bus knows
    of is flagged: its own tracks, the screen, or an inconsistency reported by a sender.
    """
    left_out = {s for node_tracks in tracks.values() for t in node_tracks.values()
                for s in t.flagged}
    at_bus = screen.flags()
    nodes = {}
    for node, node_tracks in tracks.items():
        in_conflict = any(t.conflict for t in node_tracks.values())
        nodes[node] = at_bus.get(node) or (CONFLICT if in_conflict else "")
    own = tracks.get(BUS_NODE, {})
    inconsistent = bool(at_bus) or remote_inconsistency or any(
        t.conflict or t.flagged for t in own.values())
    return StepFlags({s: s in left_out for s in sensors}, nodes, inconsistent)

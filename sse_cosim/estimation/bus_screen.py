"""The bus's screen of its fusion inputs: negative information, then a vote per pedestrian.

Paper Section III, "Robust Decision Making". Per pedestrian the bus's own estimate and the
received ones vote (:func:`sse_cosim.estimation.vote.vote`), after dropping any estimate that
lies wholly where some node looked and saw nobody (negative information: a phantom). If that
leaves nobody, the claims are kept in conflict: a phantom cannot be told from a real
pedestrian reported in the wrong place. Sources a majority outvoted wait on probation.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from sse_cosim.estimation.motion import MotionModel
from sse_cosim.estimation.occupancy import ClearRegion
from sse_cosim.estimation.vote import CONSISTENCY_TOL, Probation, interval_hull, vote
from sse_cosim.regions import RegionKind
from sse_cosim.sets import Zonotope

HULL_SOURCE = "conflict hull"  # the bus's single fusion input when its sources cannot agree
EXCLUDED = "excluded"
CONFLICT = "conflict"


def contradicted(
    position: Zonotope, clear: Sequence[ClearRegion], model: MotionModel, kind: RegionKind,
    tol: float = CONSISTENCY_TOL,
) -> bool:
    """Whether a path set (2-D, about s_k) lies wholly where a node looked and saw nobody.

    A region R seen ``age`` steps ago without the pedestrian proves p_{k-age} is outside R,
    and p_{k-age} is within jitter + reach(age) of s_k (``model``'s jitter and reach). If the
    whole set lies in R shrunk by that slack, no point of it can be s_k: the source that
    reported the set is wrong (or the viewer missed a pedestrian it could see, which the
    sensor model rules out). The erosion lies inside the exact one (the Region contract);
    each region keeps its erosions, since every source of every pedestrian is tested against
    the same views at the same slack.
    """
    lo, hi = position.interval_hull()
    shape = None
    for item in clear:
        slack = model.jitter + model.reach_m(item.age) + tol
        x0, y0, x1, y1 = item.region.bounds
        if not (x0 + slack <= lo[0] and y0 + slack <= lo[1] and hi[0] <= x1 - slack
                and hi[1] <= y1 - slack):
            continue  # the set pokes out of the region's box: it cannot lie in the region
        shape = kind.convex_outer(position.vertices()) if shape is None else shape
        inner = item.region.erode(slack)
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
    where some node looked and saw nobody); ``node``: the screening vehicle's id (the source
    name of its own estimates).
    """

    own: frozenset[str] = frozenset()
    received: dict[str, dict[str, Zonotope]] = field(default_factory=dict)
    excluded: dict[str, frozenset[str]] = field(default_factory=dict)
    conflicts: dict[str, frozenset[str]] = field(default_factory=dict)
    gone: frozenset[str] = frozenset()
    node: str = ""

    def inputs(self, person_id: str, own_estimate: Zonotope | None) -> dict[str, Zonotope]:
        """The sets fused for ``person_id`` by source, given the vehicle's own estimate of
        it."""
        mine = {self.node: own_estimate} \
            if person_id in self.own and own_estimate is not None else {}
        return mine | self.received.get(person_id, {})

    def flags(self) -> dict[str, str]:
        """Source -> ``excluded`` or ``conflict`` for every source flagged at this step."""
        result = {s: CONFLICT for sources in self.conflicts.values() for s in sources}
        result |= {s: EXCLUDED for sources in self.excluded.values() for s in sources}
        return result


class BusScreener:
    """An automated vehicle's screen of its fusion inputs (``node`` its id), with each
    pedestrian's sources on probation."""

    def __init__(self, model: MotionModel, kind: RegionKind, node: str,
                 tol: float = CONSISTENCY_TOL) -> None:
        self.model = model
        self.kind = kind
        self.node = node
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
            sources = ({self.node: own[person_id]} if person_id in own else {}) | {
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
                    kept_own |= {person_id} if self.node in chosen else set()
                    kept[person_id] = {s: sources[s] for s in chosen if s != self.node}
            if left_out:
                excluded[person_id] = left_out
        return BusScreen(frozenset(kept_own), kept, excluded, conflicts, frozenset(gone),
                         self.node)

    def _contradicted(self, estimate: Zonotope, clear: Sequence[ClearRegion]) -> bool:
        return contradicted(self.model.path_set(estimate), clear, self.model, self.kind,
                            self.tol)

    def _vote(self, person_id: str, sets: Sequence[Zonotope],
              names: Sequence[str]) -> tuple[list[str], frozenset[str]]:
        """(sources to fuse, suspects of a conflict): a majority minus those on probation."""
        probation = self._probation.get(person_id, Probation())
        proven = frozenset(i for i, name in enumerate(names) if name in probation.proven)
        result = vote([self.model.path_set(z) for z in sets], self.tol, proven)
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

"""An automated vehicle's second fusion level over anonymous tracks, and its negative information.

With ``estimator.association = "anonymous"`` no set carries a pedestrian's id: every node's
tracks are keyed ``"<node>:<id>"`` (:class:`~sse_cosim.estimation.observer.AnonymousNodeObserver`),
and the vehicle fuses its own and the received tracks only where they certainly hold the same
pedestrians (:func:`~sse_cosim.estimation.association.associate_nodes`, Proposition 2). Each
result is a *fused track*, named by its sources joined with ``+`` (``"bus:3+rsu:0"``); the
names hold for one step only (a track may merge or gain a pedestrian from one step to the
next), so nothing downstream may carry a fused track's history across steps.

Negative information for a fused track F (the regions seen without its pedestrians,
:class:`~sse_cosim.estimation.occupancy.ClearRegion`): node b's view R, taken ``age`` steps
ago, is clear for F when no track of b that joined a detection at that step (its
``detected`` tracks, as b sent them, predicted to now) meets F's path set.

Proof. Let P be a pedestrian whose path point s_k lies in F, and suppose P's position
p_{k-age} was in R. Then b's sensors detected P at step k - age (assumption A2 of
:mod:`~sse_cosim.estimation.association`), so P's state then lay in one of b's tracks that
joined a detection at that step (the first level's invariant, in the form the association
module proves it: a pedestrian detected now is in a track corrected with a detection now),
and that track's prediction to step k holds P's state at k (A3): it meets F at s_k. So if
no detected track of b meets F, no pedestrian of F was in R at step k - age, which is what a
clear region states. The vehicle's own node is one such b (age 0, its sensors' regions now).
A track that joined no detection (where a pedestrian may have hidden, or one whose pedestrians
left every view) does not keep a view from being clear: every pedestrian in view is in a
detected track too, so the test needs only those. It errs towards "meets" (tolerance), so it
never declares a region clear by rounding.

Ended tracks. A node ends only tracks that joined no detection at that step
(:class:`~sse_cosim.estimation.observer.AnonymousNodeObserver`), so the statement above (a
pedestrian in b's view is in one of b's detected tracks) and Proposition 2's certain pairs
hold with the tracks it keeps; an ended track's pedestrians are the unobserved area's from
then on (:mod:`~sse_cosim.estimation.occupancy`, :class:`~sse_cosim.estimation.v2x.V2XLink`),
which the controller takes as possibly occupied as it does every region.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from sse_cosim.estimation.association import (
    MEET_TOL,
    NodeTracks,
    associate_nodes,
    boxes_meet,
    set_boxes,
)
from sse_cosim.estimation.bus_fusion import fuse_sets
from sse_cosim.estimation.bus_screen import BusScreen
from sse_cosim.estimation.flags import step_flags
from sse_cosim.estimation.fusion_centre import BaseFusionCentre, BusEstimate
from sse_cosim.estimation.observer import Track
from sse_cosim.estimation.occupancy import ClearRegion
from sse_cosim.estimation.v2x import SharedPicture
from sse_cosim.regions import Region
from sse_cosim.sets import Zonotope, zonotopes_disjoint


@dataclass(frozen=True)
class _Node:
    """One node's tracks at the fusing step by key, its view, that view's age (steps) and the
    keys of the tracks that joined a detection when the view was taken."""

    node: str
    tracks: dict[str, Zonotope]
    view: Region
    age: int
    detected: frozenset[str]


class AnonymousFusionCentre(BaseFusionCentre):
    """Automated vehicle ``node``'s fusion of anonymous tracks, with their clear regions."""

    def step(self, tracks: Mapping[str, Mapping[str, Track]], shared: SharedPicture,
             own_view: Region, detected: frozenset[str],
             ) -> tuple[BusEstimate, dict[str, list[ClearRegion]]]:
        """The fused tracks of this step and, per fused track, the regions seen without its
        pedestrians (module docstring).

        ``tracks``: node -> track key -> local track (the vehicle's own among them);
        ``shared``: the senders' newest messages brought to this step; ``own_view``: the
        union of the vehicle's sensors' visible regions now; ``detected``: the keys of the
        node tracks some node detects now (a fused track is in view if one of them is in it).
        """
        mine = tracks.get(self.node, {})
        own = {key: t.estimate for key, t in mine.items()}
        seen = frozenset(key for key, t in mine.items() if t.detected)
        nodes = [_Node(self.node, own, own_view, 0, seen), *_senders(shared)]
        fused = associate_nodes([self._node_tracks(n) for n in nodes], self.model,
                                self._fuse, self.kind)
        ranked = {n.node: sorted(n.tracks) for n in nodes}
        every = {key: z for n in nodes for key, z in n.tracks.items()}  # keys: network-wide
        estimates: dict[str, Zonotope] = {}
        inputs: dict[str, dict[str, Zonotope]] = {}
        in_view: set[str] = set()
        for track in fused:
            keys = [ranked[node][index] for node, index in track.sources]
            name = "+".join(keys)
            estimates[name] = track.estimate
            inputs[name] = {key: every[key] for key in keys}
            if not detected.isdisjoint(keys):
                in_view.add(name)
        clear = self._clear(estimates, nodes)
        screen = BusScreen(node=self.node)  # no vote: it needs to know who is who
        flags = step_flags(self.sensors, tracks, screen, bool(shared.inconsistent), self.node)
        return BusEstimate(screen, estimates, flags, inputs, frozenset(in_view)), clear

    def _node_tracks(self, node: _Node) -> NodeTracks:
        """``node``'s tracks for :func:`associate_nodes` (ids: the keys' ranks), its view,
        and how far a pedestrian may have walked since the view was taken."""
        return NodeTracks(node.node, dict(enumerate(node.tracks[k] for k in sorted(node.tracks))),
                          node.view, self.model.reach_m(node.age))

    def _fuse(self, sets: Sequence[Zonotope]) -> Zonotope:
        return fuse_sets(sets, self.fusion_method, self.settings, self.model)

    def _detected_paths(self, node: _Node) -> _Paths:
        """The path sets of ``node``'s detected tracks, with their boxes."""
        return _Paths.of([self.model.path_set(node.tracks[key]) for key in sorted(node.detected)
                          if key in node.tracks])

    def _clear(self, fused: Mapping[str, Zonotope], nodes: Sequence[_Node]
               ) -> dict[str, list[ClearRegion]]:
        """Per fused track, the views of the nodes none of whose detected tracks meets it
        (module docstring), in the nodes' order: every fused track's box against every
        detected track's at once, node by node, then exactly where they come within
        :data:`MEET_TOL`."""
        names = list(fused)
        paths = _Paths.of([self.model.path_set(fused[name]) for name in names])
        clear: dict[str, list[ClearRegion]] = {name: [] for name in names}
        for node in nodes:
            if node.view.is_empty:
                continue
            detected = self._detected_paths(node)
            near = boxes_meet(paths.lo, paths.hi, detected.lo, detected.hi, MEET_TOL)
            for f, name in enumerate(names):
                if not any(not zonotopes_disjoint(paths.sets[f], detected.sets[k], MEET_TOL)
                           for k in np.flatnonzero(near[f])):
                    clear[name].append(ClearRegion(node.view, node.age))
        return clear


@dataclass(frozen=True)
class _Paths:
    """Path sets (k of them) and their boxes, lo and hi (k, 2)."""

    sets: list[Zonotope]
    lo: np.ndarray
    hi: np.ndarray

    @classmethod
    def of(cls, sets: list[Zonotope]) -> _Paths:
        return cls(sets, *set_boxes(sets))


def _senders(shared: SharedPicture) -> list[_Node]:
    """Every sender's tracks in its newest message (predicted to now), view, age and the keys
    of the tracks it detected then."""
    tracks: dict[str, dict[str, Zonotope]] = {sender: {} for sender in shared.regions}
    for key, by_sender in shared.estimates.items():
        for sender, estimate in by_sender.items():
            tracks[sender][key] = estimate
    return [_Node(sender, tracks[sender], shared.regions[sender], shared.ages[sender],
                  shared.detected.get(sender, frozenset()))
            for sender in sorted(shared.regions)]

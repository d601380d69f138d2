"""Where pedestrians can be, refined with negative information (regions, not zonotopes).

A sensor that sees a region V and does not detect a pedestrian proves the pedestrian is not
in V (every pedestrian inside a visible region is detected). That knowledge is not convex,
so the zonotopes (sound on their own) ignore it, and the bus keeps regions instead
(:mod:`sse_cosim.regions`):

- :class:`OccupancyTracker`, per *known* pedestrian, a region R_k for its path s;
- :class:`UnobservedArea`, where a pedestrian *nobody has detected* may be.

Both reason about the path s of :mod:`sse_cosim.estimation.motion` (p = s + e, ||e|| <= eps,
s moving at most v dt per step: the model's reach, ``MotionModel.reach_m``): if p is in a set
A, then s is in A (+) disc(eps). So

    U_k = (U_{k-1} (+) disc(v dt)) ∩ ((walkable minus views_k) (+) disc(eps)),

and the pedestrian itself is in (U_k (+) disc(eps)) ∩ walkable, minus what the bus sees now.
Shared views arrive ``latency`` steps late: U is kept exactly up to step k - latency (when
those views were taken) and carried to step k with the bus's own views. Every dilation holds
the exact one (the Region contract), so each step over-approximates.

The picture asks about U only near the crossings on the route (the window: any shape, in
several pieces with several crossings), so U is tracked in a bounded area B around that
window (B ⊇ window (+) disc(eps)) and the walkable ground outside B counts as possibly
occupied at every step: with O = (walkable (+) disc(eps)) minus B,

    Ũ_k = ((Ũ_{k-1} ∪ O) (+) disc(v dt)) ∩ ((walkable minus views_k) (+) disc(eps)) ∩ B

contains U_k ∩ B whenever Ũ_{k-1} contains U_{k-1} ∩ B, since U_{k-1} ⊆ (U_{k-1} ∩ B) ∪ O.
Only O's rim within v dt of B matters, and it moves the same way every step (its dilation is
computed once), so the per-step polygons stay the size of the window, not of the whole road.

A known pedestrian's path region is kept in B the same way (:class:`TrackedWindow`): once its
region has been cut by B's edge the pedestrian may be outside B, and from then on the path
region also takes in O's rim moved one step, until its fused set lies inside B. So
either the pedestrian is in its region or it is outside the window; there, as for hidden
ground, every walkable place counts as possibly occupied. Without this a pedestrian who has
left every view keeps a region that grows without bound.

Ended tracks (anonymous detections, :class:`EndedTrack`). A node ends an anonymous track that
has joined no detection for a while (:class:`~sse_cosim.estimation.observer.AnonymousNodeObserver`)
and hands its pedestrians to the unobserved area: a track T ended at step e adds its path set
(moved to the step it is added at) to that step's path region, before that step's views cut it:

    U_t = (((U_{t-1} (+) disc(v dt)) ∪ A_t) ∩ ((walkable minus views_t) (+) disc(eps))) ∩ B,

with A_t the union of the path sets of the tracks handed over at step t (a set of step e
added at t >= e is moved by dilation by v dt (t - e), which holds the path point at t, A3).
Proof that a pedestrian P of T (s_e in T's path set) is in U from then on, until a view that
cuts U sees it: at the step t it is added, s_t lies in A_t; at every later step, s moves at
most v dt (in U_{t-1} (+) disc(v dt)), or P entered B from outside (the inflow, as above); and
a view at step t' that removes s_{t'} saw P, so that viewer detected P at t' and holds it in
one of its tracks that joined a detection then (:mod:`~sse_cosim.estimation.association`),
which is not an ended one (a track ends only at a step it joined nothing). So at each step P
is in U or in a track the vehicle holds, as before T ended. Which track ends when does not
matter for soundness: any track may be handed over, as long as it joined no detection at
its last step. The vehicle's own ended tracks are added at the step they ended (the layers
after the base are recomputed with them); a sender's, at the base's step when its message
arrives (:class:`~sse_cosim.estimation.v2x.V2XLink`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from sse_cosim.estimation.motion import MotionModel
from sse_cosim.regions import Region, RegionKind, apart
from sse_cosim.sets import Zonotope

COARSEN_M = 0.01  # regions are kept at most this much larger, in few pieces
ROUNDING_GUARD_M = 1e-9  # far above any rounding of a set's coordinates (metres, < 1e5)


@dataclass(frozen=True)
class EndedTrack:
    """A track a node ended at ``step`` (its state set ``estimate`` then): its pedestrians, if
    it holds any, are the unobserved area's from that step on (module docstring)."""

    step: int
    estimate: Zonotope


@dataclass(frozen=True)
class ClearRegion:
    """A region some node saw, ``age`` steps ago, without the pedestrian in question."""

    region: Region
    age: int


class OccupancyTracker:
    """The bus's refined region of every known pedestrian (one region each).

    With ``walkable`` ground given, each path region is also kept within walkable (+)
    disc(eps): pedestrians stay on walkable ground (an assumption, docs/controller.md), so a
    pedestrian who has left every view stays confined to the walkable ground it can have
    reached since it was last seen, instead of spreading over the road. With a ``window`` as
    well, each is kept within B (:class:`TrackedWindow`): a pedestrian is then in its region or
    outside the window, and ``beyond`` names those who may be outside B. By induction over the
    steps: a path s outside B is in ``beyond`` (it left B from its region, or was already
    outside, and its fused set, which holds s, is not inside B), and a path inside B is in its
    region (it was there a step before, or it came in from outside through the inflow).
    """

    def __init__(self, model: MotionModel, kind: RegionKind, walkable: Region | None = None,
                 window: Region | None = None) -> None:
        if window is not None and walkable is None:
            raise ValueError("a tracked window needs the walkable ground")
        self.model = model
        self.kind = kind
        self._walkable = walkable
        self._ground = None if walkable is None else walkable.dilate(model.jitter)
        self._window = None if window is None else TrackedWindow(window, walkable, model, kind)
        self._paths: dict[str, Region] = {}
        self._step: int | None = None
        self.beyond: frozenset[str] = frozenset()  # pedestrians who may be outside B now

    def _on_foot(self, area: Region) -> Region:
        """The walkable part of ``area`` (all of it without walkable ground given): where the
        pedestrian itself can have been (A1)."""
        return area if self._walkable is None else area.intersection(self._walkable)

    @property
    def paths(self) -> dict[str, Region]:
        """Each pedestrian's path region at the last update (where its path s may be: the
        region :meth:`update` returned is it grown by the jitter and cut by what is seen
        now), what the earliest arrivals are measured from."""
        return dict(self._paths)

    def forget(self) -> None:
        """Drop every pedestrian's history: the next update starts from its sets alone."""
        self._paths = {}
        self._step = None
        self.beyond = frozenset()

    def update(
        self,
        step: int,
        fused: Mapping[str, Zonotope],
        clear: Mapping[str, Sequence[ClearRegion]],
    ) -> dict[str, Region]:
        """Where each pedestrian of ``fused`` can be at ``step`` (its position, with jitter)."""
        elapsed = 0 if self._step is None else step - self._step
        eps = self.model.jitter
        paths: dict[str, Region] = {}
        regions: dict[str, Region] = {}
        beyond: set[str] = set()
        for person_id, estimate in fused.items():
            path_set = self.model.path_set(estimate)
            if self._window is not None and self._window.misses(path_set):
                beyond.add(person_id)  # its region would be cut to nothing by B
                paths[person_id] = regions[person_id] = self.kind.empty()
                continue
            path = self.kind.convex_outer(path_set.vertices())
            # it may still be outside B unless its whole set is inside (the set holds it)
            outside = person_id in self.beyond and not self._window.tracked.covers(path)
            previous = self._paths.get(person_id)
            if previous is not None:
                moved = previous.dilate(self.model.reach_m(elapsed))
                if outside:
                    moved = moved.union(self._window.inflow(elapsed))
                path = moved.intersection(path)
            if self._ground is not None and not self._ground.covers(path):
                path = path.intersection(self._ground)
            if self._window is not None and (outside or path.is_empty
                                             or not self._window.tracked.covers(path)):
                beyond.add(person_id)
                path = self._window.clip(path)
            now_clear = [c.region for c in clear.get(person_id, ()) if c.age == 0]
            for item in clear.get(person_id, ()):
                # p was outside item.region ``age`` steps ago, on walkable ground, within
                # eps + reach(age) of s now (so ground nobody saw off the walkable, such as a
                # vehicle's shadow on the road, keeps no path alive)
                slack = eps + self.model.reach_m(item.age)
                if apart(path, item.region, slack) or path.distance(item.region) > slack:
                    # the region misses path (+) disc(slack): a point of path within eps of
                    # walkable ground has such ground, unseen, within slack of path, and the
                    # cut keeps it; left uncut, the rest stays too (a larger region)
                    continue
                outside = self._on_foot(path.dilate(slack)).difference(item.region)
                path = path.intersection(outside.dilate(slack))
            cut_path = path  # with eps = 0, cut with every region clear now (slack 0)
            paths[person_id] = path = path.coarsen(COARSEN_M)
            region = path.dilate(eps)
            if now_clear and region is not cut_path:
                # (the same cut again would be the identity, and GEOS's floating overlay can
                # return it empty when the region's edges lie on the view's, which this cut
                # gave them: locationtech/jts#1000, tests/estimation/test_association.py)
                region = region.difference(self.kind.union_all(now_clear))
            regions[person_id] = region
        self._paths = paths
        self._step = step
        self.beyond = frozenset(beyond)
        return regions


class TrackedWindow:
    """The bounded area B ⊇ window (+) disc(eps) in which path regions are tracked, and the
    inflow: where a path outside B at one step can be inside B some steps later (O's rim moved,
    O = (walkable (+) disc(eps)) minus B)."""

    def __init__(self, window: Region, walkable: Region, model: MotionModel,
                 kind: RegionKind) -> None:
        self.model = model
        self.kind = kind
        self.jitter = model.jitter
        self.walkable = walkable
        self.tracked = window.dilate(self.jitter)  # B
        self._inflows: dict[int, Region] = {}

    def inflow(self, steps: int = 1) -> Region:
        """Where a path outside B now can be inside B or near it ``steps`` steps later
        (computed once per number of steps)."""
        if steps not in self._inflows:
            reach, eps = self.model.reach_m(steps), self.jitter
            near = self.walkable.intersection(self.tracked.dilate(reach + eps))
            rim = near.dilate(eps).difference(self.tracked)
            self._inflows[steps] = rim.dilate(reach) if reach > 0 else self.kind.empty()
        return self._inflows[steps]

    def misses(self, path_set: Zonotope) -> bool:
        """Whether the box around ``path_set`` (2-D) lies apart from B's bounding box: then
        the path is outside B (by more than a rounding of the box's sums: its vertices, summed
        in another order, may stray from it by that)."""
        (x0, y0), (x1, y1) = path_set.interval_hull()
        b, g = self.tracked.bounds, ROUNDING_GUARD_M
        return x1 + g < b[0] or b[2] < x0 - g or y1 + g < b[1] or b[3] < y0 - g

    def clip(self, region: Region) -> Region:
        """``region`` ∩ B."""
        return region.intersection(self.tracked)


class UnobservedArea:
    """Walkable area where an undetected pedestrian may be, as the bus knows it: all of it, or
    (with a ``window``) at least every such place inside the window.

    Groups. A long route's window is many pieces far apart (one per crossing of a town's bus
    line), and a step moves a path region by a few decimetres: pieces more than
    :data:`GROUP_GAP_M` apart are tracked as separate groups, each with the walkable ground,
    the inflow and the views near it (a view that does not come near a group cuts nothing
    there), and the path region is the union of theirs. A group that no view comes near and
    no hand-over reaches is moved by the same computation on its path region alone, so its
    steps at rest are looked up once they come back to a region they started from
    (:class:`_Rest`; :meth:`~sse_cosim.regions.Region.same`: the same representation, so the
    same result again). A group whose path region is still its whole ground (its part of B
    within the jitter of walkable ground, where it starts: every path a pedestrian there may
    have) keeps it while at rest, as it is: a step at rest from the whole ground gives the
    whole ground again (nothing is seen there), and it holds every path the group can. Such a
    group, one far ahead of the bus, costs nothing until a view comes near; GEOS's overlays
    of a large one need not settle into a cycle (line 300's town centre did not in 80 steps).
    With one group (the paper's road, the junction, the town's street) every step is computed
    as for the whole window at once."""

    def __init__(self, walkable: Region, model: MotionModel, latency_steps: int,
                 kind: RegionKind, window: Region | None = None) -> None:
        self.model = model
        self.kind = kind
        self.latency = latency_steps
        self._window = None if window is None else TrackedWindow(window, walkable, model, kind)
        if self._window is not None:
            walkable = walkable.intersection(self._window.tracked.dilate(model.jitter))
        self.walkable = walkable  # the walkable ground whose views matter
        self._groups = self._grouped()
        # path regions at self._base_step, one per group
        self._base = tuple(g.clip(g.walkable.dilate(model.jitter)) for g in self._groups)
        self._whole = self._base  # each group's whole ground (class docstring)
        self._base_step: int | None = None
        self._own: dict[int, Region] = {}  # the bus's views not yet in the base
        self._ended: dict[int, list[Region]] = {}  # step -> path sets handed over
        self._base_moved: dict[int, tuple[Region, Region]] = {}  # group -> (base, moved)
        self._paths = self._base  # where an undetected pedestrian's path may be now
        self.path: Region = self._union(self._paths)

    def _grouped(self) -> list[_Group]:
        """The window's pieces, those closer than :data:`GROUP_GAP_M` together, each group
        with its walkable ground and inflow (class docstring); one group without a window."""
        window = self._window
        if window is None:
            return [_Group(self.walkable, None, None)]
        parts = self._window_parts(window.tracked)
        if len(parts) == 1:
            return [_Group(self.walkable, window.tracked, window.inflow())]
        eps = self.model.jitter
        groups = []
        for tracked in parts:
            ground = self.walkable.intersection(tracked.dilate(eps))
            groups.append(_Group(ground, tracked, window.inflow().intersection(tracked),
                                 self.kind.reach_of(eps)))
        return groups

    def _window_parts(self, tracked: Region) -> list[Region]:
        """B's pieces, those within :data:`GROUP_GAP_M` of each other as one (B itself if
        they all are)."""
        groups: list[list[Region]] = []
        for piece in tracked.parts():
            near = [g for g in groups if any(piece.distance(o) <= GROUP_GAP_M for o in g)]
            groups = [g for g in groups if all(g is not n for n in near)]
            groups.append([piece, *(o for g in near for o in g)])
        if len(groups) <= 1:
            return [tracked]
        return [self.kind.union_all(group) for group in groups]

    def update(
        self, step: int, own_view: Region, shared_views: Sequence[Region],
        ended: Sequence[EndedTrack] = (),
    ) -> Region:
        """Where an undetected pedestrian may be at ``step``.

        ``own_view`` is what the bus sees now; ``shared_views`` what other nodes saw at
        ``step - latency`` (the messages delivered now); ``ended``: the tracks handed over
        now (the bus's own ended at ``step``, the senders' of the messages delivered now, each
        ended at or before ``step - latency``; module docstring). Its path region (U_k, which
        the returned area is grown from) is :attr:`path` afterwards.
        """
        self._own[step] = own_view
        target = step - self.latency
        if self._base_step is None:
            self._base_step = target - 1
        for track in ended:
            self._hand_over(track, max(track.step, target))
        nothing = self.kind.empty()
        while self._base_step < target:
            self._base_step += 1
            views = [self._own.pop(self._base_step, nothing)]
            if self._base_step == target:
                views += list(shared_views)
            self._base = self._advance(self._base, views, self._ended.pop(self._base_step, []))
        current = self._base
        for later in range(target + 1, step + 1):
            current = self._advance(current, [self._own.get(later, nothing)],
                                    self._ended.get(later, []))
        if any(now is not before for now, before in zip(current, self._paths, strict=True)):
            self.path = self._union(current)
        self._paths = current
        eps = self.model.jitter
        return self._union([g.shown(path, own_view, eps)
                            for g, path in zip(self._groups, current, strict=True)])

    def _union(self, regions: Sequence[Region]) -> Region:
        """The union of one region per group (the groups lie apart)."""
        return regions[0] if len(regions) == 1 else self.kind.union_apart(regions)

    def _hand_over(self, track: EndedTrack, step: int) -> None:
        """Add ``track``'s path set, moved to ``step`` (>= its own), to that step's path region
        (module docstring)."""
        if self._base_step is not None and step <= self._base_step:
            raise ValueError(f"a track ended at step {track.step} handed over at step {step}, "
                             f"which the unobserved area has passed ({self._base_step})")
        path = self.kind.convex_outer(self.model.path_set(track.estimate).vertices())
        moved = path.dilate(self.model.reach_m(step - track.step))
        self._ended.setdefault(step, []).append(moved)

    def _advance(self, paths: tuple[Region, ...], views: Sequence[Region],
                 ended: Sequence[Region] = ()) -> tuple[Region, ...]:
        """One step of every group's path region (:meth:`_advance_group`)."""
        seen = [v for v in views if not v.is_empty]
        return tuple(self._advance_group(k, group, path, group.near(seen), group.near(ended))
                     for k, (group, path) in enumerate(zip(self._groups, paths, strict=True)))

    def _advance_group(self, k: int, group: _Group, path: Region, seen: Sequence[Region],
                       ended: Sequence[Region]) -> Region:
        """One step of group ``k``'s path region: move, add the path sets handed over at this
        step, then keep what is near unseen walkable ground; a group at rest stays as it is
        (class docstring)."""
        at_rest = not seen and not ended and len(self._groups) > 1
        if at_rest and path is self._whole[k]:
            return path
        if at_rest and (known := group.rest.get(path)) is not None:
            return known
        unseen = group.walkable.difference(self.kind.union_all(seen)) if seen \
            else group.walkable
        moved = self._moved(k, group, path)
        if ended:
            moved = self.kind.union_all([moved, *ended])
        after = group.clip(moved.intersection(unseen.dilate(self.model.jitter))).coarsen(
            COARSEN_M)
        return group.rest.put(path, after) if at_rest else after

    def _moved(self, k: int, group: _Group, path: Region) -> Region:
        """The path region one step later before any view: moved by the model's one-step reach,
        plus the inflow.

        The base's is kept: with a latency, one step carries the base forward with the bus's
        newest view and the next advances the base itself, from the same region.
        """
        kept = self._base_moved.get(k)
        if kept is not None and kept[0] is path:
            return kept[1]
        moved = path.dilate(self.model.reach_m())
        if group.inflow is not None:  # O's rim moved one step: paths entering B from outside
            moved = moved.union(group.inflow)
        if path is self._base[k]:
            self._base_moved[k] = (path, moved)
        return moved


GROUP_GAP_M = 50.0
"""Pieces of the tracked window farther apart than this are tracked as separate groups of the
unobserved area (:class:`UnobservedArea`): far beyond a step's reach plus twice the jitter, so
no path region crosses from one to another in a step but through the inflow."""


class _Rest:
    """A group's latest steps at rest (no view near it, no hand-over): each path region and
    the next one. Such a step depends on the path region alone, so the same region in gives
    the same one out, looked up, not computed. GEOS's overlays settle into a cycle of two
    representations of one set: a step that gives a region represented as one that went in
    before returns that earlier region, which closes the cycle, and from then on every step
    at rest is looked up."""

    def __init__(self) -> None:
        self._steps: list[tuple[Region, Region]] = []  # (path region, its next), oldest first

    def get(self, path: Region) -> Region | None:
        """The next path region after ``path`` at rest (None: not known)."""
        return next((after for before, after in self._steps if before is path), None)

    def put(self, path: Region, after: Region) -> Region:
        """Keep the step at rest ``path`` -> ``after``; return ``after``, or the earlier
        region represented exactly as it is."""
        after = next((before for before, _ in self._steps if after.same(before)), after)
        self._steps = [*self._steps[1 - REST_KEPT:], (path, after)]
        return after


REST_KEPT = 4  # the steps at rest a group keeps to find its cycle (GEOS's is of two)


@dataclass(eq=False)
class _Group:
    """One group of the tracked window's pieces (:class:`UnobservedArea`): the walkable
    ground whose views matter there, its part of B (None: no window), the inflow into it, how
    far beyond its part's bounds a view or a hand-over may change something there (the reach
    of a dilation by the jitter; None: one group, which every one may), its steps at rest
    (``rest``), and the areas shown for its latest path regions without the bus's view
    (``resting``)."""

    walkable: Region
    tracked: Region | None
    inflow: Region | None
    reach: float | None = None
    rest: _Rest = field(default_factory=_Rest)
    resting: list[tuple[Region, Region]] = field(default_factory=list)

    def clip(self, region: Region) -> Region:
        """``region`` ∩ its part of B."""
        return region if self.tracked is None else region.intersection(self.tracked)

    def near(self, regions: Sequence[Region]) -> list[Region]:
        """The ``regions`` within :attr:`reach` of its part's bounds (all with one group)."""
        if self.reach is None or self.tracked is None:
            return list(regions)
        return [r for r in regions if not apart(self.tracked, r, self.reach)]

    def shown(self, path: Region, own_view: Region, eps: float) -> Region:
        """Where an undetected pedestrian of this group may be: ``path`` grown by the jitter,
        on walkable ground, less what the bus sees now (``own_view``, when it comes near)."""
        if self.reach is not None and not self.near([own_view]):
            shown = next((area for before, area in self.resting if before is path), None)
            if shown is None:
                shown = path.dilate(eps).intersection(self.walkable)
                self.resting = [*self.resting[-1:], (path, shown)]
            return shown
        return path.dilate(eps).intersection(self.walkable).difference(own_view)


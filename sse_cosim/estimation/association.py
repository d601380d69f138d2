"""Association of anonymous detections with tracks, at a node and across nodes.

A real perception stack reports *anonymous* detections: the strips of one sensor about one
target (paper eq. strip), with no identity. This module starts, keeps, corrects, merges and
ends tracks from them so that every pedestrian a node has detected stays inside one of its
track sets (the first fusion level, :func:`associate`), and decides which tracks of several
nodes hold the same pedestrians and may be intersected (the second level,
:func:`associate_nodes`, Proposition 2 only where that is certain).

Assumptions (all sets are about the path point s of :mod:`sse_cosim.estimation.motion`):

- A1 bounded noise: each detection's strips, widened by the jitter (``path_strips``), hold
  its pedestrian's path point (eq. senmodel, |v_i| <= r_i).
- A2 completeness: a pedestrian whose simulated position lies in a sensor's visible region
  *is* detected by that sensor, with exactly one detection of its own (no merged targets);
  every detection comes from a pedestrian (no clutter). Outside the region it may or may not
  be detected.
- A3 speed bound: the prediction F Z (+) Q holds the next state (eq. sysmodel).
- A4 persistence: a pedestrian in the scene stays in it (hidden or not) while it is tracked;
  a pedestrian may appear at any time and anywhere. (A person the simulation removes takes
  A4 with it: its track ends once wholly visible, but until then rule R2 may trust it.)
- A5 ground (only if a walkable ground is given): pedestrians stay on it.

Rules of one step at one node (each proof in a line or two; "X" is a track's prediction):

- R1 candidates: detection d joins track T when its strips meet X (an exact test, with a
  tolerance that errs towards "meets"). Every pedestrian in X that sensor S detects has its
  detection among S's candidates of X (it lies in both).
- R2 certain match: if T is *occupied* (it surely holds a pedestrian), X lies wholly in S's
  visible region, and exactly one detection d of S meets X, then every pedestrian in X is
  d's pedestrian (A2: each is detected, by R1 among the candidates, each has its own), and
  there is one (occupied, A4): d's pedestrian is in X, so X ∩ d holds it. T *claims* d.
- R3 possibilities: per sensor S that sees part of X, every pedestrian in X is either
  hidden from S (in X minus S's visible region shrunk by the jitter) or in X ∩ d for one of
  its candidates d (R1). The corrected set is that one possibility, or the enclosure of the
  union of them all (a hull: 2-D the exact convex hull enclosed along the sets' directions,
  else the interval hull). Sensors are taken in turn (those with a single possibility
  together, one Proposition 1 step); each proof holds for every pedestrian in the
  prediction, so the order is free. A sensor whose shrunk region misses X cuts nothing (all
  of X may be hidden from it), but X still joins its candidates: a pedestrian of X it
  detects, within the jitter of its region's edge, is in X, and the invariant below needs
  X to say so.
- R4 claimed detections: a track that claims nothing leaves out the possibility X ∩ d of a
  d claimed by another track: a pedestrian of X whose detection is d is d's pedestrian,
  which the claimer keeps (claimers never leave anything out: two tracks that claim each
  other's detections would otherwise both drop it). It is then no longer known to be
  occupied.
- R5 new tracks: a detection that no track claims and whose set does not lie inside a
  prediction starts an occupied track (its pedestrian may be new and then in no other set);
  it is corrected with the other sensors by R1-R3, and the detections it claims (R2) start
  nothing. A detection inside a prediction X needs no track: its pedestrian is in X, kept by
  R3.
- R6 end: a track with no possibility left (wholly visible, no candidate) holds no
  pedestrian; so does one whose position set misses the walkable ground (A5).
- R7 merge: two tracks whose hull is at most :data:`MERGE_GROWTH` larger than the smaller
  of them become that hull (it covers both; occupied if either was); two that no detection
  touched this step, when it is at most that much larger than both areas together.
- R8 one track per detection: a track that claims nothing (R2) and that a sensor S sees in
  part with one candidate d left keeps R3's two possibilities apart instead of their hull:
  X ∩ d and X hidden from S (every pedestrian of X is in one of them). All the X ∩ d of one
  d, and d's new track (R5), become one track, their hull (it lies in d's set), with the
  lowest id: the pedestrian at a view's or an occluder's edge keeps its track, where R5
  started a new one every step. It is occupied if the new track is in it or d lies inside
  one of the predictions X whose correction left no detection out (R4): then d's pedestrian
  is in X and kept by every other sensor's cut, so it is in that piece. (A piece of an X that
  left out a claimed detection may have lost d's pedestrian to the claimer.) Each hidden
  possibility is a track not known to be occupied, joined to one beside it (R7's sum test).
  And d needs no new track if that track would claim (R2) a detection d' an existing track
  T claims: d's pedestrian is then d''s (A2, as in R2), which is in T's set.

Every rule keeps each pedestrian of a prediction in some new set, and each detected one is
in a prediction or in a new track: by induction every pedestrian ever detected stays inside
a track set (``tests/estimation/test_association.py`` checks it on random crossings), until
the node ends a track that joined no detection and hands its pedestrians over to the
unobserved areas (:class:`~sse_cosim.estimation.observer.AnonymousNodeObserver`,
:mod:`~sse_cosim.estimation.occupancy`); the rules below need only the tracks that are left.
Moreover a pedestrian detected now (by d) is in a track that joined a detection now (its
``joined`` is not empty): in a prediction X, d is X's candidate (R1) and joins the corrected
set, the piece X ∩ d of R8, or, if left out (R4), the claimer's set, which joined it (R2);
in none, it is in d's new track or the claimer's (R5, R8); merges and pools keep what their
parts joined (R7, R8). So every pedestrian in view of a node's sensors is in one of its
tracks that joined a detection, and a view is clear of a set that none of those meets
(:mod:`~sse_cosim.estimation.anonymous_fusion`), whatever the tracks that joined nothing.

Across nodes (:func:`associate_nodes`): track A of node a and track B of node b hold exactly
the same pedestrians when A lies wholly in b's visible region (so each of A's pedestrians is
detected by b and, by the invariant above, in a track of b that meets A) and B is the only
track of b that meets A, and the same with a and b swapped. Only then is A ∩ B (Prop. 2)
sound in place of both; tracks linked by such certain pairs form one group and are fused,
everything else is kept apart. All tracks are brought to the fusing step first; a region
seen earlier is trusted only for A grown by how far a pedestrian may have walked since.

Cost: bounding boxes prefilter every track-detection and track-track pair, and each region
test is one prepared predicate, so a step is about linear in the number of
(track, sensor that sees it) pairs; a hull is enclosed along the edges of its options only
(the enclosure's cost grows with the cube of its directions). The clipping, the enclosures
and the facet strips are the compiled kernels of :mod:`~sse_cosim.sets.enclosure_kernels`;
each detection's strips are scaled and mapped to the state once a step. ``make bench``
measures the cost against labelled detections (items 1 and 3b).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from sse_cosim.estimation.association_kernels import candidate_tests
from sse_cosim.estimation.motion import MotionModel
from sse_cosim.estimation.settings import EstimatorSettings, bounded
from sse_cosim.estimation.vote import interval_hull
from sse_cosim.regions import Region, RegionKind
from sse_cosim.sets import (
    Strips,
    Zonotope,
    intersect_strips,
    portable,
    zonotopes_disjoint,
)
from sse_cosim.sets.enclosure_kernels import (
    clip_to_strips,
    enclose_points,
    facet_strips,
    zonotope_vertices,
)
from sse_cosim.sets.kernels import contains_2d, full_rank_2d
from sse_cosim.sets.portable import matmul
from sse_cosim.sets.zonotope import FloatArray

MEET_TOL = 1e-6
"""m: strips widened by this before the candidate test (R1), so rounding errs to "meets"."""

VISIBLE_MARGIN = 1e-6
"""m: visible regions are shrunk by this (besides the jitter) before any test (R2, R3)."""

MERGE_GROWTH = 0.05
"""R7: two tracks merge when their hull's position area exceeds the smaller one's by at most
this fraction (near-duplicates: the same pedestrian started from two sensors)."""


@dataclass(frozen=True)
class AnonymousDetection:
    """One target measured by one sensor at one step: the sensor's name and its position
    strips (2 rows with independent normals, as measured: not yet widened by the jitter)."""

    sensor: str
    strips: Strips


@dataclass(frozen=True)
class LocalTrack:
    """A node-local track at ``step``: its state set, whether it surely holds a pedestrian
    (``occupied``, R2), and the indices of this step's detections it was corrected with."""

    track_id: int
    estimate: Zonotope
    step: int
    occupied: bool
    joined: tuple[int, ...] = ()


@dataclass(frozen=True)
class Association:
    """One step's result: the tracks (by increasing id) and the next free track id."""

    tracks: tuple[LocalTrack, ...]
    next_id: int


@dataclass(frozen=True)
class _Detections:
    """This step's detections: path strips (as measured, and about the state), their sets
    and position boxes (k, 2) lo / hi, and ``stacked``: the strips with unit normals and the
    sets' vertices in the arrays of :func:`candidate_tests`."""

    items: tuple[AnonymousDetection, ...]
    paths: tuple[Strips, ...]
    states: tuple[Strips, ...]
    parallelograms: tuple[Zonotope, ...]
    lo: FloatArray
    hi: FloatArray
    stacked: tuple[np.ndarray, ...]

    @classmethod
    def of(cls, items: Sequence[AnonymousDetection], model: MotionModel) -> _Detections:
        paths = tuple(model.path_strips(d.strips) for d in items)
        sets = tuple(_parallelogram(p) for p in paths)
        lo, hi = set_boxes(sets)
        return cls(tuple(items), paths, tuple(model.state_strips(p) for p in paths), sets,
                   lo, hi, _stacked([p.normalized() for p in paths], sets))

    def tests(self, path: Zonotope) -> tuple[np.ndarray, np.ndarray]:
        """R1 for the 2-D ``path`` set against every detection: (meets (k,), inside (k,)),
        :func:`candidate_tests` with :data:`MEET_TOL`."""
        normals, values, radii, rows, corners, corner_rows = self.stacked
        return candidate_tests(path.center, path.generators, normals, values, radii, rows,
                               corners, corner_rows, self.lo, self.hi, MEET_TOL)


def _stacked(units: Sequence[Strips], sets: Sequence[Zonotope]) -> tuple[np.ndarray, ...]:
    """Strips (unit normals) and sets' vertices stacked with the first row of each: normals
    (m, 2), values and radii (m,), rows (k + 1,), corners (v, 2), corner rows (k + 1,)."""
    corners = [z.vertices() for z in sets]
    return (np.vstack([u.normals for u in units] or [np.zeros((0, 2))]),
            np.concatenate([u.values for u in units] or [np.zeros(0)]),
            np.concatenate([u.radii for u in units] or [np.zeros(0)]),
            np.cumsum([0] + [len(u) for u in units]),
            np.vstack(corners or [np.zeros((0, 2))]),
            np.cumsum([0] + [len(c) for c in corners]))


@dataclass(frozen=True)
class _Scene:
    """What one step's rules need besides the tracks."""

    model: MotionModel
    settings: EstimatorSettings
    detections: _Detections
    eroded: Mapping[str, Region]  # sensor -> visible region shrunk by jitter + margin
    ground: Region | None
    kind: RegionKind

    def region(self, zonotope: Zonotope) -> Region:
        """A 2-D zonotope as a region."""
        return self.kind.convex_outer(zonotope.vertices())


def associate(
    model: MotionModel,
    settings: EstimatorSettings,
    tracks: Sequence[LocalTrack],
    detections: Sequence[AnonymousDetection],
    visible: Mapping[str, Region],
    step: int,
    next_id: int,
    kind: RegionKind,
    ground: Region | None = None,
) -> Association:
    """One step of a node's first fusion level from anonymous detections (rules R1-R7).

    ``tracks``: the node's tracks at earlier steps (each is predicted to ``step`` here);
    ``detections``: every detection of the node's sensors at ``step``, in a fixed order;
    ``visible``: sensor name -> its visible region at ``step`` (in the position plane, of
    ``kind``; a sensor missing here sees nothing); ``ground``: the walkable area, if
    known. New tracks take ids from ``next_id`` on. Cost: boxes prefilter every track-detection
    and track-region pair, so the exact tests run only on pairs that may meet.
    """
    found = _Detections.of(detections, model)
    shrink = model.jitter * np.sqrt(2.0) + VISIBLE_MARGIN  # box(jitter) lies in this disc
    eroded = {name: region.erode(shrink) for name, region in sorted(visible.items())}
    scene = _Scene(model, settings, found, eroded, ground, kind)
    predicted = [replace(t, estimate=model.predict(t.estimate, step - t.step), step=step)
                 for t in tracks]
    views = [_candidates(scene, t.estimate) for t in predicted]
    claims = {d for t, view in zip(predicted, views, strict=True) for d in _claimed(t, view)}
    kept: list[LocalTrack] = []
    pools: dict[int, list[tuple[LocalTrack, bool]]] = {}  # R8: d -> (visible piece, d inside)
    hidden: list[LocalTrack] = []
    for track, view in zip(predicted, views, strict=True):
        # R4: only a track that claims nothing leaves out what the others claim
        claimer = bool(_claimed(track, view))
        left_out = frozenset() if claimer else frozenset(claims)
        updated = _correct(scene, track, view, left_out, split=not claimer)
        if isinstance(updated, _Split):
            pools.setdefault(updated.detection, []).append(
                (updated.visible, updated.kept_all and updated.detection in view.inside))
            if updated.hidden is not None:
                hidden.append(updated.hidden)
        elif updated is not None:
            kept.append(updated)
    covered = claims | {d for view in views for d in view.inside}
    for d in range(len(detections)):
        members = [piece for piece, _ in pools.get(d, [])]
        occupied = any(inside for _, inside in pools.get(d, []))
        if d not in covered:
            track, claimed = _start(scene, d, step, next_id)
            covered |= claimed
            if not claimed & claims:  # R5 (else d's pedestrian is a claimer's, R8)
                if not members:
                    next_id += 1
                members.append(track)
                occupied = True
        if members:
            kept.append(_pool(scene, members, occupied))
    # R8: those whose id is free first, then the largest, so that a sliver joins the hidden
    # set beside it, which keeps its id; a piece that joins none is a track of its own
    free = {t.track_id for t in hidden} - {t.track_id for t in kept}
    for piece in sorted(hidden, key=lambda t: (t.track_id not in free,
                                                -model.position(t.estimate).volume(),
                                                t.track_id)):
        joined = _join_hidden(kept, piece, model, settings)
        if joined is not None:
            kept = joined
            continue
        if any(t.track_id == piece.track_id for t in kept):
            piece = replace(piece, track_id=next_id)
            next_id += 1
        kept.append(piece)
    return Association(tuple(sorted(_merge(kept, model, settings),
                                    key=lambda t: t.track_id)), next_id)


@dataclass(frozen=True)
class _Split:
    """R8: a track seen in part by one sensor with one candidate ``detection``, as its two
    possibilities: ``visible`` (the prediction cut with the detection, nothing known to be
    in it) and ``hidden`` (cut to where that sensor cannot see; None if it ended, R6);
    ``kept_all``: no candidate was left out (R4), so ``visible`` holds every pedestrian of the
    prediction whose detection is ``detection``."""

    visible: LocalTrack
    detection: int
    hidden: LocalTrack | None
    kept_all: bool


def _pool(scene: _Scene, members: Sequence[LocalTrack], occupied: bool) -> LocalTrack:
    """R8: one track holding every set of ``members`` (their hull; the lowest id), occupied
    as given."""
    first = min(members, key=lambda t: t.track_id)
    joined = tuple(sorted({d for t in members for d in t.joined}))
    if len(members) == 1:
        return replace(first, occupied=occupied, joined=joined)
    union = _hull([t.estimate for t in members], np.hstack([t.estimate.generators
                                                             for t in members]))
    settings = scene.settings
    return replace(first, estimate=settings.reduce(union),
                   occupied=occupied, joined=joined)


def _join_hidden(tracks: list[LocalTrack], piece: LocalTrack, model: MotionModel,
                 settings: EstimatorSettings) -> list[LocalTrack] | None:
    """R8: ``tracks`` with the hidden ``piece`` joined to the first track not known to be
    occupied whose hull with it is at most :data:`MERGE_GROWTH` larger than the two sets'
    areas together (the sliver a pedestrian at a shadow's edge leaves in the shadow, next to
    the set of the shadow); that track keeps its id. None if there is no such track."""
    box = model.position(piece.estimate).interval_hull()
    area = model.position(piece.estimate).volume()
    for i, track in enumerate(tracks):
        if track.occupied or not _boxes_meet(box, model.position(track.estimate)
                                             .interval_hull(), MEET_TOL):
            continue
        both = [track.estimate, piece.estimate]
        union = _hull(both, np.hstack([z.generators for z in both]))
        limit = (1.0 + MERGE_GROWTH) * (model.position(track.estimate).volume() + area)
        if model.position(union).volume() <= limit:
            merged = replace(track, estimate=settings.reduce(union),
                             joined=tuple(sorted({*track.joined, *piece.joined})))
            return [*tracks[:i], merged, *tracks[i + 1:]]
    return None


@dataclass(frozen=True)
class _View:
    """A track's prediction X against this step's detections and each sensor: candidates
    (detection indices meeting X, by sensor), detections whose set lies inside X (R5),
    sensors whose region holds X wholly, and sensors that see part of X."""

    candidates: Mapping[str, tuple[int, ...]]
    inside: tuple[int, ...]
    wholly: frozenset[str]
    partly: frozenset[str]


def _candidates(scene: _Scene, estimate: Zonotope, skip: str | None = None) -> _View:
    """R1 for one prediction ``estimate``: its candidates per sensor (sensor ``skip`` left out)
    and which sensors see it wholly or in part."""
    path = scene.model.path_set(estimate)
    found = scene.detections
    meets, within = found.tests(path)
    candidates: dict[str, list[int]] = {}
    inside = []
    for d in np.flatnonzero(meets):
        sensor = found.items[d].sensor
        if sensor != skip:
            candidates.setdefault(sensor, []).append(int(d))
            if within[d]:
                inside.append(int(d))
    polygon = scene.region(path)  # the regions are eroded by the jitter: s in them, p visible
    wholly: set[str] = set()
    partly: set[str] = set()
    for name, region in scene.eroded.items():
        if name == skip:
            continue
        if region.covers(polygon):
            wholly.add(name)
        elif region.intersects(polygon):
            partly.add(name)
    return _View({s: tuple(c) for s, c in candidates.items()}, tuple(inside),
                 frozenset(wholly), frozenset(partly))


def _claimed(track: LocalTrack, view: _View) -> list[int]:
    """R2: the detections an occupied track certainly holds: the only candidate of a sensor
    that sees the track wholly."""
    if not track.occupied:
        return []
    return [view.candidates[s][0] for s in sorted(view.wholly)
            if len(view.candidates.get(s, ())) == 1]


def _correct(scene: _Scene, track: LocalTrack, view: _View, left_out: frozenset[int],
             split: bool = False) -> LocalTrack | _Split | None:
    """R3, R4, R6 (and with ``split``, R8) for one predicted track: the corrected track, its
    two possibilities (R8), or None if it ended.

    Sensors with a single possibility (wholly visible, one candidate left) cut X together in
    one Proposition 1 step; the others then each replace X by the hull of their possibilities.
    Only sensors that see part of X cut it (one that sees none of it may miss them all);
    X joins the candidates of the others too (R3: their pedestrians in X stay in X).
    With ``split``, the last sensor that sees X in part and has one candidate left comes last
    and its two possibilities are kept apart (R8) instead of their hull.
    """
    states = scene.detections.states
    kept_all, certain, ambiguous = True, [], []
    for sensor in sorted(view.wholly | view.partly):
        candidates = view.candidates.get(sensor, ())
        used = [d for d in candidates if d not in left_out]
        kept_all = kept_all and len(used) == len(candidates)
        if sensor in view.partly or len(used) > 1:
            ambiguous.append((sensor, used))
        elif used:
            certain.append(used[0])
        else:
            return None  # R6: wholly visible, no pedestrian in it
    parted = [i for i, (sensor, used) in enumerate(ambiguous)
              if split and sensor in view.partly and len(used) == 1]
    last = ambiguous.pop(parted[-1]) if parted else None
    estimate = track.estimate
    if certain:
        estimate = _cut(scene, estimate, Strips.stack([states[d] for d in certain]))
    estimate = _ambiguous(scene, track, estimate, view, ambiguous)
    unseen = [d for sensor, candidates in view.candidates.items()
              if sensor not in view.wholly | view.partly
              for d in candidates if d not in left_out]
    joined = certain + [d for _, used in ambiguous for d in used] + unseen
    if last is None:
        return _finish(scene, track, estimate, track.occupied and kept_all, joined)
    sensor, (d,) = last
    visible = _finish(scene, track, _cut(scene, estimate, states[d]), False, [*joined, d])
    hidden = _finish(scene, track, _hidden(scene, estimate, track.estimate, sensor), False,
                     joined)
    if visible is None:  # off the ground: only the hidden possibility is left
        return hidden
    return _Split(visible, d, hidden, kept_all)


def _ambiguous(scene: _Scene, track: LocalTrack, estimate: Zonotope, view: _View,
               ambiguous: Sequence[tuple[str, Sequence[int]]]) -> Zonotope:
    """R3: ``estimate`` replaced, sensor by sensor, by the hull of that sensor's
    possibilities (``ambiguous``: sensor, candidates used)."""
    states = scene.detections.states
    for sensor, used in ambiguous:
        options = [_cut(scene, estimate, states[d]) for d in used]
        if sensor in view.partly:
            options.append(_hidden(scene, estimate, track.estimate, sensor))
        if len(options) == 1:
            estimate = options[0]
            continue
        edges = [matmul(scene.model.position_matrix, estimate.generators),
                 *(scene.detections.parallelograms[d].generators for d in used)]
        estimate = _hull(options, np.hstack(edges))  # along the edges of every option
    return estimate


def _finish(scene: _Scene, track: LocalTrack, estimate: Zonotope, occupied: bool,
            joined: Sequence[int]) -> LocalTrack | None:
    """The corrected track: None off the walkable ground (R6), else cut to the state bounds
    and reduced."""
    if scene.ground is not None and not scene.ground.intersects(
            scene.region(scene.model.position(estimate))):
        return None  # R6: off the walkable ground
    estimate = bounded(scene.model, scene.settings, estimate)  # the speed bound (A3), reduced
    return replace(track, estimate=estimate, occupied=occupied, joined=tuple(sorted(joined)))


def _start(scene: _Scene, d: int, step: int, track_id: int) -> tuple[LocalTrack, set[int]]:
    """R5: an occupied track from detection ``d``, corrected with the other sensors (R3,
    nothing left out), and the detections it claims (R2)."""
    sensor = scene.detections.items[d].sensor
    start = scene.model.initial_set(scene.detections.paths[d], scene.settings.gain_method)
    track = LocalTrack(track_id, start, step, True, (d,))
    view = _candidates(scene, start, skip=sensor)
    corrected = _correct(scene, track, view, frozenset())
    assert not isinstance(corrected, _Split)  # only with split
    if corrected is None:  # only if A1-A2 fail: keep the detection's own set
        return track, set()
    return replace(corrected, joined=tuple(sorted({d, *corrected.joined}))), \
        set(_claimed(track, view))


def _cut(scene: _Scene, estimate: Zonotope, strips: Strips) -> Zonotope:
    """X ∩ strips about the state (Proposition 1; path strips through
    ``model.state_strips``)."""
    return intersect_strips(estimate, strips, scene.settings.gain_method)


def _hidden(scene: _Scene, estimate: Zonotope, predicted: Zonotope, sensor: str) -> Zonotope:
    """The possibility "hidden from ``sensor``" (R3): ``estimate`` cut to an enclosure of the
    prediction's path set minus the sensor's eroded region (a pedestrian whose position
    p = s + e, |e| <= jitter, is outside the region has its s there)."""
    path = scene.model.path_set(predicted)
    corners = scene.region(path).difference(scene.eroded[sensor]).hull_points()
    enclosure = _enclose(corners, path.generators)
    if enclosure is None or not full_rank_2d(enclosure.generators):
        return estimate  # a segment or a point: no facet to cut with (nothing cut is sound)
    facets = Strips.unchecked(*facet_strips(enclosure.center, enclosure.generators))
    return _cut(scene, estimate, scene.model.state_strips(facets))


def _enclose(points: FloatArray, generators: FloatArray) -> Zonotope | None:
    """A 2-D zonotope holding conv(``points``) (k, 2), along the directions of
    ``generators`` (2, e) and the axes (compiled: :func:`enclose_points`); None if there are
    no points or no enclosure was accepted."""
    if len(points) == 0:
        return None
    found, center, enclosure = enclose_points(np.ascontiguousarray(points, dtype=np.float64),
                                              np.ascontiguousarray(generators))
    return Zonotope.unchecked(center, enclosure) if found else None


def _hull(sets: Sequence[Zonotope], generators: FloatArray) -> Zonotope:
    """A zonotope holding every set (R3, R7): 2-D the enclosure of the convex hull of their
    vertices along the directions of ``generators`` (2, e) and the axes (their edges, and
    few: the cost of the enclosure grows with their cube), else (or if that fails) the
    interval hull."""
    if sets[0].dim == 2:
        enclosure = _enclose(np.vstack([z.vertices() for z in sets]), generators)
        if enclosure is not None:
            return enclosure
    return interval_hull(sets)


def _merge(tracks: list[LocalTrack], model: MotionModel, settings: EstimatorSettings
           ) -> list[LocalTrack]:
    """R7: merge near-duplicates (the hull's position area within :data:`MERGE_GROWTH` of the
    smaller one's) until none is left, the first pair (by id) first; the merged track keeps
    the smaller id."""
    tracks = sorted(tracks, key=lambda t: t.track_id)
    rejected: set[tuple[Zonotope, Zonotope]] = set()  # pairs found apart: the same sets again
    while (found := _first_duplicate(tracks, model, rejected)) is not None:
        i, j, union = found
        first, second = tracks[i], tracks[j]
        tracks[i] = replace(first, estimate=settings.reduce(union),
                            occupied=first.occupied or second.occupied,
                            joined=tuple(sorted({*first.joined, *second.joined})))
        del tracks[j]
    return tracks


def _first_duplicate(tracks: Sequence[LocalTrack], model: MotionModel,
                     rejected: set[tuple[Zonotope, Zonotope]]) -> tuple[int, int, Zonotope] | None:
    """The first pair i < j (in that order) of near-duplicates (R7) and their hull, or None.
    The position boxes of every pair are compared at once; areas first, then hulls, but not
    for a pair of sets in ``rejected`` (the same objects: found apart before), to which the
    pairs found apart now are added."""
    positions = [model.position(t.estimate) for t in tracks]
    lo, hi = set_boxes(positions)
    meet = boxes_meet(lo, hi, lo, hi)
    areas = np.array([z.volume() for z in positions])
    touched = np.array([bool(t.joined) for t in tracks], dtype=bool)
    first, second = np.nonzero(np.triu(meet, k=1))  # row by row
    untouched = ~touched[first] & ~touched[second]
    smaller = np.minimum(areas[first], areas[second])
    larger = np.maximum(areas[first], areas[second])
    # _near_duplicate's first test for every pair at once: the larger within the limit
    possible = larger <= (1.0 + MERGE_GROWTH) * np.where(untouched, smaller + larger, smaller)
    for i, j, both in zip(first[possible], second[possible], untouched[possible], strict=True):
        pair = (tracks[i].estimate, tracks[j].estimate)
        if pair in rejected:
            continue
        union = _near_duplicate(*pair, model, bool(both), (float(areas[i]), float(areas[j])))
        if union is not None:
            return int(i), int(j), union
        rejected.add(pair)
    return None


def _near_duplicate(first: Zonotope, second: Zonotope, model: MotionModel,
                    untouched: bool, position_areas: tuple[float, float]) -> Zonotope | None:
    """Their hull when its position area is within :data:`MERGE_GROWTH` of the smaller one's,
    or, for two sets no detection touched this step (``untouched``, R8), of the sum of both
    areas (overlapping or side by side: the hull adds next to nothing to their union);
    ``position_areas``: the two position sets' areas."""
    areas = sorted(position_areas)
    limit = (1.0 + MERGE_GROWTH) * (areas[0] + areas[1] if untouched else areas[0])
    if areas[1] > limit:
        return None  # the hull is at least as large as the larger one
    union = _hull([first, second], np.hstack([first.generators, second.generators]))
    return union if model.position(union).volume() <= limit else None


def _boxes_meet(first: tuple[FloatArray, FloatArray], second: tuple[FloatArray, FloatArray],
                tol: float = 0.0) -> bool:
    """Whether two boxes (lo, hi) overlap, or come within ``tol``."""
    return bool((first[0] <= second[1] + tol).all() and (second[0] <= first[1] + tol).all())


def _parallelogram(path: Strips) -> Zonotope:
    """The set of a detection's two path strips: <H^-1 y, H^-1 diag(r)> (H (2, 2))."""
    inverse = portable.inverse_2x2(path.normals[:2])
    return Zonotope(matmul(inverse, path.values[:2]), inverse * path.radii[np.newaxis, :2])


def meets_reference(path_set: Zonotope, unit: Strips) -> bool:
    """Whether the 2-D set meets the strips ``unit`` (unit normals) widened by
    :data:`MEET_TOL` (exact clipping): the reference of
    :func:`~sse_cosim.estimation.association_kernels.candidate_tests`'s ``meets``."""
    clipped = clip_to_strips(zonotope_vertices(path_set.generators), unit.normals,
                             unit.values - matmul(unit.normals, path_set.center),
                             unit.radii + MEET_TOL)
    return len(clipped) > 0


def inside_reference(inner: Zonotope, path: Zonotope) -> bool:
    """Whether the 2-D set ``inner`` lies inside the 2-D set ``path`` (a strict test: every
    vertex at least :data:`MEET_TOL` inside): the reference of
    :func:`~sse_cosim.estimation.association_kernels.candidate_tests`'s ``inside``."""
    if not full_rank_2d(path.generators):
        return False
    return bool(np.all(contains_2d(path.center, path.generators, inner.vertices(), -MEET_TOL)))


@dataclass(frozen=True)
class NodeTracks:
    """One node's tracks at the fusing step, for :func:`associate_nodes`.

    ``tracks``: track id -> state set brought to the fusing step; ``visible``: the union of
    the node's sensors' visible regions at the step its tracks were corrected; ``reach``:
    how far (m) a pedestrian may have moved since then (0 for this step's tracks).
    """

    node: str
    tracks: Mapping[int, Zonotope]
    visible: Region
    reach: float = 0.0


@dataclass(frozen=True)
class FusedTrack:
    """A set for the pedestrians of its ``sources`` ((node, track id), in the order of the
    nodes given, then by id): their intersection (Prop. 2) when they certainly hold the same
    pedestrians, else the one source's set."""

    estimate: Zonotope
    sources: tuple[tuple[str, int], ...]


Fusion = Callable[[Sequence[Zonotope]], Zonotope]
"""Encloses the intersection of state sets of the same pedestrians (Proposition 2), e.g.
``lambda sets: bus_fusion.fuse_sets(sets, method, settings, model)``."""


def associate_nodes(nodes: Sequence[NodeTracks], model: MotionModel, fusion: Fusion,
                    kind: RegionKind) -> list[FusedTrack]:
    """The second fusion level over anonymous tracks: every track of every node lands in
    exactly one result; tracks linked by certain pairs (module docstring) are fused by
    ``fusion`` (called only on groups of two or more), the rest come back alone. Cost: one
    region test per (track, other node), exact overlap tests only for box-overlapping pairs.
    """
    keys = [(n.node, tid) for n in nodes for tid in sorted(n.tracks)]
    sets = {(n.node, tid): z for n in nodes for tid, z in n.tracks.items()}
    group = {key: key for key in keys}

    def root(key: tuple[str, int]) -> tuple[str, int]:
        while group[key] != key:
            key = group[key]
        return key

    sole = _sole_meetings(nodes, keys, [sets[key] for key in keys], model, kind)
    for (key, node), partner in sole.items():
        if partner is not None and sole[((node, partner), key[0])] == key[1]:
            group[root((node, partner))] = root(key)
    members: dict[tuple[str, int], list[tuple[str, int]]] = {}
    for key in keys:
        members.setdefault(root(key), []).append(key)
    return [FusedTrack(fusion([sets[k] for k in m]) if len(m) > 1 else sets[m[0]], tuple(m))
            for m in members.values()]


def _sole_meetings(nodes: Sequence[NodeTracks], keys: Sequence[tuple[str, int]],
                   estimates: Sequence[Zonotope], model: MotionModel, kind: RegionKind
                   ) -> dict[tuple[tuple[str, int], str], int | None]:
    """For every track (``keys``, ``estimates``) and every other node: the id of that node's
    only track meeting it when the track's position set, grown by the node's reach, lies
    wholly in the node's region; else None.

    That is tested as the position set inside the region eroded by as much (the Region
    contract: a set inside the erosion by d, grown by d, lies in the region), one erosion per
    node and step (the region keeps it). Boxes first, every track's against every other
    node's at once; a position set's polygon is made only for a region whose box holds it.
    """
    positions = [model.position(z) for z in estimates]
    paths = [model.path_set(z) for z in estimates]
    position_lo, position_hi = set_boxes(positions)
    path_lo, path_hi = set_boxes(paths)
    polygons: dict[int, Region] = {}
    sole: dict[tuple[tuple[str, int], str], int | None] = {}
    for other in nodes:
        rows = [i for i, key in enumerate(keys) if key[0] == other.node]  # its tracks
        ids = [keys[i][1] for i in rows]
        trusted = other.visible.erode(other.reach + VISIBLE_MARGIN)
        x0, y0, x1, y1 = trusted.bounds
        held = (position_lo[:, 0] >= x0) & (position_lo[:, 1] >= y0) \
            & (position_hi[:, 0] <= x1) & (position_hi[:, 1] <= y1) & (not trusted.is_empty)
        near = boxes_meet(path_lo, path_hi, path_lo[rows], path_hi[rows], MEET_TOL)
        for i, key in enumerate(keys):
            if key[0] == other.node:
                continue
            sole[(key, other.node)] = None
            if not held[i]:
                continue  # the set pokes out of the trusted region's box
            if i not in polygons:
                polygons[i] = kind.convex_outer(positions[i].vertices())
            if not trusted.covers(polygons[i]):
                continue
            meeting = [ids[k] for k in np.flatnonzero(near[i])
                       if not zonotopes_disjoint(paths[i], paths[rows[k]], MEET_TOL)]
            sole[(key, other.node)] = meeting[0] if len(meeting) == 1 else None
    return sole


def boxes_meet(first_lo: FloatArray, first_hi: FloatArray, second_lo: FloatArray,
               second_hi: FloatArray, tol: float = 0.0) -> np.ndarray:
    """Whether each box of the first (lo, hi (n, 2)) and each of the second (m, 2) overlap,
    or come within ``tol``: (n, m) bool (:func:`_boxes_meet` for every pair at once)."""
    return (second_lo[None, :, :] <= first_hi[:, None, :] + tol).all(axis=2) \
        & (first_lo[:, None, :] <= second_hi[None, :, :] + tol).all(axis=2)


def set_boxes(sets: Sequence[Zonotope]) -> tuple[FloatArray, FloatArray]:
    """The sets' boxes: lo, hi (k, 2)."""
    boxes = [z.interval_hull() for z in sets]
    return (np.array([b[0] for b in boxes]).reshape(-1, 2),
            np.array([b[1] for b in boxes]).reshape(-1, 2))

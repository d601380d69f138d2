"""One node's local observer: predict, correct with its own strips (Proposition 1), reduce.

Every node (bus, connected car, road-side unit) runs one. A track starts from the strips of
its first detection; when the node loses sight it keeps predicting, so the set grows by the
process noise each step and still contains the pedestrian. :class:`NodeObserver` associates
detections with tracks by the pedestrian's id (the simulation knows who is who; the paper has
one pedestrian); :class:`AnonymousNodeObserver` works from anonymous detections, as a real
perception stack reports them (:mod:`sse_cosim.estimation.association`), with node-local
track ids, and ends a track that has joined no detection for :data:`END_AFTER_STEPS` steps in
a row: its pedestrians, if any, go to the automated vehicles' unobserved areas
(:class:`~sse_cosim.estimation.occupancy.EndedTrack`), which the node's messages carry.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Generic, Protocol, TypeVar

import numpy as np

from sse_cosim.estimation import track_kernels
from sse_cosim.estimation.association import AnonymousDetection, Association, associate
from sse_cosim.estimation.correction import Suspicion, TrackCorrection, correct
from sse_cosim.estimation.motion import MotionModel
from sse_cosim.estimation.occupancy import EndedTrack
from sse_cosim.estimation.settings import EstimatorSettings, bounded
from sse_cosim.estimation.vote import CONSISTENCY_TOL
from sse_cosim.regions import Region, RegionKind
from sse_cosim.sets import Strips, Zonotope, intersect_strips, portable

END_AFTER_STEPS = 10
"""An anonymous track that joined no detection at this many steps in a row ends (its set
handed to the unobserved area). Any number is sound (:mod:`~sse_cosim.estimation.occupancy`):
it trades the track's memory of where its pedestrian cannot be against its growth."""

ENDED_KEPT_STEPS = 50
"""A node's messages list the tracks it ended in this many steps up to the message's own: a
receiver that missed fewer messages in a row learns every ending from the next one
(:class:`~sse_cosim.estimation.v2x.V2XLink`)."""


@dataclass(frozen=True)
class Track:
    """A node's state set for one pedestrian at ``step``; ``detected`` if a sensor saw it.

    ``flagged``: sensors whose strips were judged inconsistent and left out this step;
    ``conflict``: the estimate is a hull of hypotheses (an inconsistency the node cannot
    attribute, :mod:`sse_cosim.estimation.correction`).
    """

    person_id: str
    estimate: Zonotope
    step: int
    detected: bool
    flagged: frozenset[str] = frozenset()
    conflict: bool = False


class LocalTracks(dict[str, Track]):
    """One node's tracks at a step (track key -> track) and the tracks it ended lately:
    ``ended`` holds every track it ended at a step >= ``ended_since`` (labelled tracks never
    end: none since step 0)."""

    def __init__(self, tracks: Mapping[str, Track], ended: tuple[EndedTrack, ...] = (),
                 ended_since: int = 0) -> None:
        super().__init__(tracks)
        self.ended = ended
        self.ended_since = ended_since

    def ended_at(self, step: int) -> tuple[EndedTrack, ...]:
        """The tracks the node ended at ``step``."""
        return tuple(t for t in self.ended if t.step == step)


class NodeObserver:
    """Local set-membership observer of one node (paper Fig. 3, first fusion level)."""

    def __init__(self, node: str, model: MotionModel, settings: EstimatorSettings) -> None:
        self.node = node
        self.model = model
        self.settings = settings
        self.tracks: dict[str, Track] = {}
        self._suspicion: dict[str, Suspicion] = {}  # person id -> sensors held out
        # person id -> step -> the path strips its correction used then, for the model's
        # velocity windows (kept as far back as the longest)
        self._used: dict[str, dict[int, Strips]] = {}

    def step(
        self, step: int, detections: Mapping[str, Sequence[Strips] | Mapping[str, Strips]]
    ) -> LocalTracks:
        """Advance every track to ``step`` and correct those detected now.

        ``detections`` maps a pedestrian id to the position strips of this node's sensors
        that see it at this step, by sensor name (or as a list). Strips inconsistent with the
        prediction and the other sensors are left out (:func:`correction.correct`). The
        plain updates go through one compiled call (:func:`_plain_tracks`), the rest one by
        one (:meth:`_track`).
        """
        order = list(self.tracks.keys() | detections.keys())
        by_sensor = {pid: _by_sensor(detections.get(pid, ())) for pid in order}
        updated = self._plain_tracks(step, by_sensor)
        for person_id in order:
            if person_id not in updated:
                updated[person_id] = self._track(step, person_id, by_sensor[person_id])
        self.tracks = {person_id: updated[person_id] for person_id in order}
        return LocalTracks(self.tracks)

    def _track(self, step: int, person_id: str, strips: Mapping[str, Strips]) -> Track:
        """One track's update by the per-track path (the reference of :meth:`_plain_tracks`)."""
        previous = self.tracks.get(person_id)
        predicted = None if previous is None else self.model.predict(
            previous.estimate, step - previous.step)
        update = correct(self.model, self.settings.gain_method, predicted, strips,
                         self._suspicion.get(person_id, Suspicion()))
        self._suspicion[person_id] = update.suspicion
        estimate = bounded(self.model, self.settings,
                           self._with_windows(step, person_id, update, strips))
        return Track(person_id, estimate, step, bool(strips), update.flagged, update.conflict)

    def _with_windows(self, step: int, person_id: str, update: TrackCorrection,
                      strips: Mapping[str, Strips]) -> Zonotope:
        """The corrected set cut by the path strips this track used ``model.velocity_windows``
        steps ago, moved to now (:meth:`MotionModel.velocity_strips`); this step's used ones
        are kept for later steps (none after a conflict: the node could not tell whom to
        trust)."""
        windows = self.model.velocity_windows
        if not windows:
            return update.estimate
        kept = self._used.setdefault(person_id, {})
        for old in [k for k in kept if k <= step - max(windows)]:
            del kept[old]
        past = [_narrowing(self.model.velocity_strips(kept[step - n], n), n, update.estimate,
                           self.model) for n in windows if step - n in kept]
        past = [strips for strips in past if strips is not None]
        used = [self.model.path_strips(s) for name, s in strips.items()
                if name not in update.flagged]
        if used and not update.conflict:
            kept[step] = Strips.stack(used)
        estimate = update.estimate
        for strips_then in past:  # each window kept only where it narrows the velocity
            cut = intersect_strips(estimate, strips_then, self.settings.gain_method)
            if _velocity_width(cut) < _velocity_width(estimate):
                estimate = cut
        return estimate

    def _plain_tracks(self, step: int, by_sensor: Mapping[str, Mapping[str, Strips]]
                      ) -> dict[str, Track]:
        """The tracks whose update is plain, in one compiled call
        (:func:`~sse_cosim.estimation.track_kernels.plain_updates`): an existing track that
        no sensor sees, or that one sensor sees (two strips) while none is held out; the
        same estimates as :meth:`_track`. Those the kernel does not settle are left out."""
        if not self._compiled_path:
            return {}
        plain = [pid for pid, strips in by_sensor.items()
                 if pid in self.tracks and (not strips or (
                     len(strips) == 1 and len(next(iter(strips.values()))) == 2
                     and _unsuspected(self._suspicion.get(pid))))]
        if not plain:
            return {}
        previous = [self.tracks[pid].estimate for pid in plain]
        widest = max(z.n_generators for z in previous)
        generators = np.zeros((len(plain), 2, widest))
        for t, z in enumerate(previous):
            generators[t, :, :z.n_generators] = z.generators
        normals, values, radii = np.zeros((len(plain), 2, 2)), np.zeros((len(plain), 2)), \
            np.ones((len(plain), 2))
        detected = np.zeros(len(plain), dtype=np.bool_)
        for t, pid in enumerate(plain):
            if by_sensor[pid]:
                strips = next(iter(by_sensor[pid].values()))
                normals[t], values[t], radii[t] = strips.normals, strips.values, strips.radii
                detected[t] = True
        settled, centers, reduced, counts = track_kernels.plain_updates(
            np.array([z.center for z in previous]), generators,
            np.array([z.n_generators for z in previous], dtype=np.int64),
            np.array([step - self.tracks[pid].step for pid in plain], dtype=np.int64),
            self.model.process_noise.generators, normals, values, radii, detected,
            self.model.jitter, track_kernels.GAIN_CODES[self.settings.gain_method],
            self.settings.max_generators, CONSISTENCY_TOL)
        tracks = {}
        for t, pid in enumerate(plain):
            if settled[t]:
                estimate = Zonotope.unchecked(centers[t].copy(), reduced[t, :, :counts[t]].copy())
                # unseen, a track keeps its sensors held out; seen, none was (nothing changes)
                latched = bool(self._suspicion.get(pid, Suspicion()).latched)
                tracks[pid] = Track(pid, estimate, step, bool(detected[t]), frozenset(), latched)
        return tracks

    @cached_property
    def _compiled_path(self) -> bool:
        """Whether :meth:`_plain_tracks` applies: a 2-D position model (transition I, no
        state bounds), a gain with a compiled 2-D correction and Girard's reduction."""
        return (self.model.dim == 2 and np.array_equal(self.model.transition, np.eye(2))
                and self.model.state_bounds is None
                and self.settings.gain_method in track_kernels.GAIN_CODES
                and self.settings.reduction_method == "girard")


def _narrowing(strips: Strips, steps_ago: int, estimate: Zonotope,
               model: MotionModel) -> Strips | None:
    """Those of a window's ``strips`` (normals (h, -N dt h), m x 4) that can narrow the velocity
    below the speed bound: with the position part of ``estimate`` each bounds h.v to
    [(lo - y - r) / (N dt), (hi - y + r) / (N dt)] ([lo, hi]: h.s over the set); one whose
    interval holds [-v_max ||h||, v_max ||h||] says nothing the speed bound does not, and is
    left out (leaving out a true constraint is always sound), saving its linear program.
    None if no strip is left."""
    h = strips.normals[:, :2]
    support = np.abs(portable.matmul(h, estimate.generators[:2])).sum(axis=1)
    middle = portable.matmul(h, estimate.center[:2]) - strips.values
    reach = model.step_length * steps_ago
    bound = model.max_speed * np.sqrt((h * h).sum(axis=1))
    useful = ((middle - support - strips.radii) / reach > -bound) \
        | ((middle + support + strips.radii) / reach < bound)
    return strips.select(useful) if useful.any() else None


def _velocity_width(estimate: Zonotope) -> float:
    """The widths of a (position, velocity) set's velocity interval hull, summed (m/s)."""
    return float(np.abs(estimate.generators[2:]).sum())


def _unsuspected(suspicion: Suspicion | None) -> bool:
    """No sensor of the track held out (latched or on probation)."""
    return suspicion is None or not (suspicion.latched or suspicion.probation.remaining)


@dataclass(frozen=True)
class NodeScan:
    """What a node's sensors report at one step without ids: every detection (in a fixed
    order) and each sensor's visible region (sensor name -> region; a pedestrian
    inside it is detected by that sensor; a sensor left out sees nothing)."""

    detections: tuple[AnonymousDetection, ...] = ()
    visible: Mapping[str, Region] = field(default_factory=dict)


class AnonymousNodeObserver:
    """A node's observer from anonymous detections (paper Fig. 3, first fusion level).

    Tracks are started, corrected, merged and ended by
    :func:`~sse_cosim.estimation.association.associate`; every pedestrian the node has
    detected stays inside one of their sets, or in the set of a track the node handed over.
    A track whose id joined no detection at :data:`END_AFTER_STEPS` steps in a row is handed
    over, and so is at once a track with a new id that joined none (R8's possibility that a
    pedestrian is hidden from a sensor, when it joins no track beside it): dropped, and kept for
    :data:`ENDED_KEPT_STEPS` steps in the output's ``ended`` (the node's messages carry it to
    the unobserved areas, :mod:`~sse_cosim.estimation.occupancy`). It joined nothing at the
    step it ends, so every pedestrian in the node's view is still in one of its tracks that
    joined a detection (what the second level and the clear regions rely on,
    :mod:`~sse_cosim.estimation.anonymous_fusion`). The output has :class:`Track`'s shape,
    keyed by ``"<node>:<track id>"``: the id is local to the node, so tracks of different
    nodes never share a key (fusing them by key would assume they hold the same pedestrian;
    use :func:`~sse_cosim.estimation.association.associate_nodes`). No sensor is flagged: the
    consistency vote needs to know which strips are about the same pedestrian.
    """

    def __init__(self, node: str, model: MotionModel, settings: EstimatorSettings,
                 kind: RegionKind, ground: Region | None = None) -> None:
        self.node = node
        self.model = model
        self.settings = settings
        self.kind = kind
        self.ground = ground
        self.association = Association((), 0)
        self._joined_at: dict[int, int] = {}  # track id -> the last step it joined a detection
        self._ended: tuple[EndedTrack, ...] = ()

    def step(self, step: int, scan: NodeScan) -> LocalTracks:
        """Tracks at ``step`` from the node's ``scan`` at ``step``, and those it ended lately."""
        association = associate(
            self.model, self.settings, self.association.tracks, scan.detections, scan.visible,
            step, self.association.next_id, self.kind, self.ground)
        joined_at = {t.track_id: step if t.joined
                     else self._joined_at.get(t.track_id, step - END_AFTER_STEPS)
                     for t in association.tracks}
        live = {t.track_id: step - joined_at[t.track_id] < END_AFTER_STEPS
                for t in association.tracks}
        kept = tuple(t for t in association.tracks if live[t.track_id])
        ended = [EndedTrack(step, t.estimate) for t in association.tracks if not live[t.track_id]]
        self.association = Association(kept, association.next_id)
        self._joined_at = {t.track_id: joined_at[t.track_id] for t in kept}
        since = step - ENDED_KEPT_STEPS + 1
        self._ended = (*(t for t in self._ended if t.step >= since), *ended)
        tracks = [Track(f"{self.node}:{t.track_id}", t.estimate, step, bool(t.joined))
                  for t in kept]
        return LocalTracks({track.person_id: track for track in tracks}, self._ended, since)


NodeInput = TypeVar("NodeInput", Mapping[str, Mapping[str, Strips]], NodeScan)
"""What one node's observer takes at a step: labelled detections (pedestrian id -> sensor
name -> strips, :class:`NodeObserver`) or a :class:`NodeScan` (:class:`AnonymousNodeObserver`)."""


class Observer(Protocol[NodeInput]):
    """One node's observer: its tracks at a step from that step's input."""

    def step(self, step: int, found: NodeInput, /) -> LocalTracks: ...


class LocalObservers(Generic[NodeInput]):
    """Every node's observer, stepped together: the first fusion level of the network.

    The scenario's nodes have one from the start (``make(node)``); a node that appears at run
    time (a vehicle carrying sensors by type) gets one the first step it is in the input, and
    keeps it (predicting, from ``idle``: nothing seen) after it left. Use :meth:`labelled` or
    :meth:`anonymous`.
    """

    def __init__(self, nodes: Iterable[str], make: Callable[[str], Observer[NodeInput]],
                 idle: NodeInput) -> None:
        self._make = make
        self._idle = idle
        self._observers = {node: make(node) for node in nodes}

    @classmethod
    def labelled(cls, nodes: Iterable[str], model: MotionModel, settings: EstimatorSettings
                 ) -> LocalObservers[Mapping[str, Mapping[str, Strips]]]:
        """Observers that associate detections by the pedestrian's id."""
        return LocalObservers(nodes, lambda node: NodeObserver(node, model, settings), {})

    @classmethod
    def anonymous(cls, nodes: Iterable[str], model: MotionModel, settings: EstimatorSettings,
                  kind: RegionKind) -> LocalObservers[NodeScan]:
        """Observers of anonymous detections (node-local track ids; regions of ``kind``)."""
        return LocalObservers(
            nodes, lambda node: AnonymousNodeObserver(node, model, settings, kind), NodeScan())

    def step(self, step: int, found: Mapping[str, NodeInput]) -> dict[str, LocalTracks]:
        """Node -> its tracks at ``step`` (track key -> track, and those it ended lately), from
        ``found``: node -> what that node's sensors report now (labelled: pedestrian id ->
        sensor name -> strips; anonymous: its :class:`NodeScan`)."""
        for node in found:
            if node not in self._observers:
                self._observers[node] = self._make(node)
        return {node: observer.step(step, found.get(node, self._idle))
                for node, observer in self._observers.items()}


def _by_sensor(strips: Sequence[Strips] | Mapping[str, Strips]) -> dict[str, Strips]:
    """Detections keyed by sensor name; a plain list is keyed by position."""
    if isinstance(strips, Mapping):
        return dict(strips)
    return {str(i): s for i, s in enumerate(strips)}

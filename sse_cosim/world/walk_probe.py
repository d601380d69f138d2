"""Lone walkers in a short SUMO session: where SUMO's pedestrian model really puts a walker.

``walk_alone(net_path, walkers, step_s, work_dir)`` runs the given walkers -- and nothing else --
on a network and returns each one's trace: its centre and its lane at every step it walked.
The session is a run's session (:mod:`sse_cosim.world.sumo_setup`: the same SUMO options, the
same step length, the same reading of a person's centre), and each walker has the vType a
scenario's pedestrian gets (:func:`sse_cosim.world.demand.pedestrian_vtype`), so a walker moves
in a probe exactly as a scenario's pedestrian on the same walk -- as long as nothing else is
near it (in a run, vehicles and other persons may hold it up).

Times are a run's snapshot times: the state after SUMO's step to ``t + step_s`` is time ``t``,
as SUMO's own outputs (FCD) and :class:`sse_cosim.world.sumo.SumoWorld` give it; a walker that
departs at ``depart_s`` is first seen at ``depart_s``.

libsumo holds one simulation per process: a probe refuses to start while one is open
(:class:`SimulationError`) and always closes its own, so a run or another probe can follow in
the same process. Its files (``walkers.rou.xml``, ``sumo.sumocfg``, ``sumo.log``) go into
``work_dir``, a folder the caller owns.

Speed ramp. Given an acceleration bound (``accel_mps2``: the estimator's motion model bounds
the acceleration), the walkers' speeds are ramped as in a run
(:class:`~sse_cosim.world.sumo_setup.SpeedRamp`), so that a walker walks as a scenario's
pedestrian of that run does; without one, SUMO walks them as it does.

:class:`ProbeTimer` times the scenario's pedestrians with it (a
:data:`~sse_cosim.world.demand.WalkTimer`): how long SUMO's walker takes from the start of its
walk to its first step on its crossing, which is how the world starts each walk in time.
"""

from __future__ import annotations

import gzip
import math
import re
import shutil
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

import numpy as np

from sse_cosim.errors import SimulationError
from sse_cosim.files import write_text_atomic
from sse_cosim.scenario.model import Pedestrian
from sse_cosim.world.demand import WalkToCrossing, pedestrian_vtype
from sse_cosim.world.sumo_setup import (
    LIBSUMO_ERRORS,
    LOG_FILE_NAME,
    SpeedRamp,
    libsumo,
    message,
    person_centre,
    write_config,
)

PROBE = "walk probe"  # what its errors name instead of a scenario
ROUTE_FILE_NAME = "walkers.rou.xml"
# walkers draw no random numbers (no dawdling, no speed deviation): any seed gives the same run
PROBE_SEED = 1
DEFAULT_RADIUS_M = float(Pedestrian.model_fields["radius_m"].default)
_VARS = (libsumo.VAR_POSITION, libsumo.VAR_ANGLE, libsumo.VAR_LANE_ID, libsumo.VAR_SPEED)
_EPS = 1e-9
SLOT_SLACK_S = 3.0  # a lone walker's slot outlasts 1.5 times its walk at its speed by this (s)
_DURATION = re.compile(r'duration="([0-9.]+)"')


@dataclass(frozen=True)
class Walker:
    """One walker: the walk as in ``<walk edges="...">`` (sidewalks, walking areas,
    crossings), from ``depart_pos_m`` on ``edges[0]`` to ``arrival_pos_m`` on ``edges[-1]`` at
    ``speed_mps``, departing at ``depart_s``; ``radius_m`` is its body (a scenario
    pedestrian's by default)."""

    id: str
    edges: tuple[str, ...]
    depart_pos_m: float
    arrival_pos_m: float
    speed_mps: float
    depart_s: float = 0.0
    radius_m: float = DEFAULT_RADIUS_M


@dataclass(frozen=True)
class WalkTrace:
    """A walker's trace: ``times_s`` (k,) every step it was on the network, walking; ``xy``
    (k, 2) its centre then (network coordinates, as a run's snapshot reads it); ``lanes`` (k,)
    the SUMO lane it was on."""

    times_s: np.ndarray
    xy: np.ndarray
    lanes: tuple[str, ...]

    def first_time_on(self, edge_ids: frozenset[str] | set[str]) -> float | None:
        """The first time (s) it was on a lane of one of ``edge_ids``; None if never."""
        for t, lane in zip(self.times_s, self.lanes, strict=True):
            if lane.rpartition("_")[0] in edge_ids:
                return float(t)
        return None


def walk_alone(net_path: Path, walkers: Sequence[Walker], step_s: float, work_dir: Path,
               until_s: float | None = None, accel_mps2: float | None = None,
               lights: bool = True) -> dict[str, WalkTrace]:
    """Run the walkers (and nothing else) on the network; every walker's trace by id.

    SUMO steps until every walker has arrived, or until the state at time ``until_s`` if
    given; ``accel_mps2``: the speed ramp's acceleration (module docstring), None for none;
    ``lights``: the traffic lights run their programs (else every link shows green all
    session long, and no walker waits at one).
    Raises :class:`SimulationError` (one line) when a SUMO simulation is already open in
    this process, when SUMO cannot route a walker (naming it, see ``work_dir/sumo.log``), and
    when a walker is not on the network at its departure.
    """
    ids = [w.id for w in walkers]
    if len(set(ids)) != len(ids):
        raise ValueError(f"walker ids must be unique: {sorted(ids)}")
    if libsumo.isLoaded():
        raise SimulationError(PROBE, "another SUMO simulation is already open in this process; "
                              "libsumo runs one at a time -- close it first")
    if not walkers:
        return {}
    work_dir.mkdir(parents=True, exist_ok=True)
    routes = write_text_atomic(work_dir / ROUTE_FILE_NAME, _route_text(walkers))
    config = write_config(work_dir, net_path, [routes], step_s, PROBE_SEED,
                          f"SUMO configuration of {len(walkers)} lone walkers, written by "
                          "sse_cosim.world.walk_probe")
    try:
        libsumo.start(["sumo", "-c", str(config)])
    except LIBSUMO_ERRORS as exc:
        _close()
        raise SimulationError(PROBE, f"SUMO did not start{_named(exc, walkers)}: {message(exc)} "
                              f"(see {work_dir / LOG_FILE_NAME})") from exc
    try:
        _check_positions(walkers)
        if not lights:  # every link green until the session ends
            for light in libsumo.trafficlight.getIDList():
                links = len(libsumo.trafficlight.getRedYellowGreenState(light))
                libsumo.trafficlight.setRedYellowGreenState(light, "G" * links)
        ramp = None if accel_mps2 is None else SpeedRamp(accel_mps2, step_s)
        return _walk(walkers, step_s, until_s, ramp)
    except LIBSUMO_ERRORS as exc:
        raise SimulationError(PROBE, f"SUMO failed{_named(exc, walkers)}: {message(exc)} "
                              f"(see {work_dir / LOG_FILE_NAME})") from exc
    finally:
        _close()


class ProbeTimer:
    """Times pedestrians' walks on the network at ``net_path`` with lone SUMO walkers (a
    :data:`~sse_cosim.world.demand.WalkTimer`).

    One session walks every pedestrian's walk, one after the other in slots of
    :func:`slot_s` (so each walks alone; a walker still on the network when the next departs
    is an error), each with the pedestrian's speed and size, and with the run's speed ramp
    if ``accel_mps2`` is given (the motion model's acceleration bound: module docstring).
    A walk's time is the first step its walker is on the crossing's lane less its departure:
    a whole number of steps. The traffic lights are off: a walk's time is its walking, and
    the planner fits it to the lights' programs (:mod:`sse_cosim.world.demand`). The
    session's files go into ``work_dir`` (kept), or a temporary folder (removed) if None.

    A timer keeps the times of every set of walks it has timed: lone walkers draw no random
    numbers, so the same walks in the same order at the same step length walk the same in
    every session. A planner that asks again (the safety campaign's combinations differ in
    step-out times, noise and seeds far more often than in walks) pays for one session.
    """

    def __init__(self, net_path: Path, work_dir: Path | None = None,
                 accel_mps2: float | None = None) -> None:
        self.net_path = Path(net_path)
        self.work_dir = work_dir
        self.accel_mps2 = accel_mps2
        self._timed: dict[tuple[tuple[tuple[str, WalkToCrossing], ...], float],
                          dict[str, float]] = {}

    def __call__(self, walks: Mapping[str, WalkToCrossing], step_s: float) -> dict[str, float]:
        key = (tuple(walks.items()), step_s)
        if key not in self._timed:
            self._timed[key] = self._time(walks, step_s)
        return dict(self._timed[key])

    def _time(self, walks: Mapping[str, WalkToCrossing], step_s: float) -> dict[str, float]:
        """Every walk's time from one SUMO session (class docstring)."""
        walkers: list[Walker] = []
        depart = 0.0
        for pid, walk in walks.items():
            walkers.append(Walker(pid, walk.path, walk.start_pos_m, walk.end_pos_m,
                                  walk.speed_mps, depart, walk.radius_m))
            depart = round(depart + slot_s(walk.length_m / walk.speed_mps, step_s), 6)
        if self.work_dir is not None:
            traces = walk_alone(self.net_path, walkers, step_s, self.work_dir,
                                accel_mps2=self.accel_mps2, lights=False)
        else:
            traces = walk_alone_kept_on_error(self.net_path, walkers, step_s,
                                              "sse-cosim-walk-probe-",
                                              accel_mps2=self.accel_mps2, lights=False)
        times: dict[str, float] = {}
        for walker, following in zip(walkers, [*walkers[1:], None], strict=True):
            trace = traces[walker.id]
            crossing = walks[walker.id].crossing
            if following is not None and trace.times_s[-1] >= following.depart_s - _EPS:
                raise SimulationError(PROBE, f"the lone walker of pedestrian {walker.id!r} was "
                                      f"still walking at {following.depart_s:g} s, when the "
                                      f"next ({following.id!r}) departed: the timing would not "
                                      "be of a walker alone")
            on = trace.first_time_on({crossing})
            if on is None:
                raise SimulationError(PROBE, f"the lone walker of pedestrian {walker.id!r} never "
                                      f"stepped onto its crossing {crossing} (its lanes: "
                                      f"{', '.join(dict.fromkeys(trace.lanes))})")
            times[walker.id] = round(on - walker.depart_s, 6)
        return times


def slot_s(walk_s: float, step_s: float, cycle_s: float = 0.0) -> float:
    """How long (s, whole steps) a lone walker's slot lasts so that it has arrived before the
    next walker of its slot departs: 1.5 times its walk (``walk_s`` at its speed), a whole
    signal cycle ``cycle_s`` it may wait at a pedestrian light, and :data:`SLOT_SLACK_S`."""
    return math.ceil((1.5 * walk_s + cycle_s + SLOT_SLACK_S) / step_s - _EPS) * step_s


def longest_cycle_s(net_path: Path) -> float:
    """The longest signal cycle (s) of the network's traffic lights (0 without any): the sum
    of a ``<tlLogic>``'s phase durations, read from the file line by line."""
    longest = cycle = 0.0
    opener = gzip.open if net_path.name.endswith(".gz") else open
    with opener(net_path, "rt", encoding="utf-8") as stream:
        for line in stream:
            if "<tlLogic" in line:
                cycle = 0.0
            elif "<phase " in line:
                found = _DURATION.search(line)
                cycle += float(found.group(1)) if found else 0.0
                longest = max(longest, cycle)
    return longest


def walk_alone_kept_on_error(net_path: Path, walkers: Sequence[Walker], step_s: float,
                             prefix: str, **options: Any) -> dict[str, WalkTrace]:
    """:func:`walk_alone` in a new temporary folder (named ``prefix...``), removed once the
    walkers have walked; kept when SUMO fails, since the error names its log there."""
    folder = Path(tempfile.mkdtemp(prefix=prefix))
    traces = walk_alone(net_path, walkers, step_s, folder, **options)
    shutil.rmtree(folder, ignore_errors=True)
    return traces


def _walk(walkers: Sequence[Walker], step_s: float, until_s: float | None,
          ramp: SpeedRamp | None) -> dict[str, WalkTrace]:
    """Step the open session and collect the traces (see :func:`walk_alone`), ramping the
    walkers' speeds with ``ramp`` if given."""
    radius = {w.id: w.radius_m for w in walkers}
    walking = {w.id: w.speed_mps for w in walkers}
    present: dict[str, dict[int, Any]] = {}  # the walkers on the network after the step
    waiting = sorted(walkers, key=lambda w: w.depart_s)  # not yet seen on the network
    seen: set[str] = set()
    times: dict[str, list[float]] = {w.id: [] for w in walkers}
    xy: dict[str, list[tuple[float, float]]] = {w.id: [] for w in walkers}
    lanes: dict[str, list[str]] = {w.id: [] for w in walkers}
    sim = libsumo.simulation
    while sim.getMinExpectedNumber() > 0:
        if ramp is not None:
            ramp.apply({pid: (walking[pid], float(values[libsumo.VAR_SPEED]))
                        for pid, values in present.items()})
        libsumo.simulationStep()
        t = round(sim.getTime() - step_s, 6)
        for pid in sim.getDepartedPersonIDList():
            libsumo.person.subscribe(pid, _VARS)
            seen.add(pid)
        while waiting and waiting[0].depart_s <= t + _EPS:
            walker = waiting.pop(0)
            if walker.id not in seen:
                raise SimulationError(PROBE, f"walker {walker.id!r} is not on the network at "
                                      f"its departure ({walker.depart_s:g} s): SUMO did not "
                                      f"insert it at {walker.depart_pos_m:g} m on edge "
                                      f"{walker.edges[0]!r}")
        present = libsumo.person.getAllSubscriptionResults()
        for pid, values in present.items():
            lane = str(values[libsumo.VAR_LANE_ID])
            if not lane:
                continue  # not walking (SUMO has none of these in a probe: no stops)
            x, y = values[libsumo.VAR_POSITION]
            times[pid].append(t)
            xy[pid].append(person_centre(x, y, values[libsumo.VAR_ANGLE], 2.0 * radius[pid]))
            lanes[pid].append(lane)
        if until_s is not None and t >= until_s - _EPS:
            break
    return {pid: WalkTrace(np.asarray(times[pid], dtype=float),
                           np.asarray(xy[pid], dtype=float).reshape(-1, 2), tuple(lanes[pid]))
            for pid in times}


def _check_positions(walkers: Sequence[Walker]) -> None:
    """Each walker departs and arrives on its edges (SUMO would move a position beyond an edge's
    end to the end, with only a warning)."""
    for w in walkers:
        for edge, pos, what in ((w.edges[0], w.depart_pos_m, "depart_pos_m"),
                                (w.edges[-1], w.arrival_pos_m, "arrival_pos_m")):
            length = float(libsumo.lane.getLength(f"{edge}_0"))
            if not 0.0 <= pos <= length + _EPS:
                raise SimulationError(PROBE, f"walker {w.id!r}: {what} = {pos:g} m lies off "
                                      f"edge {edge!r} (0 to {length:g} m)")


def _route_text(walkers: Sequence[Walker]) -> str:
    """The route file: one vType per distinct (speed, radius), the walkers in departure
    order."""
    types: dict[tuple[float, float], str] = {}
    for w in walkers:
        types.setdefault((w.speed_mps, w.radius_m), f"walker{len(types)}")
    persons = [
        f'    <person id={quoteattr(w.id)} type="{types[(w.speed_mps, w.radius_m)]}" '
        f'depart="{w.depart_s:.10g}" departPos="{w.depart_pos_m:.10g}">\n'
        f'        <walk edges={quoteattr(" ".join(w.edges))} '
        f'arrivalPos="{w.arrival_pos_m:.10g}"/>\n'
        "    </person>"
        for w in sorted(walkers, key=lambda w: w.depart_s)]
    return "\n".join([
        '<?xml version="1.0" encoding="UTF-8"?>',
        "<!-- Lone walkers, generated by sse_cosim.world.walk_probe; do not edit. -->",
        "<routes>",
        *(pedestrian_vtype(tid, speed, r) for (speed, r), tid in types.items()),
        *persons,
        "</routes>",
        "",
    ])


def _named(exc: BaseException, walkers: Sequence[Walker]) -> str:
    """`` for walker 'x'`` when SUMO's message names walker ``x`` or an edge of its walk (the
    first such walker)."""
    quoted = re.findall(r"'([^']*)'", str(exc))
    for name in quoted:
        if any(w.id == name for w in walkers):
            return f" for walker {name!r}"
    for name in quoted:
        for w in walkers:
            if name in w.edges:
                return f" for walker {w.id!r} (its walk lists edge {name!r})"
    return ""


def _close() -> None:
    """Close the session; a failure to close leaves nothing to do."""
    try:
        libsumo.close()
    except LIBSUMO_ERRORS:
        return

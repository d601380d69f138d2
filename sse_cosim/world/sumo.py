"""The SUMO world: a scenario's run in SUMO. Only the world's SUMO modules (this one,
:mod:`sse_cosim.world.sumo_setup` and :mod:`sse_cosim.world.walk_probe`) import ``libsumo``.

``SumoWorld(scenario, run_dir, scenario_name)`` is a context manager. Entering it takes the
scenario's network (``network.net_file`` as it is, or built from ``network.sources_dir``:
:mod:`sse_cosim.world.network`), checks the scenario's actors and its route files
(``network.route_files``, :mod:`sse_cosim.world.route_files`) against it, writes the run's SUMO
files into ``run_dir`` (``scenario.rou.xml``, ``sumo.sumocfg`` -- ``sumo-gui -c
run_dir/sumo.sumocfg`` replays the run's scene -- and ``sumo.log`` with SUMO's warnings) and
starts SUMO in-process. Leaving it always closes SUMO, also when a step raised.

Route-file actors. SUMO loads the scenario's route files after its own route file: their
vehicles are in every snapshot (role ``other``, with their type id, which sensors carried by
type follow), their persons are in ``Snapshot.persons`` like the scenario's pedestrian.

Time. ``step()`` advances SUMO by one step and returns the :class:`Snapshot` of the new state.
Its ``time`` is the time SUMO's own outputs (FCD etc.) give that state: the first step returns
t=0 with the actors that depart at t=0 standing at their departure places, i.e. one step less
than ``libsumo.simulation.getTime()`` after the step.

Insertion. SUMO inserts a vehicle only where it has room and where the vehicle behind it can
still brake for it; otherwise it keeps the vehicle waiting and inserts it later, at the same
position (a car placed ahead of the fast bus on the bus's lane would then appear behind the
bus). So ``step()`` raises :class:`UserError` naming the vehicle's ``depart_pos_m``
(``automated.bus.depart_pos_m``, ``vehicles.car.depart_pos_m``) as soon as an automated or a
moving vehicle is not on the road at its departure: a scenario's actors start where and when it
says, or the run is refused.

Every pedestrian exists from t=0 and stands at its start until its walk starts (see
:mod:`sse_cosim.world.demand`); meanwhile the snapshot places it at its plan's standing point
on the sidewalk, where its walk then begins, not where SUMO draws a waiting person. Its walk is
timed before SUMO starts by a lone walker on the same walk
(:class:`sse_cosim.world.walk_probe.ProbeTimer`), so it steps onto its crossing at its
``steps_onto_crossing_s`` within one step; ``step()`` checks that it did and raises
:class:`SimulationError` (one line: the pedestrian, the planned and the actual time, the fix)
when SUMO held it up or let it on early -- never a silent mismatch.

Lane change mode. Every automated vehicle drives under lane change mode 512: SUMO changes
none of its lanes of its own accord (no overtaking, no keeping right), and keeps its safety
checks. Its lanes are its controller's plan (``RoadMap.route_plan``: on each edge the
rightmost lane that leads on; where the route cannot be driven lane to lane, a change on the
edge entered on a lane that does not lead on), and the world asks SUMO for each planned
change once the body is on its edge (``changeLane``).

Speed mode. Every automated vehicle drives under speed mode 31 (SUMO's default, set
explicitly): SUMO keeps the safe speed towards leaders, the vehicle's maximum acceleration and
deceleration, and the right of way at junctions -- so SUMO still yields to pedestrians on the
priority crossing -- while :meth:`SumoWorld.set_speed` sets the speed it follows
(``vehicle.setSpeed``, held until the next command) as closely as its acceleration and
deceleration allow. The actual speed is in the snapshot, the command in
``last_commanded_speed(vehicle_id)``. Before the first command it drives at its nominal speed
(its maximum speed).

Emergency brake. ``set_speed(vid, v, emergency=True)`` sets the vehicle's deceleration to its
emergency deceleration (``vehicle.setDecel``) before commanding ``v``; the next normal command
restores the comfortable deceleration. So an emergency brake uses the same
control path as any command (speed mode, right of way and safe speed stay on) and brakes at
exactly ``emergency_decel_mps2`` per second; ``slowDown`` would instead spread the change over
a chosen duration, which is not what a brake is.

Actuation delay. A vehicle with ``actuation_delay_s`` acts on each command (its emergency
brake included) that many whole steps after it was given; until its first command acts it
drives at its nominal speed. ``last_commanded_speed`` is the latest command, as given.

One simulation per process. libsumo runs SUMO inside this process and holds one simulation at
a time: a second ``SumoWorld`` entered while one is open raises :class:`SimulationError`. After
``close()`` a new simulation can be started in the same process (the tests do so), but sweeps
run each simulation in its own process so that they can run in parallel.

Bounded acceleration. When the estimator's motion model bounds the acceleration
(:func:`sse_cosim.estimation.motion.acceleration_bound`: the ``bounded-acceleration`` model),
SUMO's walkers, which start and stop within one step, are ramped: before every step each
person's speed is capped at min(its own walking speed, its speed now + a_max dt)
(:class:`~sse_cosim.world.sumo_setup.SpeedRamp`; a scenario pedestrian's own speed is its
``walking_speed_mps``, a route file's person's the one SUMO gives it at its departure). The
lone walkers that time the walks and measure the jitter walk the same ramp, and the motion
check is :mod:`sse_cosim.world.acceleration_assumption`'s: one path keeping the speed bound,
the acceleration bound and the jitter at once (it implies the speed check, which then does
not run). Its breaks are ``pedestrian_speed``'s, as the speed check's are.

Pauses. A scenario pedestrian with ``pause_for_s`` stops ``pause_after_s`` after it stepped
onto its crossing and walks on after ``pause_for_s`` (:mod:`sse_cosim.world.walker_pause`):
``person.setSpeed`` before each step, ramped as above under the bounded-acceleration model.

Turn-backs. A scenario pedestrian with ``turn_back_after_s`` still on its crossing that long
after stepping onto it turns back, waits at the near end and crosses after all
(:mod:`sse_cosim.world.walker_turn`): from then on the world holds it at speed 0 in SUMO and
places it on the crossing's lane before every step (``person.moveTo``, by its front, its
lateral position kept), reports the turned walk's speed and heading in its snapshots, and
removes it at the far end.

Walkable ground. The estimator assumes every pedestrian's centre lies on the road map's
walkable ground (:attr:`sse_cosim.world.roadmap.RoadMap.walkable`): sidewalks, walking areas and
crossings, and the patches where SUMO's lone walkers were measured to leave them
(:mod:`sse_cosim.world.walker_jitter`, measured before every run -- also in a study that sets
its own jitter and breaks ``pedestrian_speed``), the junctions' ground grown by
``estimator.junction_ground_margin_m``. The world fills the road map's patches before
anything reads the road map, and ``step()`` checks every pedestrian's
true centre against that ground.

Checked assumptions. After each step the world runs every check of
:mod:`sse_cosim.world.checks` on the snapshot (the motion model, the walkable ground, the
pedestrian lights): a break stops the run with :class:`~sse_cosim.errors.AssumptionBroken`
(exit status 5, one line), unless the study lists that assumption in ``breaks_assumptions``;
then it is counted (:attr:`SumoWorld.breaks`) and the run goes on.

Traffic lights. Each snapshot carries the scene's traffic lights (the road map's
:attr:`~sse_cosim.world.roadmap.RoadMap.lights`): program, phase, state and time in the phase.

Determinism. Every vehicle and person type has ``speedDev=0`` and ``sigma=0`` (the route
files' too, or they are refused), pedestrians do not dawdle (``pedestrian.striping.dawdling
0``) and SUMO's seed is the scenario's seed: one scenario gives one sequence of snapshots.
Nobody is teleported (``time-to-teleport -1``); collisions are reported (``collision.action
warn``, junctions included) and kept in ``collisions``.
"""

from __future__ import annotations

import contextlib
import logging
import math
from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from types import TracebackType
from typing import Any

import shapely

from sse_cosim.errors import SimulationError, UserError
from sse_cosim.estimation.motion import acceleration_bound
from sse_cosim.scenario.model import (
    CROSSING_TOLERANCE_S,
    AutomatedVehicle,
    Scenario,
    present,
)
from sse_cosim.world import checks, demand, walker_jitter
from sse_cosim.world.checks import CheckSetup, StepFacts
from sse_cosim.world.checks.motion import MotionCheck
from sse_cosim.world.demand import ActorPlan, PedestrianPlan
from sse_cosim.world.extent import (
    MAX_MEASURED_JITTER_M,
    JitterScope,
    SceneExtent,
    jitter_scope,
    scene_extent,
)
from sse_cosim.world.network import NetworkBuildError, scenario_net_path
from sse_cosim.world.roadmap import (
    LaneChange,
    RoadMap,
    load_scene_roadmap,
    require_pedestrian_ground,
)
from sse_cosim.world.route_files import RouteFiles, read_route_files
from sse_cosim.world.signals import SignalState
from sse_cosim.world.snapshot import Footprint, PersonState, Pose, Snapshot, VehicleState
from sse_cosim.world.sumo_setup import (
    CONFIG_FILE_NAME as CONFIG_FILE_NAME,  # re-exported: where a run's configuration is
)
from sse_cosim.world.sumo_setup import (
    LIBSUMO_ERRORS,
    LOG_FILE_NAME,
    SpeedRamp,
    heading,
    libsumo,
    message,
    person_centre,
    write_config,
)
from sse_cosim.world.walk_probe import PROBE, ProbeTimer
from sse_cosim.world.walker_pause import TIME_EPS_S, Pause
from sse_cosim.world.walker_turn import CrossingWalker, StraightLane, TurnBack

log = logging.getLogger(__name__)

AUTOMATED_SPEED_MODE = 31
AUTOMATED_LANE_CHANGE_MODE = 512  # no lane change of SUMO's own; safety checks kept
_VEHICLE_VARS = (libsumo.VAR_POSITION, libsumo.VAR_ANGLE, libsumo.VAR_SPEED)
_AUTOMATED_VARS = (*_VEHICLE_VARS, libsumo.VAR_DISTANCE, libsumo.VAR_LANE_ID,
                   libsumo.VAR_LANEPOSITION)
_PERSON_VARS = (libsumo.VAR_POSITION, libsumo.VAR_ANGLE, libsumo.VAR_SPEED, libsumo.VAR_ROAD_ID,
                libsumo.VAR_LANE_ID)

TURN_MARGIN_M = 0.05  # how far from its lane's ends a turned walker's centre and front stay

_open_world: SumoWorld | None = None


def sumo_version() -> str:
    """SUMO's version, e.g. ``1.28.0`` (of the libsumo in use)."""
    version = str(libsumo.__version__) if hasattr(libsumo, "__version__") else ""
    if version:
        return version
    return str(libsumo.getVersion()[1]).removeprefix("SUMO ").strip()


def measure_walkers(net_path: Path, roadmap: RoadMap, extent: SceneExtent | None,
                    speed_mps: float, step_s: float, radius_m: float,
                    accel_mps2: float | None = None,
                    scope: JitterScope | None = None) -> walker_jitter.NetworkJitter:
    """The jitter SUMO's lone walkers need on the walking areas of ``roadmap`` (of the network
    at ``net_path``) in ``extent`` (all for None) at the junctions of ``scope`` (all for None),
    and where they leave its plain ground (:mod:`sse_cosim.world.walker_jitter`, cached); with
    ``accel_mps2`` (a motion model that bounds the acceleration), walkers ramped within it and
    the jitter that model needs."""
    return walker_jitter.measure(
        net_path, roadmap.net, extent, roadmap.ground, speed_mps, step_s, radius_m,
        sumo_version(), accel_mps2, scope)


@dataclass
class _Automated:
    """What the world keeps of one automated vehicle: its latest command, the commands still
    on their way (``actuation_delay_steps`` of them: ``pending``) and the one it acts on
    (``acting``: speed, emergency), its deceleration now in SUMO, the distance it drove and
    whether it arrived."""

    config: AutomatedVehicle
    decel: float
    actuation_delay_steps: int = 0
    commanded: float | None = None
    pending: deque[tuple[float, bool]] = field(default_factory=deque)
    acting: tuple[float, bool] | None = None
    distance: float = 0.0
    arrived: bool = False
    changes: deque[LaneChange] = field(default_factory=deque)  # those still to make

    def command(self, speed: float, emergency: bool) -> None:
        """A new command: it is acted on once ``actuation_delay_steps`` later ones came."""
        self.commanded = speed
        self.pending.append((speed, emergency))
        if len(self.pending) > self.actuation_delay_steps:
            self.acting = self.pending.popleft()


@dataclass
class _Turned:
    """A turned-back pedestrian the world places (:mod:`sse_cosim.world.walker_turn`): its
    walk along the crossing's lane, the lane (SUMO's id and geometry), its lateral position
    on it (m, left of the lane's direction) and its heading (rad; kept while it stands)."""

    walker: CrossingWalker
    lane_id: str
    lane: StraightLane
    lateral: float
    heading: float


@dataclass(frozen=True)
class Collision:
    """A collision SUMO reported (it only warns; nobody is removed)."""

    time: float
    collider: str
    victim: str
    kind: str


class SumoWorld:
    """The scenario's scene in SUMO, stepped by the caller (see module docstring)."""

    def __init__(self, scenario: Scenario, run_dir: str | Path, scenario_name: str) -> None:
        self.scenario = scenario
        self.run_dir = Path(run_dir)
        self.scenario_name = scenario_name
        self._dt = scenario.simulation.step_length_s
        self._roadmap: RoadMap | None = None
        self._plan: ActorPlan | None = None
        self._net_path: Path | None = None
        self._route_files = RouteFiles((), frozenset())
        self._open = False
        self._entered = False
        self._time = -self._dt
        self._departed: set[str] = set()  # vehicles SUMO has inserted
        self._automated = {vid: _Automated(av, av.comfortable_decel_mps2,
                                           round(av.actuation_delay_s / self._dt))
                           for vid, av in present(scenario.automated).items()}
        self._kinds = {
            **dict.fromkeys(present(scenario.parked), "parked"),
            **dict.fromkeys(present(scenario.vehicles), "vehicle"),
            **dict.fromkeys(self._automated, "automated"),
        }
        self._teleports = 0
        self._collisions: list[Collision] = []
        self._statics: dict[str, tuple[float, float, str]] = {}
        self._person_length: dict[str, float] = {}
        self._motion_declared = MotionCheck.name in scenario.breaks_assumptions
        self._accel = acceleration_bound(scenario.estimator, self._dt)
        self._ramp = None if self._accel is None else SpeedRamp(self._accel, self._dt)
        self._walking_speeds: dict[str, float] = {}  # each person's own speed (ramped walkers)
        self._person_speeds: dict[str, float] = {}  # each person's speed at the latest snapshot
        self._ledger = checks.Ledger((), (), scenario_name)  # every check, once resolved
        self._person_lanes: dict[str, str] = {}  # each person's lane at the latest snapshot
        self._previous_lanes: dict[str, str] = {}
        self._stepped_on: dict[str, float] = {}  # pedestrian -> when it stepped onto its crossing
        self._pauses = {pid: pause for pid, ped in present(scenario.pedestrians).items()
                        if (pause := Pause.of(ped)) is not None}
        self._turns = {pid: turn for pid, ped in present(scenario.pedestrians).items()
                       if (turn := TurnBack.of(ped)) is not None}  # not yet turned
        self._turned: dict[str, _Turned] = {}  # placed by the world every step
        self._centres: dict[str, tuple[float, float]] = {}  # at the latest snapshot
        self._previous_centres: dict[str, tuple[float, float]] = {}
        self._lights: tuple[str, ...] = ()  # the scene's traffic lights (the road map's)

    # --- context manager ------------------------------------------------------------------

    def __enter__(self) -> SumoWorld:
        global _open_world
        if self._entered:
            raise RuntimeError("a SumoWorld runs once; create a new one for another run")
        if _open_world is not None or libsumo.isLoaded():
            raise SimulationError(self.scenario_name, "another SUMO simulation is already open in "
                                  "this process; libsumo runs one at a time -- close it first, "
                                  "or run each simulation in its own process")
        self._entered = True
        network = self.scenario.network
        try:
            self._net_path = scenario_net_path(network, self.scenario_name)
        except NetworkBuildError as exc:
            raise SimulationError(self.scenario_name, "the road network does not build: "
                                  f"{exc.one_line()}") from exc
        self._roadmap = load_scene_roadmap(self._net_path, self.scenario)
        if present(self.scenario.pedestrians):
            require_pedestrian_ground(
                self._roadmap, self.scenario_name,
                "network.net_file" if network.net_file else "network.sources_dir")
        self._route_files = read_route_files(network.route_files, self.scenario.actor_ids(),
                                             self.scenario_name)
        self._check_carrier_types()
        with self._walking_alone():
            self._plan = demand.plan_actors(self.scenario, self._net_path, self._roadmap,
                                            source=self.scenario_name,
                                            timer=ProbeTimer(self._net_path,
                                                             accel_mps2=self._accel))
            for state in self._automated.values():  # routes checked: plan their changes
                state.changes.extend(self._roadmap.route_changes(state.config.route_edges))
            measured = self._measure()
            self.scenario = self._with_jitter(measured)
        estimator = self.scenario.estimator
        self._roadmap = self._roadmap.with_ground_patches(
            measured.ground_patches, estimator.junction_ground_margin_m,
            estimator.position_jitter_m or 0.0)
        shapely.prepare(self._roadmap.walkable)
        self._lights = self._roadmap.lights
        self._ledger = checks.ledger(CheckSetup(self.scenario, self._roadmap, self._accel),
                                     self.scenario_name)
        config = self._write_files()
        try:
            libsumo.start(["sumo", "-c", str(config)])
        except LIBSUMO_ERRORS as exc:
            with contextlib.suppress(*LIBSUMO_ERRORS):
                libsumo.close()
            raise SimulationError(self.scenario_name, f"SUMO did not start: {message(exc)} "
                                  f"(see {self.run_dir / LOG_FILE_NAME})") from exc
        _open_world = self
        self._open = True
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()

    def close(self) -> None:
        """Close SUMO (idempotent)."""
        global _open_world
        if not self._open:
            return
        self._open = False
        _open_world = None
        try:
            libsumo.close()
        except LIBSUMO_ERRORS as exc:
            log.warning("%s: closing SUMO failed: %s", self.scenario_name, message(exc))

    # --- stepping -------------------------------------------------------------------------

    def step(self) -> Snapshot:
        """Advance SUMO by one step and return the new state.

        Raises :class:`UserError` when a vehicle is not on the road at its departure (SUMO
        found no room to insert it where the scenario places it), and
        :class:`AssumptionBroken` when the world breaks an assumption of the estimator or the
        controller (:mod:`sse_cosim.world.checks`) that the scenario does not list in
        ``breaks_assumptions``.
        """
        self._require_open()
        try:
            self._set_walking_speeds()
            self._place_turned_walkers()
            libsumo.simulationStep()
            snapshot = self._snapshot()
        except LIBSUMO_ERRORS as exc:
            raise SimulationError(self.scenario_name,
                                  f"SUMO step at t={self._time + self._dt:.2f} s failed: "
                                  f"{message(exc)}") from exc
        self._check_insertions()
        self._check_steps_onto_crossings(snapshot)
        self._ledger.step(snapshot, StepFacts(self._previous_lanes, self._person_lanes))
        return snapshot

    @property
    def breaks(self) -> dict[str, dict[str, Any]]:
        """The breaks of the assumptions the study lists in ``breaks_assumptions``, by their
        summary key (:attr:`~sse_cosim.world.checks.Ledger.summary`)."""
        return self._ledger.summary

    def _set_walking_speeds(self) -> None:
        """Each walker's speed for the next step: its own, or a pausing pedestrian's
        (:class:`~sse_cosim.world.walker_pause.Pause`), ramped within the acceleration bound
        where the motion model has one (then every walker's, every step)."""
        walking = {pid: speed for pid, speed in self._person_speeds.items()
                   if pid not in self._turned}  # (the world places a turned walker itself)
        wanted = {pid: self._pauses[pid].speed(self._since_on(pid))
                  for pid in self._pauses.keys() & walking.keys()}
        if self._ramp is not None:
            self._ramp.apply({pid: (wanted.get(pid, self._walking_speeds[pid]), speed)
                              for pid, speed in walking.items()})
            return
        for pid, speed in sorted(wanted.items()):
            libsumo.person.setSpeed(pid, speed)

    def _place_turned_walkers(self) -> None:
        """Turn back every pedestrian whose turn is due (one that has left its crossing does
        not turn; one not wholly on it yet turns a step later), and place every turned one for
        the next step, or remove it at the far end."""
        for pid in sorted(self._turns):
            if not self._turns[pid].due(self._since_on(pid)):
                continue
            if not self._on_crossing(pid):
                del self._turns[pid]  # it has crossed
                continue
            turned = self._turn(pid, self._turns[pid])
            if turned is not None:
                self._turned[pid] = turned
                del self._turns[pid]
                libsumo.person.setSpeed(pid, 0.0)
        for pid in sorted(self._turned):
            turned = self._turned[pid]
            at = turned.walker.step()
            if at is None:
                libsumo.person.remove(pid)
                del self._turned[pid]
                continue
            if turned.walker.velocity_mps != 0.0:
                turned.heading = turned.lane.heading + (
                    0.0 if turned.walker.velocity_mps > 0.0 else math.pi)
            libsumo.person.moveTo(pid, turned.lane_id, at + 0.5 * self._person_size(pid),
                                  turned.lateral)

    def _turn(self, pid: str, turn: TurnBack) -> _Turned | None:
        """Pedestrian ``pid`` turned back on the lane it is on, or None while its centre is
        not wholly on it (SUMO places it by its front, which :meth:`_place_turned_walkers`
        puts half its length ahead along the lane, where SUMO then faces it)."""
        lane_id = self._person_lanes[pid]
        xy = libsumo.lane.getShape(lane_id)
        lane = StraightLane(tuple(xy[0]), tuple(xy[-1]))
        centre, before = self._centres[pid], self._previous_centres.get(pid, self._centres[pid])
        at = lane.along(centre)
        low = TURN_MARGIN_M
        high = lane.length - 0.5 * self._person_size(pid) - TURN_MARGIN_M
        if not low <= at <= high:
            return None
        velocity = (at - lane.along(before)) / self._dt
        # it came from the end on its start's side (it may stand still now: a pause)
        start = self.pedestrian_plans[pid].standing_xy
        forward = math.dist(lane.start, start) < math.dist(lane.end, start)
        near, far = (low, high) if forward else (high, low)
        rise = None if self._accel is None else self._accel * self._dt
        walker = CrossingWalker(at, velocity, near, far, turn.walking_mps, turn.wait_s,
                                self._dt, rise)
        return _Turned(walker, lane_id, lane, lane.lateral(centre),
                       lane.heading + (0.0 if forward else math.pi))

    def _on_crossing(self, pid: str) -> bool:
        """Whether scenario pedestrian ``pid`` is on its planned crossing now."""
        plan = self.pedestrian_plans[pid]
        return self._person_lanes.get(pid, "").rpartition("_")[0] == plan.crossing

    def _since_on(self, pid: str) -> float | None:
        """How long ago (s) pedestrian ``pid`` stepped onto its crossing; None: not yet."""
        on = self._stepped_on.get(pid)
        return None if on is None else self._time - on

    @contextlib.contextmanager
    def _walking_alone(self) -> Iterator[None]:
        """A failure of the short SUMO sessions before the run (lone walkers timing the walks
        and measuring the jitter, :mod:`sse_cosim.world.walk_probe`) names the scenario."""
        try:
            yield
        except SimulationError as exc:
            if exc.scenario != PROBE:
                raise
            raise SimulationError(self.scenario_name, f"{exc.problem} (lone walkers before the "
                                  "run)") from exc

    def _measure(self) -> walker_jitter.NetworkJitter:
        """What SUMO's lone walkers need on the scene's walking areas in the jitter's scope:
        the jitter and each junction's ground margin (:mod:`sse_cosim.world.walker_jitter`,
        cached)."""
        assert self._roadmap is not None and self._net_path is not None
        net = self._roadmap.net  # None: the whole network (route files)
        return measure_walkers(self._net_path, self._roadmap,
                               None if net is None else scene_extent(self.scenario, net),
                               self.scenario.estimator.max_pedestrian_speed_mps, self._dt,
                               self.scenario.pedestrian_radius_m(), self._accel,
                               jitter_scope(self.scenario, self._roadmap,
                                            self._walked_edges()))

    def _walked_edges(self) -> frozenset[str] | None:
        """Every edge a walker of the scene walks or stands on: the pedestrians' planned paths
        and the route files' persons' (None: SUMO routes some person itself)."""
        assert self._plan is not None
        files = self._route_files.walked_edges
        if files is None:
            return None
        return files | {edge for plan in self._plan.pedestrians.values() for edge in plan.path}

    def _with_jitter(self, measured: walker_jitter.NetworkJitter) -> Scenario:
        """The scenario with the position jitter its network needs: its own where it sets one
        at least the ``measured`` one (or the study lists ``pedestrian_speed``), else the
        measured one up to :data:`MAX_MEASURED_JITTER_M`; a UserError otherwise, whose advice
        the next run accepts."""
        estimator = self.scenario.estimator
        configured = estimator.position_jitter_m
        if configured is not None and (self._motion_declared
                                       or configured >= measured.jitter_m):
            return self.scenario
        if measured.jitter_m > MAX_MEASURED_JITTER_M:
            raise UserError(self.scenario_name, "estimator.position_jitter_m",
                            f"SUMO's walkers need {measured.jitter_m:.3f} m on this network "
                            f"({measured.where()}), more than the {MAX_MEASURED_JITTER_M:g} m "
                            "a measured jitter may be without being asked for",
                            f"set estimator.position_jitter_m = {measured.jitter_m:.3f} (or more; "
                            "every metre of it costs the bus speed near hidden ground), or "
                            "smooth the walking areas of the network")
        if configured is None:
            return _with_estimator(self.scenario, position_jitter_m=measured.jitter_m)
        if configured < measured.jitter_m:
            raise UserError(
                self.scenario_name, "estimator.position_jitter_m",
                f"{configured:g} m is below the {measured.jitter_m:.3f} m SUMO's lone walkers "
                f"need on this network at {measured.speed_mps:g} m/s and {self._dt:g} s steps "
                f"({measured.where()})",
                f"leave estimator.position_jitter_m out to take the measured "
                f"{measured.jitter_m:.3f} m or set at least that (or list "
                f"'{MotionCheck.name}' in breaks_assumptions in a study that breaks it on "
                "purpose)")
        return self.scenario

    def set_speed(self, vehicle_id: str, commanded_mps: float, emergency: bool = False) -> None:
        """Command automated vehicle ``vehicle_id``'s speed (m/s); ``emergency`` brakes at its
        emergency deceleration.

        It follows the command from the next step on, as its acceleration and deceleration
        allow, and never faster than its nominal speed; SUMO's own right of way stays on. A
        command given before it departs applies from its departure on; after it arrived it is
        only recorded.
        """
        if not math.isfinite(commanded_mps) or commanded_mps < 0:
            raise ValueError(f"commanded speed must be finite and >= 0, got {commanded_mps}")
        self._require_open()
        state = self._automated[vehicle_id]
        state.command(float(commanded_mps), bool(emergency))
        if vehicle_id not in self._departed or state.arrived:
            return
        try:
            self._apply_command(vehicle_id)
        except LIBSUMO_ERRORS as exc:
            raise SimulationError(self.scenario_name, f"setting the speed of {vehicle_id!r} "
                                  f"failed: {message(exc)}") from exc

    def _change_lanes(self, vehicle_id: str, lane_id: str, lane_pos: float) -> None:
        """Ask SUMO for automated vehicle ``vehicle_id``'s next planned lane change
        (``RoadMap.route_plan``) once its body is on the change's edge (its front on lane
        ``lane_id`` at ``lane_pos`` m, more than its length): SUMO moves it to the next lane
        within the step where the gaps allow (lane change mode 512), a lane at a time, until
        it is on the planned one. Its sweep covers each lane it may be on meanwhile."""
        state = self._automated[vehicle_id]
        if not state.changes or lane_id.startswith(":") or not lane_id:
            return
        change = state.changes[0]
        lane = self.roadmap.lane(lane_id)
        if lane.edge_id != change.edge_id:
            return
        if lane.index == change.to_index:
            state.changes.popleft()
        elif lane_pos > state.config.length_m:
            libsumo.vehicle.changeLane(vehicle_id, change.to_index, self._dt)

    def _apply_command(self, vehicle_id: str) -> None:
        state = self._automated[vehicle_id]
        if state.acting is None:
            return
        speed, emergency = state.acting
        decel = state.config.emergency_decel_mps2 if emergency \
            else state.config.comfortable_decel_mps2
        if decel != state.decel:
            libsumo.vehicle.setDecel(vehicle_id, decel)
            state.decel = decel
        libsumo.vehicle.setSpeed(vehicle_id, speed)

    # --- state ----------------------------------------------------------------------------

    @property
    def roadmap(self) -> RoadMap:
        """The road's geometry (available once entered)."""
        if self._roadmap is None:
            raise RuntimeError("SumoWorld: enter the context first")
        return self._roadmap

    @property
    def net_path(self) -> Path:
        if self._net_path is None:
            raise RuntimeError("SumoWorld: enter the context first")
        return self._net_path

    @property
    def pedestrian_plans(self) -> dict[str, PedestrianPlan]:
        """Where each present pedestrian waits, when it walks and steps onto the crossing, by
        id."""
        return {} if self._plan is None else self._plan.pedestrians

    @property
    def time(self) -> float:
        """Time (s) of the latest snapshot; ``-step_length`` before the first step."""
        return self._time

    @property
    def step_length(self) -> float:
        return self._dt

    def route_length(self, vehicle_id: str) -> float:
        """Length (m) of automated vehicle ``vehicle_id``'s route from the start of its first
        edge to the end of its last, junction passages included; the frame of its
        ``depart_pos_m``."""
        return self.roadmap.route_length(self._automated[vehicle_id].config.route_edges)

    def route_position(self, vehicle_id: str) -> float:
        """Automated vehicle ``vehicle_id``'s front position (m) along its route, same frame
        as ``route_length``."""
        state = self._automated[vehicle_id]
        return state.config.depart_pos_m + state.distance

    def departed(self, vehicle_id: str) -> bool:
        """Whether SUMO has inserted vehicle ``vehicle_id``."""
        return vehicle_id in self._departed

    def arrived(self, vehicle_id: str) -> bool:
        """Whether automated vehicle ``vehicle_id`` reached the end of its route (and left
        the simulation)."""
        return self._automated[vehicle_id].arrived

    @property
    def all_arrived(self) -> bool:
        """Whether every automated vehicle reached the end of its route."""
        return all(state.arrived for state in self._automated.values())

    def last_commanded_speed(self, vehicle_id: str) -> float | None:
        """The latest ``set_speed`` command of ``vehicle_id`` (m/s), None before the first."""
        return self._automated[vehicle_id].commanded

    @property
    def teleports(self) -> int:
        """Vehicles SUMO teleported so far (always 0 unless something is badly wrong)."""
        return self._teleports

    @property
    def collisions(self) -> tuple[Collision, ...]:
        return tuple(self._collisions)

    # --- internals ------------------------------------------------------------------------

    def _require_open(self) -> None:
        if not self._open:
            raise SimulationError(self.scenario_name, "the SUMO world is not open "
                                  "(use it inside 'with SumoWorld(...) as world:')")

    def _check_carrier_types(self) -> None:
        """A sensor carried by type names a vehicle type of the route files."""
        for name, sensor in self.scenario.sensors.items():
            carrier = sensor.carrier_type
            if carrier is not None and carrier not in self._route_files.type_ids:
                raise UserError(self.scenario_name, f"sensors.{name}.carrier_type",
                                f"no file in network.route_files declares the type {carrier!r}",
                                "name a vType of the route files, or carry the sensor on a "
                                "node (sensors.<name>.node)")

    def _check_steps_onto_crossings(self, snapshot: Snapshot) -> None:
        """Every planned pedestrian steps onto its crossing within its
        ``crossing_tolerance_s`` (:data:`CROSSING_TOLERANCE_S` where left out, at least one
        step) of its ``steps_onto_crossing_s``; SUMO holding it up longer (a person or
        vehicle in its way, a red light) or letting it step on earlier stops the run
        (:class:`SimulationError`, naming the vehicles on that crossing: SUMO keeps a
        pedestrian off a crossing a vehicle occupies)."""
        time = snapshot.time
        for pid, plan in self.pedestrian_plans.items():
            if pid in self._stepped_on:
                continue
            wanted = plan.crossing_time_s
            on = self._on_crossing(pid)
            if on:
                self._stepped_on[pid] = time
            tolerance = self.scenario.pedestrians[pid].crossing_tolerance_s
            allowed = max(self._dt, CROSSING_TOLERANCE_S if tolerance is None else tolerance)
            if abs(time - wanted) <= allowed + TIME_EPS_S or (not on and time < wanted):
                continue
            when = f"stepped onto it at {time:.2f} s" if on else (
                f"had not stepped onto it by {time:.2f} s"
                f"{self._occupied(plan.crossing, snapshot)}")
            raise SimulationError(
                self.scenario_name, f"pedestrian {pid!r} was to step onto its crossing "
                f"{plan.crossing} at {wanted:g} s (pedestrians.{pid}.steps_onto_crossing_s, "
                f"walking from {plan.walk_start_s:g} s) and {when}, more than "
                f"{allowed:g} s off: something in SUMO held it up or its walk differs from "
                "the lone walker's that timed it -- clear its walk (persons or vehicles in its "
                f"way, a pedestrian light), change pedestrians.{pid}.steps_onto_crossing_s "
                f"or pedestrians.{pid}.start_pos_m, or allow more with "
                f"pedestrians.{pid}.crossing_tolerance_s")

    def _occupied(self, crossing: str, snapshot: Snapshot) -> str:
        """Which vehicles' bodies are on ``crossing`` now, as a clause of the message; empty
        if none is."""
        on = sorted(v.id for v in snapshot.vehicles.values() if crossing in v.on_crossings)
        return f" (on it: {', '.join(on)})" if on else ""

    def _check_insertions(self) -> None:
        """Every automated and moving vehicle is on the road from its departure on; SUMO
        would keep one it has no room for waiting and insert it later (see module
        docstring)."""
        for vid, av in present(self.scenario.automated).items():
            self._check_inserted(vid, av.depart_s, f"automated.{vid}", av.route_edges[0],
                                 av.depart_pos_m,
                                 f"move automated.{vid}.depart_pos_m to where there is room, or "
                                 f"change automated.{vid}.depart_s")
        for vid, car in present(self.scenario.vehicles).items():
            self._check_inserted(vid, car.depart_s, f"vehicles.{vid}", car.route_edges[0],
                                 car.depart_pos_m,
                                 "place it where nothing stands and, on an automated "
                                 "vehicle's lane, far enough ahead of it to brake (or behind "
                                 f"it), or change vehicles.{vid}.depart_s")

    def _check_inserted(self, vid: str, depart_s: float, table: str, edge: str, pos: float,
                        fix: str) -> None:
        if vid in self._departed or self._time < depart_s - 1e-9:
            return
        raise UserError(self.scenario_name, f"{table}.depart_pos_m", f"SUMO cannot insert "
                        f"{vid!r} at {pos:g} m on edge {edge!r} ({table}.depart_s = "
                        f"{depart_s:g} s) at its departure: no room there, or the vehicle "
                        "behind it could not brake for it; SUMO would insert it later, behind "
                        f"that vehicle (see {self.run_dir / LOG_FILE_NAME})", fix)

    def _write_files(self) -> Path:
        assert self._plan is not None and self._net_path is not None
        try:
            self.run_dir.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise UserError(str(self.run_dir), "", f"cannot create the run folder ({exc})",
                            "choose a writable output folder") from None
        routes = demand.write_route_file(self.scenario, self._plan,
                                         self.run_dir / demand.ROUTE_FILE_NAME)
        sim = self.scenario.simulation
        return write_config(self.run_dir, self._net_path, [routes, *self._route_files.paths],
                            sim.step_length_s, sim.seed,
                            f"SUMO configuration of scenario {self.scenario_name!r}, written by "
                            "sse_cosim.world; replay with: sumo-gui -c sumo.sumocfg")

    def _snapshot(self) -> Snapshot:
        sim = libsumo.simulation
        self._time = round(sim.getTime() - self._dt, 6)
        for vid in sim.getDepartedIDList():
            self._departed.add(vid)
            automated = vid in self._automated
            libsumo.vehicle.subscribe(vid, _AUTOMATED_VARS if automated else _VEHICLE_VARS)
            if automated:
                libsumo.vehicle.setSpeedMode(vid, AUTOMATED_SPEED_MODE)
                libsumo.vehicle.setLaneChangeMode(vid, AUTOMATED_LANE_CHANGE_MODE)
                self._apply_command(vid)
        for pid in sim.getDepartedPersonIDList():
            libsumo.person.subscribe(pid, _PERSON_VARS)
            if self._ramp is not None:
                self._walking_speeds[pid] = self._walking_speed(pid)
        for vid in sim.getArrivedIDList():
            if vid in self._automated:
                self._automated[vid].arrived = True
        self._teleports += sim.getStartingTeleportNumber()
        for c in sim.getCollisions():
            self._collisions.append(Collision(self._time, c.collider, c.victim, c.type))
        vehicles: dict[str, VehicleState] = {}
        for vid, values in libsumo.vehicle.getAllSubscriptionResults().items():
            x, y = values[libsumo.VAR_POSITION]
            length, width, type_id = self._static(vid)
            footprint = Footprint(Pose(float(x), float(y), heading(values[libsumo.VAR_ANGLE])),
                                  length, width)
            if vid in self._automated:
                self._automated[vid].distance = float(values[libsumo.VAR_DISTANCE])
                self._change_lanes(vid, str(values[libsumo.VAR_LANE_ID]),
                                   float(values[libsumo.VAR_LANEPOSITION]))
            vehicles[vid] = VehicleState(
                id=vid, kind=self._kinds.get(vid, "other"), footprint=footprint,
                speed=float(values[libsumo.VAR_SPEED]), type_id=type_id,
                on_crossings=self.roadmap.crossings_meeting(footprint.polygon()),
                route_m=self.route_position(vid) if vid in self._automated else None)
        persons: dict[str, PersonState] = {}
        self._previous_lanes = self._person_lanes
        self._previous_centres = self._centres
        self._person_lanes = {}
        self._person_speeds = {}
        self._centres = {}
        for pid, values in libsumo.person.getAllSubscriptionResults().items():
            self._person_lanes[pid] = str(values[libsumo.VAR_LANE_ID])
            self._person_speeds[pid] = float(values[libsumo.VAR_SPEED])
            walking = bool(values[libsumo.VAR_LANE_ID])
            self._centres[pid] = self._person_position(pid, values)
            speed, walking_heading = float(values[libsumo.VAR_SPEED]), \
                heading(values[libsumo.VAR_ANGLE]) if walking else None
            turned = self._turned.get(pid)
            if turned is not None:  # SUMO holds it at speed 0, facing along the lane
                speed, walking_heading = abs(turned.walker.velocity_mps), turned.heading
            road = str(values[libsumo.VAR_ROAD_ID])
            persons[pid] = PersonState(
                id=pid, position=self._centres[pid], speed=speed,
                crossing=road if road in self.roadmap.crossing_ids else None,
                heading=walking_heading, next_crossing=self._next_crossing(pid, road))
        return Snapshot(time=self._time, vehicles=vehicles, persons=persons,
                        signals={light: _signal_state(light) for light in self._lights})

    def _next_crossing(self, pid: str, road: str) -> str | None:
        """The crossing next on person ``pid``'s walk while it is on a walking area (the
        internal edges a person walks are walking areas and crossings); None otherwise."""
        if not road.startswith(":") or road in self.roadmap.crossing_ids:
            return None
        edge = libsumo.person.getNextEdge(pid)
        return edge if edge in self.roadmap.crossing_ids else None

    def _person_position(self, pid: str, values: dict[int, Any]) -> tuple[float, float]:
        """A person's centre. A walking person SUMO places by its front; a waiting one (on no
        lane: a pedestrian before its walk) it draws beside the sidewalk, so its plan's
        standing point is used, where its walk then begins."""
        plan = self.pedestrian_plans.get(pid)
        if not values[libsumo.VAR_LANE_ID] and plan is not None:
            return plan.standing_xy
        x, y = values[libsumo.VAR_POSITION]
        return person_centre(x, y, values[libsumo.VAR_ANGLE], self._person_size(pid))

    def _walking_speed(self, pid: str) -> float:
        """The speed (m/s) person ``pid`` walks at unramped: a scenario pedestrian's
        ``walking_speed_mps``; a route file's person's speed as SUMO gives it at its departure
        (its type's, with its speed factor), before the ramp first sets it."""
        ped = self.scenario.pedestrians.get(pid)
        return ped.walking_speed_mps if ped is not None else float(libsumo.person.getMaxSpeed(pid))

    def _static(self, vid: str) -> tuple[float, float, str]:
        """A vehicle's length, width (m) and type id, which do not change during a run."""
        static = self._statics.get(vid)
        if static is None:
            static = (float(libsumo.vehicle.getLength(vid)), float(libsumo.vehicle.getWidth(vid)),
                      str(libsumo.vehicle.getTypeID(vid)))
            self._statics[vid] = static
        return static

    def _person_size(self, pid: str) -> float:
        length = self._person_length.get(pid)
        if length is None:
            ped = self.scenario.pedestrians.get(pid)
            length = (2.0 * ped.radius_m if ped is not None
                      else float(libsumo.person.getLength(pid)))
            self._person_length[pid] = length
        return length


def _with_estimator(scenario: Scenario, **changes: Any) -> Scenario:
    """``scenario`` with ``changes`` to its estimator section (a validated copy)."""
    estimator = scenario.estimator.model_copy(update=changes)
    return scenario.model_copy(update={"estimator": estimator})


def _signal_state(light: str) -> SignalState:
    """Traffic light ``light`` as SUMO runs it now."""
    lights = libsumo.trafficlight
    return SignalState(lights.getProgram(light), lights.getPhase(light),
                       lights.getRedYellowGreenState(light), lights.getSpentDuration(light))

"""The SUMO world: the only module of the project that imports ``libsumo``.

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
bus). So ``step()`` raises :class:`UserError` naming ``bus.depart_pos_m``
(``car.depart_pos_m``) as soon as the bus (the car) is not on the road at its departure: a
scenario's actors start where and when it says, or the run is refused.

The pedestrian exists from t=0 and stands at its start until its walk starts (see
:mod:`sse_cosim.world.demand`); meanwhile the snapshot places it at the plan's standing point
on the sidewalk, where its walk then begins, not where SUMO draws a waiting person.

Speed mode. The bus drives under speed mode 31 (SUMO's default, set explicitly): SUMO keeps the
safe speed towards leaders, the bus's maximum acceleration and deceleration, and the right of
way at junctions -- so SUMO still yields to pedestrians on the priority crossing -- while
:meth:`SumoWorld.set_bus_speed` sets the speed the bus follows (``vehicle.setSpeed``, held
until the next command) as closely as its acceleration and deceleration allow. The actual speed
is in the snapshot (``Snapshot.bus_actual_speed``), the command in ``last_commanded_speed``.
Before the first command the bus drives at its nominal speed (its maximum speed).

Emergency brake. ``set_bus_speed(v, emergency=True)`` sets the bus's deceleration to the
scenario's emergency deceleration (``vehicle.setDecel``) before commanding ``v``; the next
normal command restores the comfortable deceleration. So an emergency brake uses the same
control path as any command (speed mode, right of way and safe speed stay on) and brakes at
exactly ``emergency_decel_mps2`` per second; ``slowDown`` would instead spread the change over
a chosen duration, which is not what a brake is.

One simulation per process. libsumo runs SUMO inside this process and holds one simulation at
a time: a second ``SumoWorld`` entered while one is open raises :class:`SimulationError`. After
``close()`` a new simulation can be started in the same process (the tests do so), but sweeps
run each simulation in its own process so that they can run in parallel.

Determinism. Every vehicle and person type has ``speedDev=0`` and ``sigma=0`` (the route
files' too, or they are refused), pedestrians do not dawdle (``pedestrian.striping.dawdling
0``) and SUMO's seed is the scenario's seed: one scenario gives one sequence of snapshots.
Nobody is teleported (``time-to-teleport -1``); collisions are reported (``collision.action
warn``, junctions included) and kept in ``collisions``.
"""

from __future__ import annotations

import contextlib
import io
import logging
import math
import os
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import Any
from xml.sax.saxutils import quoteattr

from sse_cosim.errors import SimulationError, UserError
from sse_cosim.files import write_text_atomic
from sse_cosim.scenario.model import Scenario
from sse_cosim.world import demand
from sse_cosim.world.demand import (
    BUS_ID,
    CAR_ID,
    PEDESTRIAN_ID,
    ROLES,
    ActorPlan,
    PedestrianPlan,
)
from sse_cosim.world.network import NetworkBuildError, scenario_net_path
from sse_cosim.world.roadmap import RoadMap, load_roadmap, require_pedestrian_ground
from sse_cosim.world.route_files import RouteFiles, read_route_files
from sse_cosim.world.snapshot import Footprint, PersonState, Pose, Snapshot, VehicleState

with contextlib.redirect_stdout(io.StringIO()):
    # libsumo's import prints a note about the installed pyarrow's version; keep stdout clean.
    import libsumo

log = logging.getLogger(__name__)

BUS_SPEED_MODE = 31
CONFIG_FILE_NAME = "sumo.sumocfg"
LOG_FILE_NAME = "sumo.log"
_VEHICLE_VARS = (libsumo.VAR_POSITION, libsumo.VAR_ANGLE, libsumo.VAR_SPEED)
_BUS_VARS = (*_VEHICLE_VARS, libsumo.VAR_DISTANCE)
_PERSON_VARS = (libsumo.VAR_POSITION, libsumo.VAR_ANGLE, libsumo.VAR_SPEED, libsumo.VAR_ROAD_ID,
                libsumo.VAR_LANE_ID)
_LIBSUMO_ERRORS: tuple[type[BaseException], ...] = (
    libsumo.TraCIException, libsumo.FatalTraCIError, RuntimeError)

_open_world: SumoWorld | None = None


def sumo_version() -> str:
    """SUMO's version, e.g. ``1.28.0`` (of the libsumo in use)."""
    version = str(libsumo.__version__) if hasattr(libsumo, "__version__") else ""
    if version:
        return version
    return str(libsumo.getVersion()[1]).removeprefix("SUMO ").strip()


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
        self._bus_arrived = False
        self._bus_distance = 0.0
        self._bus_decel = scenario.bus.comfortable_decel_mps2
        self._last_commanded: float | None = None
        self._last_emergency = False
        self._teleports = 0
        self._collisions: list[Collision] = []
        self._statics: dict[str, tuple[float, float, str]] = {}
        self._person_length: dict[str, float] = {}

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
        self._roadmap = load_roadmap(self._net_path)
        if self.scenario.pedestrian.present:
            require_pedestrian_ground(
                self._roadmap, self.scenario_name,
                "network.net_file" if network.net_file else "network.sources_dir")
        self._route_files = read_route_files(network.route_files, (*ROLES, PEDESTRIAN_ID),
                                             self.scenario_name)
        self._check_carrier_types()
        self._plan = demand.plan_actors(self.scenario, self._net_path, self._roadmap,
                                        source=self.scenario_name)
        config = self._write_files()
        try:
            libsumo.start(["sumo", "-c", str(config)])
        except _LIBSUMO_ERRORS as exc:
            with contextlib.suppress(*_LIBSUMO_ERRORS):
                libsumo.close()
            raise SimulationError(self.scenario_name, f"SUMO did not start: {_message(exc)} "
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
        except _LIBSUMO_ERRORS as exc:
            log.warning("%s: closing SUMO failed: %s", self.scenario_name, _message(exc))

    # --- stepping -------------------------------------------------------------------------

    def step(self) -> Snapshot:
        """Advance SUMO by one step and return the new state.

        Raises :class:`UserError` when a vehicle is not on the road at its departure (SUMO
        found no room to insert it where the scenario places it).
        """
        self._require_open()
        try:
            libsumo.simulationStep()
            snapshot = self._snapshot()
        except _LIBSUMO_ERRORS as exc:
            raise SimulationError(self.scenario_name,
                                  f"SUMO step at t={self._time + self._dt:.2f} s failed: "
                                  f"{_message(exc)}") from exc
        self._check_insertions()
        return snapshot

    def set_bus_speed(self, commanded_mps: float, emergency: bool = False) -> None:
        """Command the bus's speed (m/s); ``emergency`` brakes at the emergency deceleration.

        The bus follows the command from the next step on, as its acceleration and
        deceleration allow, and never faster than its nominal speed; SUMO's own right of way
        stays on. A command given before the bus departs applies from its departure on;
        after the bus arrived it is only recorded.
        """
        if not math.isfinite(commanded_mps) or commanded_mps < 0:
            raise ValueError(f"commanded bus speed must be finite and >= 0, got {commanded_mps}")
        self._require_open()
        self._last_commanded = float(commanded_mps)
        self._last_emergency = bool(emergency)
        if not self.bus_departed or self._bus_arrived:
            return
        try:
            self._apply_command()
        except _LIBSUMO_ERRORS as exc:
            raise SimulationError(self.scenario_name,
                                  f"setting the bus's speed failed: {_message(exc)}") from exc

    def _apply_command(self) -> None:
        if self._last_commanded is None:
            return
        bus = self.scenario.bus
        decel = bus.emergency_decel_mps2 if self._last_emergency else bus.comfortable_decel_mps2
        if decel != self._bus_decel:
            libsumo.vehicle.setDecel(BUS_ID, decel)
            self._bus_decel = decel
        libsumo.vehicle.setSpeed(BUS_ID, self._last_commanded)

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
    def pedestrian_plan(self) -> PedestrianPlan | None:
        """Where the pedestrian waits, when it walks and steps onto the crossing (None without
        one)."""
        return None if self._plan is None else self._plan.pedestrian

    @property
    def time(self) -> float:
        """Time (s) of the latest snapshot; ``-step_length`` before the first step."""
        return self._time

    @property
    def step_length(self) -> float:
        return self._dt

    @property
    def bus_route_length(self) -> float:
        """Length (m) of the bus's route from the start of its first edge to the end of its last,
        junction passages included; the frame of ``bus.depart_pos_m``."""
        return self.roadmap.route_length(self.scenario.bus.route_edges)

    @property
    def bus_route_position(self) -> float:
        """The bus front's position (m) along its route, same frame as ``bus_route_length``."""
        return self.scenario.bus.depart_pos_m + self._bus_distance

    @property
    def bus_departed(self) -> bool:
        """Whether SUMO has inserted the bus (it may wait for room at its departure)."""
        return BUS_ID in self._departed

    @property
    def bus_arrived(self) -> bool:
        """Whether the bus reached the end of its route (and left the simulation)."""
        return self._bus_arrived

    @property
    def last_commanded_speed(self) -> float | None:
        """The latest ``set_bus_speed`` command (m/s), None before the first."""
        return self._last_commanded

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

    def _check_insertions(self) -> None:
        """Every vehicle is on the road from its departure on; SUMO would keep one it has no
        room for waiting and insert it later (see module docstring)."""
        bus, car = self.scenario.bus, self.scenario.car
        self._check_inserted(BUS_ID, 0.0, "bus.depart_pos_m",
                             f"at {bus.depart_pos_m:g} m on edge {bus.route_edges[0]!r}",
                             "move bus.depart_pos_m to where there is room")
        if car.present:
            self._check_inserted(CAR_ID, car.depart_s, "car.depart_pos_m",
                                 f"at {car.depart_pos_m:g} m on edge {car.route_edges[0]!r} "
                                 f"(car.depart_s = {car.depart_s:g} s)",
                                 "place the car where nothing stands and, on the bus's lane, "
                                 "far enough ahead of the bus for it to brake (or behind it), "
                                 "or change car.depart_s")

    def _check_inserted(self, vid: str, depart_s: float, field: str, where: str,
                        fix: str) -> None:
        if vid in self._departed or self._time < depart_s - 1e-9:
            return
        raise UserError(self.scenario_name, field, f"SUMO cannot insert the {ROLES[vid]} "
                        f"{where} at its departure: no room there, or the vehicle behind it "
                        "could not brake for it; SUMO would insert it later, behind that vehicle "
                        f"(see {self.run_dir / LOG_FILE_NAME})", fix)

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
        # relative to this file, where SUMO resolves them: no machine path in a results folder
        route_files = [routes.name, *(self._relative(p) for p in self._route_files.paths)]
        options = {
            "input": {"net-file": self._relative(self._net_path),
                      "route-files": ",".join(route_files)},
            "time": {"begin": "0", "step-length": f"{sim.step_length_s:.10g}"},
            "processing": {
                "time-to-teleport": "-1",
                "collision.action": "warn",
                "collision.check-junctions": "true",
                "pedestrian.model": "striping",
                "pedestrian.striping.dawdling": "0",
                "pedestrian.striping.stripe-width": f"{demand.STRIPE_WIDTH_M:g}",
            },
            "report": {"no-step-log": "true", "duration-log.disable": "true",
                       "error-log": LOG_FILE_NAME},
            "random_number": {"seed": str(sim.seed)},
        }
        lines = ['<?xml version="1.0" encoding="UTF-8"?>',
                 f"<!-- SUMO configuration of scenario {self.scenario_name!r}, written by "
                 "sse_cosim.world; replay with: sumo-gui -c sumo.sumocfg -->",
                 "<configuration>"]
        for section, values in options.items():
            lines.append(f"    <{section}>")
            lines += [f"        <{k} value={quoteattr(v)}/>" for k, v in values.items()]
            lines.append(f"    </{section}>")
        lines += ["</configuration>", ""]
        return write_text_atomic(self.run_dir / CONFIG_FILE_NAME, "\n".join(lines))

    def _relative(self, path: Path) -> str:
        """``path`` relative to the run folder (where SUMO resolves the configuration's)."""
        return os.path.relpath(path.resolve(), self.run_dir.resolve())

    def _snapshot(self) -> Snapshot:
        sim = libsumo.simulation
        self._time = round(sim.getTime() - self._dt, 6)
        for vid in sim.getDepartedIDList():
            self._departed.add(vid)
            libsumo.vehicle.subscribe(vid, _BUS_VARS if vid == BUS_ID else _VEHICLE_VARS)
            if vid == BUS_ID:
                libsumo.vehicle.setSpeedMode(BUS_ID, BUS_SPEED_MODE)
                self._apply_command()
        for pid in sim.getDepartedPersonIDList():
            libsumo.person.subscribe(pid, _PERSON_VARS)
        if BUS_ID in sim.getArrivedIDList():
            self._bus_arrived = True
        self._teleports += sim.getStartingTeleportNumber()
        for c in sim.getCollisions():
            self._collisions.append(Collision(self._time, c.collider, c.victim, c.type))
        vehicles: dict[str, VehicleState] = {}
        for vid, values in libsumo.vehicle.getAllSubscriptionResults().items():
            x, y = values[libsumo.VAR_POSITION]
            length, width, type_id = self._static(vid)
            heading = _heading(values[libsumo.VAR_ANGLE])
            vehicles[vid] = VehicleState(
                id=vid, role=ROLES.get(vid, "other"),
                footprint=Footprint(Pose(float(x), float(y), heading), length, width),
                speed=float(values[libsumo.VAR_SPEED]), type_id=type_id)
            if vid == BUS_ID:
                self._bus_distance = float(values[libsumo.VAR_DISTANCE])
        persons: dict[str, PersonState] = {}
        for pid, values in libsumo.person.getAllSubscriptionResults().items():
            persons[pid] = PersonState(
                id=pid,
                position=self._person_position(pid, values),
                speed=float(values[libsumo.VAR_SPEED]),
                on_crossing=values[libsumo.VAR_ROAD_ID] in self.roadmap.crossing_ids)
        return Snapshot(time=self._time, vehicles=vehicles, persons=persons)

    def _person_position(self, pid: str, values: dict[int, Any]) -> tuple[float, float]:
        """A person's centre. A walking person SUMO places by its front; a waiting one (on no
        lane: the pedestrian before its walk) it draws beside the sidewalk, so the plan's
        standing point is used, where its walk then begins."""
        plan = self.pedestrian_plan
        if not values[libsumo.VAR_LANE_ID] and pid == PEDESTRIAN_ID and plan is not None:
            return plan.standing_xy
        x, y = values[libsumo.VAR_POSITION]
        heading = _heading(values[libsumo.VAR_ANGLE])
        half = 0.5 * self._person_size(pid)
        return float(x) - half * math.cos(heading), float(y) - half * math.sin(heading)

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
            length = (2.0 * self.scenario.pedestrian.radius_m if pid == PEDESTRIAN_ID
                      else float(libsumo.person.getLength(pid)))
            self._person_length[pid] = length
        return length


def _heading(nav_angle_deg: float) -> float:
    """SUMO's navigational angle (deg, 0 = north, clockwise) as a heading (rad, CCW from east),
    in [-pi, pi)."""
    return math.radians((90.0 - nav_angle_deg + 180.0) % 360.0 - 180.0)


def _message(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text or type(exc).__name__

"""The scenario schema: every field a scenario file may set, with its unit and default.

Coordinates are SUMO network coordinates in metres (x east, y north). Angles called
``heading_deg`` / ``yaw_deg`` are mathematical: counter-clockwise from east (+x), unlike
SUMO's navigational angle (clockwise from north); the world adapter converts.
"""

from __future__ import annotations

from typing import Any, Literal, TypeVar

from pydantic import (
    Field,
    SerializerFunctionWrapHandler,
    field_validator,
    model_serializer,
    model_validator,
)

from sse_cosim.estimation.motion import MODELS
from sse_cosim.regions import KINDS
from sse_cosim.scenario.base import NonNegativeFloat, PositiveFloat, StrictModel
from sse_cosim.sensors.kinds import Sensor, SensorMount
from sse_cosim.sets import available_fusion_methods, available_gain_methods
from sse_cosim.sets.reduction import REDUCTION_METHODS

__all__ = ["NonNegativeFloat", "PositiveFloat", "Sensor", "SensorMount", "StrictModel"]

Assumption = Literal["pedestrian_speed", "walkable_ground", "pedestrian_lights",
                     "sensor_bounds", "shared_estimates", "reaction_time"]


class Simulation(StrictModel):
    duration_s: PositiveFloat = Field(30.0, description="Simulated time in seconds.")
    step_length_s: PositiveFloat = Field(
        0.1, ge=0.001, le=1.0, description="SUMO step length in seconds (SUMO's resolution is "
        "1 ms)."
    )
    seed: int = Field(1, ge=0, description="Seed of SUMO and of every random draw (noise, V2X).")


DEFAULT_SOURCES_DIR = "../sumo_net"
CROSSING_TOLERANCE_S = 1.0  # a planned step onto a crossing may come this late or early (s)


class Network(StrictModel):
    sources_dir: str | None = Field(
        None,
        description="Folder of the plain-XML network sources, relative to the file that sets it "
        "(to the working directory with --set); built by netconvert; unset and without "
        f"net_file: {DEFAULT_SOURCES_DIR!r}.",
    )
    net_file: str | None = Field(
        None,
        description="An existing SUMO network (.net.xml), relative to the file that sets it (to "
        "the working directory with --set); "
        "instead of sources_dir (docs/own_network.md).",
    )
    route_files: list[str] = Field(
        default_factory=list,
        description="SUMO route files (.rou.xml) loaded next to the scenario's own, relative to "
        "the file that sets them (to the working directory with --set): their vehicles "
        "occlude, their persons are pedestrians; every type must set speedDev=\"0\" and "
        "sigma=\"0\".",
    )

    @model_validator(mode="before")
    @classmethod
    def _one_network(cls, data: Any) -> Any:
        """Exactly one of sources_dir and net_file; neither: the default sources."""
        if not isinstance(data, dict):
            return data
        given = [k for k in ("sources_dir", "net_file") if data.get(k) is not None]
        if len(given) == 2:
            raise ValueError("net_file: network.sources_dir and network.net_file are both set; "
                             "keep one of them (a plain-XML folder or an existing .net.xml)")
        return data if given else {**data, "sources_dir": DEFAULT_SOURCES_DIR}


class AutomatedVehicle(StrictModel):
    present: bool = Field(True, description="Whether the vehicle is in the scene (false removes "
                          "an inherited one).")
    vehicle_class: Literal["bus", "passenger", "delivery", "truck"] = Field(
        "bus", description="SUMO vehicle class (and drawn shape).")
    route_edges: list[str] = Field(["WC", "CE"], min_length=1, description="Edge ids, in order.")
    depart_s: NonNegativeFloat = Field(0.0, description="Departure time (s).")
    depart_pos_m: NonNegativeFloat = Field(0.0, description="Front position on the first edge (m).")
    nominal_speed_mps: PositiveFloat = Field(
        20.0, description="Nominal speed (m/s), Table I: 20; at most the fastest speed limit on "
        "its route. The vehicle drives each lane at most at the lane's limit, and its controller "
        "plans with the limits ahead."
    )
    length_m: PositiveFloat = Field(12.0, description="Length (m).")
    width_m: PositiveFloat = Field(2.55, description="Width (m).")
    accel_mps2: PositiveFloat = Field(1.5, description="Maximum acceleration (m/s^2).")
    comfortable_decel_mps2: PositiveFloat = Field(
        3.0, description="Deceleration used between speed levels (m/s^2)."
    )
    emergency_decel_mps2: PositiveFloat = Field(
        7.0, description="Deceleration of an emergency brake (m/s^2)."
    )
    actuation_delay_s: NonNegativeFloat = Field(
        0.0, description="How long the simulated vehicle takes to act on a command beyond "
        "SUMO's own step (s, whole steps): each command, the emergency brake included, is "
        "applied this much later. A4 (docs/controller.md) asks controller.reaction_time_s to "
        "cover it; a longer delay (a controller deliberately mis-set) needs 'reaction_time' in "
        "breaks_assumptions."
    )

    @model_serializer(mode="wrap")
    def _no_zero_delay(self, handler: SerializerFunctionWrapHandler) -> dict[str, Any]:
        """A vehicle that acts at SUMO's own step writes no ``actuation_delay_s`` (its
        default), so every ``scenario.json`` written before the field reads the same."""
        data = handler(self)
        if self.actuation_delay_s == 0.0:
            data.pop("actuation_delay_s", None)
        return data


class ParkedVehicle(StrictModel):
    present: bool = Field(True, description="Whether the vehicle is in the scene (false removes "
                          "an inherited one).")
    edge: str = Field("WC", description="Edge it is parked on.")
    lane_index: int = Field(1, ge=0, description="Lane index on that edge (1 = parking strip).")
    end_pos_m: NonNegativeFloat = Field(
        183.0,
        description="Position of its front along the edge (m): 15 m before the crossing (the "
        "crossing starts at 198 m; Swedish rules forbid parking within 10 m before it).",
    )
    length_m: PositiveFloat = Field(10.0, description="Length (m).")
    width_m: PositiveFloat = Field(2.5, description="Width (m).")


class Vehicle(StrictModel):
    present: bool = Field(True, description="Whether the vehicle is in the scene (false removes "
                          "an inherited one).")
    connected: bool = Field(True, description="Whether it shares over V2X (only a connected "
                            "vehicle may carry sensors).")
    route_edges: list[str] = Field(["EC", "CW"], min_length=1, description="Edge ids, in order.")
    lane_index: int = Field(2, ge=0, description="Driving lane index on its edges.")
    depart_s: NonNegativeFloat = Field(0.0, description="Departure time (s).")
    depart_pos_m: NonNegativeFloat = Field(0.0, description="Front position on the first edge (m).")
    speed_mps: PositiveFloat = Field(
        10.0,
        description="Constant speed (m/s); at most the speed limit of every lane on its route.",
    )
    length_m: PositiveFloat = Field(4.5, description="Length (m).")
    width_m: PositiveFloat = Field(1.8, description="Width (m).")


class Pedestrian(StrictModel):
    present: bool = Field(True, description="Whether the pedestrian is in the scene (false "
                          "removes an inherited one).")
    start_edge: str = Field("WC", description="Edge whose sidewalk it starts on.")
    start_pos_m: NonNegativeFloat = Field(
        184.0, description="Start position along that edge (m): 14 m before the crossing, "
        "1 m past the truck's front."
    )
    end_edge: str = Field("CW", description="Edge whose sidewalk it walks to (across the zebra).")
    end_pos_m: NonNegativeFloat = Field(4.0, description="Arrival position along that edge (m).")
    walking_speed_mps: PositiveFloat = Field(
        1.5, le=3.0, description="Walking speed (m/s); at most estimator.max_pedestrian_speed_mps "
        "unless breaks_assumptions lists 'pedestrian_speed'."
    )
    steps_onto_crossing_s: NonNegativeFloat = Field(
        11.5, description="Time at which it steps onto the crossing (s), within one simulation "
        "step. It stands at its start from t = 0 and starts walking in time, timed by a lone "
        "SUMO walker on its walk; it does not wait for vehicles at the kerb. A time its walk "
        "cannot make is an error naming the earliest one."
    )
    crossing_tolerance_s: NonNegativeFloat | None = Field(
        None, description="How far (s) its step onto the crossing may be from "
        "steps_onto_crossing_s before the run stops (at least one step); left out: "
        f"{CROSSING_TOLERANCE_S:g} s, room for a car's right of way holding it at the kerb for "
        "a moment. A crowd whose pedestrians hold each other up on the sidewalk sets more "
        "(scenarios/crowd.toml)."
    )
    crossing: str | None = Field(
        None, description="SUMO id of the crossing its walk takes (e.g. ':C_c0'), where the walk "
        "has a choice; left out: the crossing of the shortest walk."
    )
    radius_m: PositiveFloat = Field(0.3, description="Body radius used for collisions (m).")
    pause_after_s: NonNegativeFloat = Field(
        0.0, description="How long after stepping onto its crossing it stops (s), when "
        "pause_for_s is set: a pedestrian who hesitates on the zebra (or beyond it, if it has "
        "crossed by then). It stops and walks on within one step, or within "
        "estimator.max_pedestrian_accel_mps2 under the bounded-acceleration model."
    )
    pause_for_s: NonNegativeFloat = Field(
        0.0, description="How long it stands still there (s), then walks on at its walking "
        "speed; 0: it does not stop."
    )
    turn_back_after_s: NonNegativeFloat | None = Field(
        None, description="How long after stepping onto its crossing it turns back (s): it "
        "stops, walks back to the zebra's near end, waits there turn_back_wait_s, then crosses "
        "after all and leaves the scene at the far end (a pedestrian who thinks better of "
        "crossing, then goes), within its walking speed, and within "
        "estimator.max_pedestrian_accel_mps2 under the bounded-acceleration model. If it has "
        "left the crossing by then, it does not turn. None: it crosses."
    )
    turn_back_wait_s: NonNegativeFloat = Field(
        0.0, description="How long it waits at the zebra's near end after turning back (s)."
    )


class RoadSideUnit(StrictModel):
    x_m: float = Field(description="Position x (m, network coordinates).")
    y_m: float = Field(description="Position y (m, network coordinates).")
    heading_deg: float = Field(0.0, description="Heading (deg, CCW from east).")


class V2X(StrictModel):
    range_m: PositiveFloat = Field(
        300.0, description="Communication range between a sender and an automated vehicle (m).")
    latency_steps: int = Field(1, ge=0, le=100, description="Delivery delay (simulation steps).")
    drop_probability: float = Field(0.0, ge=0, lt=1, description="Probability a message is lost.")


StateModel = Literal[tuple(MODELS)]  # the registered names, in order
"""A registered motion model's name (:data:`sse_cosim.estimation.motion.MODELS`)."""

RegionKindName = Literal[tuple(KINDS)]  # the registered names, in order
"""A registered region representation's name (:data:`sse_cosim.regions.KINDS`)."""


class Estimator(StrictModel):
    state_model: StateModel = Field(
        "position", description="Pedestrian state: 2-D position, or 4-D position and velocity."
    )
    max_pedestrian_speed_mps: PositiveFloat = Field(
        2.5, description="Speed bound (m/s): the process noise |dx|, |dy| <= bound * step length."
    )
    position_jitter_m: NonNegativeFloat | None = Field(
        None,
        description="How far the simulated position may stray from a path that keeps the motion "
        "model's bounds (m); covers SUMO's pedestrian jumps at lane transitions. Left out: the "
        "value measured for the network, step length and bounds (a lone SUMO walker at the "
        "speed bound through every passage of every walking area of the scene, ramped within "
        "the acceleration bound for 'bounded-acceleration', cached with the network; "
        "`sse-cosim network` reports it). A value below the measured one is refused unless "
        "breaks_assumptions lists 'pedestrian_speed'. Every step checks that each pedestrian's "
        "true motion keeps it; a run that breaks it stops (exit status 5) naming the jitter its "
        "walk needs, unless breaks_assumptions lists 'pedestrian_speed'.",
    )
    junction_ground_margin_m: NonNegativeFloat = Field(
        0.0,
        description="How far beyond each junction's walking areas, crossings and measured "
        "ground patch a pedestrian's centre may be (m): the walkable ground the estimator "
        "assumes grows by it there. SUMO's lone walkers measure where a walker leaves the "
        "drawn ground; walkers that meet on a walking area push each other farther (a crowd "
        "sets it, as it sets a larger position_jitter_m). Every step checks that each "
        "pedestrian's true centre is on the walkable ground; a run in which one is off it "
        "stops (exit status 5) naming how far off, unless breaks_assumptions lists "
        "'walkable_ground'.",
    )
    max_velocity_change_mps: PositiveFloat = Field(
        5.0,
        description="Bound on a velocity component's change per step (m/s); constant velocity.",
    )
    max_pedestrian_accel_mps2: PositiveFloat = Field(
        3.2,
        description="Acceleration bound (m/s²) of the 'bounded-acceleration' model: no "
        "pedestrian's path speeds up, slows down or turns faster (Fugger et al., TRR 1705, "
        "2000: 0.14 ± 0.09 g from standstill at crosswalks; 3.2 m/s² is above their mean plus "
        "two standard deviations; docs/method.md). With that model the world ramps every SUMO "
        "walker's speed within it and checks it every step.",
    )
    gain_method: str = Field(
        "enclose", description="Correction: 'enclose' (the exact 2-D intersection enclosed in a "
        "zonotope; the tightest) or a Proposition 1 gain (sets.gains)."
    )
    fusion_method: str = Field(
        "enclose", description="Fusion: 'enclose' (the exact 2-D intersection enclosed in a "
        "zonotope; the tightest), 'strips' or Proposition 2 weights (sets.fusion)."
    )
    reduction_method: str = Field("girard", description="Order reduction method (sets.reduction).")
    max_generators: int = Field(8, ge=2, le=64, description="Generators kept after reduction.")
    filter: Literal["zonotope", "kalman"] = Field(
        "zonotope",
        description="Pedestrian regions the controller uses: the zonotopes refined with negative "
        "information, or a Kalman filter's 3-sigma ellipses (baseline, not guaranteed).",
    )
    regions: RegionKindName = Field(
        "polygon",
        description="How the regions (where a pedestrian may be, what is seen) are kept: "
        "'polygon', exact polygons whose dilations are mitred (the reference), or 'raster', "
        "cells of 0.1 m that hold every point the polygon would (docs/method.md, Regions).",
    )
    association: Literal["labelled", "anonymous"] = Field(
        "labelled",
        description="How detections find their tracks: 'labelled' by the simulation's person id "
        "(the default; every published result), 'anonymous' without any id, as a real "
        "perception stack reports them: each node starts, keeps and ends tracks by "
        "set-membership association, and each automated vehicle fuses only tracks that surely "
        "hold the same pedestrians (docs/method.md). No faults beyond the estimator's bounds, "
        "no Kalman filter.",
    )

    @field_validator("state_model", mode="before")
    @classmethod
    def _known_state_model(cls, value: Any) -> Any:
        if isinstance(value, str) and value not in MODELS:
            raise ValueError(f"unknown state model {value!r}; use one of {', '.join(MODELS)}")
        return value

    @field_validator("gain_method")
    @classmethod
    def _known_gain(cls, value: str) -> str:
        return _one_of(value, available_gain_methods())

    @field_validator("fusion_method")
    @classmethod
    def _known_fusion(cls, value: str) -> str:
        return _one_of(value, available_fusion_methods())

    @field_validator("reduction_method")
    @classmethod
    def _known_reduction(cls, value: str) -> str:
        return _one_of(value, sorted(REDUCTION_METHODS))


class Controller(StrictModel):
    policy: Literal["safe", "paper"] = Field(
        "safe",
        description="'safe': the fastest level from which the bus can still stop before, stand "
        "still before, or pass every conflict zone before any pedestrian can reach it (proof in "
        "docs/controller.md); 'paper': the rules of the paper's Section IV.",
    )
    cautious_factor: float = Field(0.7, gt=0, le=1, description="Cautious speed / nominal.")
    slow_factor: float = Field(0.5, gt=0, le=1, description="Slow speed / nominal.")
    very_slow_factor: float = Field(0.2, gt=0, le=1, description="Very slow speed / nominal.")
    crossing_horizon_m: PositiveFloat = Field(
        60.0,
        description="The crossing counts as 'ahead' within this distance of the bus front (m).",
    )
    interest_radius_m: PositiveFloat = Field(
        15.0,
        description="Radius around every crossing on the bus's route (and any other conflict "
        "zone) within which hidden walkable ground is tracked (m); beyond it every walkable "
        "place counts as possibly occupied (the safe policy's source farthest out). The paper "
        "policy's reach radius (pedestrian speed bound x time for the bus to clear the "
        "crossing) is capped by it.",
    )
    occlusion_threshold_m2: NonNegativeFloat = Field(
        0.5, description="Unresolved occluded area of interest above which the bus slows (m^2)."
    )
    path_margin_m: NonNegativeFloat = Field(
        1.5, description="Lateral margin around the bus's swept path for 'near the path' (m)."
    )
    reaction_time_s: NonNegativeFloat = Field(
        0.3, description="Delay before a stop acts, added to stopping distances and times (s)."
    )
    stopping_margin_m: NonNegativeFloat = Field(
        2.0, description="Distance kept, when stopping, before a conflict zone (safe policy) or "
        "a pedestrian set (paper policy) (m)."
    )
    inconsistent_level: Literal["cautious", "slow", "very slow"] = Field(
        "slow",
        description="Least severe level while the bus's picture is inconsistent (a source "
        "left out or an unresolved conflict; docs/faults.md).",
    )

    @model_validator(mode="after")
    def _ordered_levels(self) -> Controller:
        if not self.very_slow_factor <= self.slow_factor <= self.cautious_factor:
            raise ValueError(
                "speed factors must satisfy very_slow_factor <= slow_factor <= cautious_factor"
            )
        return self


class FaultWindow(StrictModel):
    """When a fault is active: from ``start_s`` until ``end_s`` (or the end of the run)."""

    start_s: NonNegativeFloat = Field(0.0, description="Time the fault starts (s).")
    end_s: PositiveFloat | None = Field(
        None, description="Time the fault ends (s); unset: it lasts to the end of the run."
    )

    @model_validator(mode="after")
    def _ordered_window(self) -> FaultWindow:
        if self.end_s is not None and self.end_s <= self.start_s:
            raise ValueError("end_s: must be later than start_s; move it, or remove it to last "
                             "to the end of the run")
        return self

    def _only_for(self, kind: str, fields: dict[str, str]) -> None:
        """Reject a field set explicitly for a kind other than ``kind`` (field -> its kind)."""
        for name, owner in fields.items():
            if owner != kind and name in self.model_fields_set:
                raise ValueError(f"{name}: only used with kind = {owner!r}; remove it")


class SensorFault(FaultWindow):
    sensor: str = Field(description="The faulty sensor (a name under [sensors]).")
    kind: Literal["bias", "stuck", "dropout", "phantom"] = Field(
        description="bias: offset measurements; stuck: the measurement freezes; dropout: frames "
        "are lost; phantom: a pedestrian that is not there is reported."
    )
    bias_m: tuple[float, float] = Field(
        (0.0, 0.0), description="bias: offset added along the measurement's two axes (m): a "
        "camera's forward and lateral axes, a range sensor's measured bearing and across it; "
        "beyond the noise bound it contradicts the other sources."
    )
    within_bound: bool = Field(
        False, description="bias: clip the biased error to the strips' half-widths (a camera's "
        "noise bound), so the strips still hold the truth (a fault the estimator's bounds "
        "cover)."
    )
    dropout_probability: float = Field(
        0.5, gt=0, le=1, description="dropout: probability that a step's frame is lost (seeded)."
    )
    phantom_id: str = Field(
        "phantom", min_length=1, description="phantom: the person id it is reported under (the "
        "real pedestrian's id, 'pedestrian', makes it a wrong association)."
    )
    phantom_xy_m: tuple[float, float] | None = Field(
        None, description="phantom: its position at start_s (m, network coordinates)."
    )
    phantom_velocity_mps: tuple[float, float] = Field(
        (0.0, 0.0), description="phantom: its velocity (m/s, network x and y)."
    )

    @model_validator(mode="after")
    def _kind_fields(self) -> SensorFault:
        self._only_for(self.kind, {"bias_m": "bias", "within_bound": "bias",
                                   "dropout_probability": "dropout", "phantom_id": "phantom",
                                   "phantom_xy_m": "phantom", "phantom_velocity_mps": "phantom"})
        if self.kind == "bias" and not any(self.bias_m):
            raise ValueError("bias_m: a bias fault needs a non-zero offset, e.g. [3.0, 0.0]")
        if self.kind == "phantom" and self.phantom_xy_m is None:
            raise ValueError("phantom_xy_m: a phantom needs a position, e.g. [200.0, 0.0]")
        return self

    @property
    def holds_bounds(self) -> bool:
        """Whether every strip it leaves still holds the truth (A2): a dropout loses whole
        frames, a within-bound bias keeps its error inside the noise bound."""
        return self.kind == "dropout" or (self.kind == "bias" and self.within_bound)


class NodeFault(FaultWindow):
    node: str = Field(description="The misbehaving node (a connected vehicle, a unit or an "
                      "automated vehicle that sends to another).")
    kind: Literal["shift", "shrink"] = Field(
        description="shift: the estimates it sends are moved; shrink: they are scaled down "
        "about their centres (a spoofed, over-confident sender)."
    )
    shift_m: tuple[float, float] = Field(
        (0.0, 0.0), description="shift: offset added to every estimate it sends (m, network "
        "x and y)."
    )
    scale: float = Field(
        0.2, gt=0, lt=1, description="shrink: factor applied to the generators of every "
        "estimate it sends."
    )

    @model_validator(mode="after")
    def _kind_fields(self) -> NodeFault:
        self._only_for(self.kind, {"shift_m": "shift", "scale": "shrink"})
        if self.kind == "shift" and not any(self.shift_m):
            raise ValueError("shift_m: a shift fault needs a non-zero offset, e.g. [4.0, 0.0]")
        return self


class LinkFault(FaultWindow):
    node: str = Field(description="Sender whose V2X links to the automated vehicles fail (a "
                      "connected vehicle, a unit or an automated vehicle that sends to another).")
    kind: Literal["loss", "latency"] = Field(
        description="loss: every message sent in the window is lost (a burst); latency: they "
        "arrive later."
    )
    extra_latency_steps: int = Field(
        5, ge=1, le=100, description="latency: steps added to the link's latency."
    )

    @model_validator(mode="after")
    def _kind_fields(self) -> LinkFault:
        self._only_for(self.kind, {"extra_latency_steps": "latency"})
        return self


class Faults(StrictModel):
    sensor: dict[str, SensorFault] = Field(
        default_factory=dict, description="Sensor faults by fault name."
    )
    node: dict[str, NodeFault] = Field(
        default_factory=dict, description="Connected-node faults by fault name."
    )
    link: dict[str, LinkFault] = Field(
        default_factory=dict, description="V2X link faults by fault name."
    )


ACTOR_TABLES = ("automated", "vehicles", "parked", "pedestrians")
"""The scenario's tables of actors that SUMO moves or parks (road-side units are not in SUMO)."""


class Scenario(StrictModel):
    """One scenario: the scene, its sensors, the estimator and the controller."""

    name: str = Field(min_length=1, description="Short name used in reports (e.g. 'S1').")
    description: str = Field("", description="One sentence for reports.")
    simulation: Simulation = Field(default_factory=Simulation)
    network: Network = Field(default_factory=Network)
    automated: dict[str, AutomatedVehicle] = Field(
        default_factory=dict, description="Automated vehicles by id (their SUMO and node id): "
        "each estimates, fuses and controls its speed; at least one."
    )
    parked: dict[str, ParkedVehicle] = Field(
        default_factory=dict, description="Parked vehicles by id."
    )
    vehicles: dict[str, Vehicle] = Field(
        default_factory=dict, description="Other moving vehicles by id, connected or not."
    )
    pedestrians: dict[str, Pedestrian] = Field(
        default_factory=dict, description="Pedestrians by id, each walking its own plan."
    )
    rsus: dict[str, RoadSideUnit] = Field(
        default_factory=dict, description="Road-side units by id."
    )
    sensors: dict[str, Sensor] = Field(default_factory=dict, description="Sensors by name.")
    v2x: V2X = Field(default_factory=V2X)
    estimator: Estimator = Field(default_factory=Estimator)
    controller: Controller = Field(default_factory=Controller)
    faults: Faults = Field(default_factory=Faults)
    breaks_assumptions: list[Assumption] = Field(
        default_factory=list,
        description="Assumptions of the estimator this study breaks on purpose (anything else "
        "that would break one is an error): 'pedestrian_speed': a pedestrian walks faster than "
        "estimator.max_pedestrian_speed_mps, or (with the 'bounded-acceleration' model) speeds up, "
        "slows down or turns faster than estimator.max_pedestrian_accel_mps2, or SUMO moves it "
        "farther off such a path than estimator.position_jitter_m (the run counts these breaks "
        "and goes on); "
        "'walkable_ground': a pedestrian's centre leaves the walkable ground (sidewalks, "
        "walking areas and crossings, each junction's grown by the margin SUMO's lone walkers "
        "were measured to need there; the run counts these steps and goes on); "
        "'pedestrian_lights': a walker steps onto a signalised crossing while its light "
        "shows red before the network's signal program could change it, a light runs another "
        "program than the network's, or a walker on a crossing lies outside its area (the run "
        "counts these and goes on; the controller's arrivals rely on it); "
        "'sensor_bounds': sensors whose measurements leave "
        "their noise bounds or report what is not there (bias beyond the bound, stuck, phantom); "
        "'shared_estimates': connected nodes send estimates that do not hold their bounds "
        "(node shift and shrink faults); "
        "'reaction_time': an automated vehicle acts on its commands later "
        "(automated.<id>.actuation_delay_s) than controller.reaction_time_s allows for.",
    )

    @model_validator(mode="after")
    def _actors_and_nodes(self) -> Scenario:
        if not present(self.automated):
            raise ValueError("automated: no automated vehicle in the scene; add one, e.g. "
                             "[automated.bus]")
        self._unique_ids()
        self._sensors_on_existing_nodes()
        self._faults_on_existing_targets()
        self._broken_assumptions_declared()
        self._anonymous_without_ids()
        return self

    def _anonymous_without_ids(self) -> None:
        """Faults beyond the estimator's bounds (caught by the vote and probation) and the Kalman
        baseline tell pedestrians apart by their id, which anonymous detections do not carry;
        faults within the bounds need no screening."""
        if self.estimator.association != "anonymous":
            return
        if self.estimator.filter == "kalman":
            raise ValueError("estimator.filter: the Kalman baseline associates detections by "
                             "person id, which estimator.association = 'anonymous' hides; use "
                             "filter = 'zonotope' or association = 'labelled'")
        beyond = [f"faults.sensor.{name}" for name, fault in self.faults.sensor.items()
                  if not fault.holds_bounds] + [f"faults.node.{name}" for name in self.faults.node]
        for name in beyond:
            raise ValueError(f"{name}: a fault beyond the estimator's bounds is screened per "
                             "person id, which estimator.association = 'anonymous' hides; "
                             "remove it (faults within the bounds, a dropout, a within-bound "
                             "bias or a link fault, are kept) or use association = 'labelled'")

    def _unique_ids(self) -> None:
        """An id names one actor or unit: it is its SUMO id and its node id."""
        seen: dict[str, str] = {}
        for table in (*ACTOR_TABLES, "rsus"):
            for key in getattr(self, table):
                if key in seen:
                    raise ValueError(f"{table}.{key}: the id {key!r} is taken by "
                                     f"{seen[key]}.{key}; give each actor and unit its own id")
                seen[key] = table

    def _sensors_on_existing_nodes(self) -> None:
        nodes = self.node_ids()
        for name, sensor in self.sensors.items():
            if sensor.node is None:  # carried by every vehicle of a type (carrier_type)
                continue
            vehicle = self.vehicles.get(sensor.node)
            if vehicle is not None and vehicle.present and not vehicle.connected:
                raise ValueError(f"sensors.{name}.node: vehicle {sensor.node!r} is not "
                                 "connected, so it cannot share what it sees; set "
                                 f"vehicles.{sensor.node}.connected = true")
            if sensor.node not in nodes:
                raise ValueError(
                    f"sensors.{name}.node: no node {sensor.node!r}; "
                    f"use one of {', '.join(nodes)}"
                )

    def _broken_assumptions_declared(self) -> None:
        """What breaks an assumption of the estimator is listed in ``breaks_assumptions``.

        The sets are guaranteed to hold the pedestrian only under those assumptions, so a study
        that breaks one says so; dropouts and link faults break nothing (the estimator handles
        missing frames and late messages).
        """
        declared = set(self.breaks_assumptions)
        bound = self.estimator.max_pedestrian_speed_mps
        for pid, pedestrian in present(self.pedestrians).items():
            speed = pedestrian.walking_speed_mps
            if speed <= bound:
                continue
            _require(declared, "pedestrian_speed", f"pedestrians.{pid}.walking_speed_mps",
                     f"{speed:g} m/s is above estimator.max_pedestrian_speed_mps ({bound:g} m/s), "
                     f"the bound the estimator relies on; walk at most {bound:g} m/s or raise "
                     "the bound")
        reaction = self.controller.reaction_time_s
        for vid, vehicle in present(self.automated).items():
            delay = vehicle.actuation_delay_s
            if delay > reaction + 1e-9:
                _require(declared, "reaction_time", f"automated.{vid}.actuation_delay_s",
                         f"{delay:g} s is longer than controller.reaction_time_s ({reaction:g} "
                         "s), the delay the controller's stops allow for; set the reaction "
                         "time to at least the delay")
        for name, fault in self.faults.sensor.items():
            if not fault.holds_bounds:
                _require(declared, "sensor_bounds", f"faults.sensor.{name}.kind",
                         _SENSOR_FAULT_BREAKS[fault.kind])
        for name, node_fault in self.faults.node.items():
            _require(declared, "shared_estimates", f"faults.node.{name}.kind",
                     f"a {node_fault.kind} fault sends estimates that do not hold their bounds")

    def _faults_on_existing_targets(self) -> None:
        """Every fault names a sensor of the scenario, or a node that sends to an automated
        vehicle."""
        for name, fault in self.faults.sensor.items():
            if fault.sensor not in self.sensors:
                raise ValueError(f"faults.sensor.{name}.sensor: no sensor {fault.sensor!r}; "
                                 f"use one of {', '.join(self.sensors) or '(none)'}")
            if self.sensors[fault.sensor].carrier_type is not None:
                raise ValueError(f"faults.sensor.{name}.sensor: {fault.sensor!r} is carried by "
                                 "every vehicle of a type, faults act on one sensor of one "
                                 "node; give the fault a sensor with a node")
        senders = self.sender_ids()
        use = f"use one of {', '.join(senders)}" if senders else \
            "this scenario has none: add a connected vehicle or a road-side unit"
        for table, faults in (("node", self.faults.node), ("link", self.faults.link)):
            for name, fault in faults.items():
                if fault.node not in senders:
                    raise ValueError(f"faults.{table}.{name}.node: {fault.node!r} is no node "
                                     f"that sends to an automated vehicle; {use}")

    def node_ids(self) -> list[str]:
        """Nodes that can carry sensors: the automated vehicles, the connected vehicles and
        the units (present ones, in that order; the vehicles that carry sensors by type,
        ``carrier_type``, are nodes only at run time)."""
        connected = [vid for vid, v in present(self.vehicles).items() if v.connected]
        return [*present(self.automated), *connected, *self.rsus]

    def sender_ids(self) -> list[str]:
        """Nodes that send to some automated vehicle: every node but an automated vehicle
        that is the only one (it has nobody to send to)."""
        receivers = present(self.automated)
        return [n for n in self.node_ids() if len(receivers) > 1 or n not in receivers]

    def pedestrian_radius_m(self) -> float:
        """The largest body radius among the present pedestrians (m), the default radius
        without any: the body the controller keeps clear of."""
        radii = [p.radius_m for p in present(self.pedestrians).values()]
        return max(radii, default=Pedestrian.model_fields["radius_m"].default)

    def person_radius_m(self, person_id: str) -> float:
        """The body radius of person ``person_id`` (m): its own if the scenario places it, else
        (a person from a route file) :meth:`pedestrian_radius_m`, the radius the controller
        keeps clear of."""
        pedestrian = self.pedestrians.get(person_id)
        return self.pedestrian_radius_m() if pedestrian is None else pedestrian.radius_m

    def actor_ids(self) -> list[str]:
        """The ids of every actor the scenario places in SUMO (present or not: a route file
        may not reuse them)."""
        return [key for table in ACTOR_TABLES for key in getattr(self, table)]


Actor = TypeVar("Actor", AutomatedVehicle, ParkedVehicle, Vehicle, Pedestrian)


def present(actors: dict[str, Actor]) -> dict[str, Actor]:
    """The actors of a table that are in the scene (``present = true``), by id, in order."""
    return {key: actor for key, actor in actors.items() if actor.present}


_SENSOR_FAULT_BREAKS = {
    "bias": "a bias beyond the noise bound (within_bound = false) puts the measurements outside "
    "the bound the estimator relies on",
    "stuck": "a stuck sensor's measurements leave the noise bound the estimator relies on",
    "phantom": "a phantom is reported where no pedestrian is, which the estimator does not expect",
}


def _require(declared: set[str], assumption: str, field: str, problem: str) -> None:
    """Reject ``field`` (a ValueError naming it) unless ``assumption`` is declared broken."""
    if assumption not in declared:
        raise ValueError(f"{field}: {problem}; if the study breaks it on purpose, add "
                         f'"{assumption}" to breaks_assumptions')


def _one_of(value: str, allowed: list[str]) -> str:
    if value not in allowed:
        raise ValueError(f"unknown method {value!r}; use one of {', '.join(allowed)}")
    return value

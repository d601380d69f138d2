"""The motion model's seam: the :class:`MotionModel` protocol every layer uses, and the linear
machinery (:class:`LinearModel`) the registered models share.

Paper eq. ``sysmodel``: x_{k+1} = F x_k + n_k, n_k in Z_Q. Sensors measure the position only:
``position_matrix`` C (2, n) maps a state to it. A model also says how far a path point can
move (:meth:`MotionModel.reach_m`), which every polygon layer grows its regions by (the refined
regions, the unobserved area, the bus's screen, the anonymous association), and how soon a
pedestrian can reach a place (:meth:`MotionModel.earliest_arrival_s`), the controller's
earliest arrivals. Both take an optional state set: a model whose reach depends on the
velocity may use it; the speed-bounded models here ignore it (the worst case over all
velocities within v_max).

Jitter. SUMO's pedestrian models jump by up to 0.7 m in one step where a pedestrian moves
from one lane to the next (walking area to crossing), faster than any speed bound that is
useful. We therefore model the simulated position as p = s + e: a path s that obeys the
model's bounds plus a jitter ||e|| <= eps. Every node estimates s, so its strips widen by
eps * ||h|| (|h.e| <= eps ||h||), and the position set it reports for p is C Z (+) box(eps),
which holds the disc of radius eps. Any admissible path s lies in every node's set, hence
in the fused one. ``tests/world`` checks that SUMO's trajectories admit such a path.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Protocol

import numpy as np

from sse_cosim.memo import IdentityMemo
from sse_cosim.sets import Strips, Zonotope, intersect_block_strips, intersect_strips, portable

POSITION_MEMO = 1024
"""Path and position sets a MotionModel keeps (each, about 1 kB): a crowd's step asks for those
of some hundred estimates (every source of every pedestrian), each several times."""
VELOCITY = 2  # a (position, velocity) state's velocity block starts at this entry


def unit_fan(count: int) -> np.ndarray:
    """``count`` unit directions evenly around the circle from east, shape (count, 2)
    (libm's sine and cosine: the same on every machine)."""
    angles = [2.0 * math.pi * i / count for i in range(count)]
    return np.array([[portable.cos(a), portable.sin(a)] for a in angles])


class MotionModel(Protocol):
    """What the estimator, the polygon layers and the controller ask of a pedestrian's motion
    model (a registered one: :data:`sse_cosim.estimation.motion.MODELS`)."""

    @property
    def transition(self) -> np.ndarray:
        """F (n, n)."""

    @property
    def process_noise(self) -> Zonotope:
        """Z_Q (dimension n)."""

    @property
    def position_matrix(self) -> np.ndarray:
        """C (2, n) = [I 0]: the state's first two entries are its position."""

    @property
    def state_bounds(self) -> Strips | None:
        """Strips about the state (m, n) that always hold (pseudo-measurements), if any."""

    def bound_state(self, estimate: Zonotope) -> Zonotope:
        """``estimate`` cut by :attr:`state_bounds` without widening its position set
        (``estimate`` itself without bounds)."""

    @property
    def max_speed(self) -> float:
        """v_max (m/s): no pedestrian walks faster."""

    @property
    def jitter(self) -> float:
        """eps (m): how far the simulated position strays from its path."""

    @property
    def step_length(self) -> float:
        """dt (s): one step of :meth:`predict`."""

    @property
    def dim(self) -> int:
        """n: the state's dimension."""

    @property
    def jitter_box(self) -> Zonotope:
        """box(jitter) (2-D)."""

    def predict(self, estimate: Zonotope, steps: int = 1) -> Zonotope:
        """The state set ``steps`` steps later (Definition 1)."""

    def path_set(self, estimate: Zonotope) -> Zonotope:
        """C Z: the path's 2-D position set."""

    def position(self, estimate: Zonotope) -> Zonotope:
        """C Z (+) box(jitter): the simulated 2-D position set."""

    def path_strips(self, measured: Strips) -> Strips:
        """Position strips (m, 2) widened into strips about the path."""

    def state_strips(self, path: Strips) -> Strips:
        """Path strips (m, 2) as strips about the state (m, n)."""

    def initial_set(self, strips: Strips, gain_method: str) -> Zonotope:
        """A first state set from path strips (m, 2)."""

    @property
    def acceleration_bound_mps2(self) -> float | None:
        """a_max (m/s²) if the model bounds the path's acceleration (the world then ramps its
        walkers' speeds and checks the bound), else None."""

    @property
    def uses_state(self) -> bool:
        """Whether :meth:`reach_m` and :meth:`earliest_arrival_s` use a state set (else a
        caller need not build one, nor a separation)."""

    @property
    def velocity_windows(self) -> tuple[int, ...]:
        """How many steps ago a node's path strips also bound the current state
        (:meth:`velocity_strips`); empty: only the current strips are used."""

    def velocity_strips(self, path: Strips, steps_ago: int) -> Strips:
        """Path strips (m, 2) measured ``steps_ago`` steps ago as strips about the current
        state (m, n)."""

    def reach_m(self, steps: int = 1, state: Zonotope | None = None) -> float:
        """How far (m) a path point, with its state in ``state`` (None: unknown), can move in
        ``steps`` steps: every polygon layer grows a path region by this disc."""

    def reach_during_m(self, distance_m: float, speed_mps: float,
                       state: Zonotope | None = None) -> float:
        """How far (m) a path point can move while something at ``speed_mps`` (> 0) covers
        ``distance_m``."""

    def earliest_arrival_s(self, distance_m: np.ndarray, state: Zonotope | None = None,
                           separation: Separation | None = None,
                           of_path: bool = False) -> np.ndarray:
        """The earliest time (s) a pedestrian whose position is ``distance_m`` (any shape)
        from each place can be in it; ``state``: its state set, if known; ``separation``:
        how far its position must move along each direction of a fan to be in each place;
        ``of_path``: the distances and the separation are measured from where its path s
        may be (a path region), not its simulated position p."""

    def path_gap_m(self, distance_m: np.ndarray, of_path: bool = False) -> np.ndarray:
        """How far the path must move (m, same shape, >= 0) to put the simulated position
        into a place ``distance_m`` away: the distance less the jitter once at the place
        (a position there is within eps of its path) and, for a distance measured from a
        position (``of_path`` false), once more at the start."""


@dataclass(frozen=True)
class Separation:
    """How far a pedestrian's position must move along each of K unit ``directions`` (K, 2) to
    be in each of z places: ``gaps_m`` (z, K), the least n.q over the place minus the largest
    n.p over the pedestrian's region (negative where the two overlap along n)."""

    directions: np.ndarray
    gaps_m: np.ndarray


@dataclass(frozen=True)
class LinearModel:
    """A linear model with a speed bound: F (n, n), process-noise zonotope Q (dimension n),
    position matrix C (2, n), and its path moves at most ``max_speed`` in any direction.

    Its reach ignores the state set (a disc of v_max dt per step, whatever the velocity).
    """

    transition: np.ndarray
    process_noise: Zonotope
    position_matrix: np.ndarray
    state_bounds: Strips | None
    max_speed: float
    step_length: float
    jitter: float = 0.0
    velocity_windows: tuple[int, ...] = ()
    # the newest POSITION_MEMO path and position sets, by their estimates' identities
    _paths: IdentityMemo[Zonotope] = field(
        default_factory=lambda: IdentityMemo(POSITION_MEMO), init=False, repr=False,
        compare=False)
    _positions: IdentityMemo[Zonotope] = field(
        default_factory=lambda: IdentityMemo(POSITION_MEMO), init=False, repr=False,
        compare=False)

    def __post_init__(self) -> None:
        if not (np.isfinite(self.jitter) and self.jitter >= 0):
            raise ValueError(f"jitter must be finite and >= 0; got {self.jitter}")
        if not (np.isfinite(self.max_speed) and self.max_speed > 0):
            raise ValueError(f"max speed must be finite and > 0; got {self.max_speed}")
        if not (np.isfinite(self.step_length) and self.step_length > 0):
            raise ValueError(f"step length must be finite and > 0; got {self.step_length}")
        if not np.array_equal(self.position_matrix, np.eye(2, self.dim)):
            raise ValueError("the position matrix must pick the state's first two entries")

    @property
    def dim(self) -> int:
        return int(self.transition.shape[0])

    @property
    def acceleration_bound_mps2(self) -> float | None:
        """None: a linear model alone bounds the speed, not the acceleration."""
        return None

    @property
    def uses_state(self) -> bool:
        """False: its reach and arrivals are the speed bound's, whatever the state."""
        return False

    def bound_state(self, estimate: Zonotope) -> Zonotope:
        """``estimate`` cut by :attr:`state_bounds`, strips on the velocity (state entries 2
        and 3), by Prop. 1 with a gain that is zero on the position
        (:func:`~sse_cosim.sets.intersect_block_strips`): the position set stays as it is.
        A volume-minimising gain on the whole state widens the position to narrow the
        velocity, so an unseen track's position would grow about quadratically instead of by
        v_max dt a step. ``estimate`` itself for a model without bounds."""
        if self.state_bounds is None:
            return estimate
        return intersect_block_strips(estimate, self.state_bounds, VELOCITY)

    def velocity_strips(self, path: Strips, steps_ago: int) -> Strips:
        """Path strips |h.s_{k-N} - y| <= r of N = ``steps_ago`` steps ago (m, 2) as strips
        about the current state x_k = (s_k, v_k) of a model with F = [[I, dt I], [0, I]] and
        process noise <0, [0; G_v]> (the velocity changes by w_j in <0, G_v> per step):

            |h.s_k - N dt h.v_k - y| <= r + dt (N (N + 1) / 2) sum_i |h.g_i|,

        since s_{k-N} = s_k - N dt v_k + dt sum_j c_j w_j, each of the N changes w_j counted
        c_j <= N times, sum_j c_j = N (N + 1) / 2. Normals (h, -N dt h) (m, 4). With the strips
        of now, their difference bounds h.v_k: the velocity estimated over time (eq. 2 has no
        memory: each step's Proposition 1 keeps only what a zonotope of bounded order holds).
        """
        if self.dim != 4 or self.process_noise.generators[:2].any():
            raise ValueError("velocity strips need a (position, velocity) model whose noise "
                             "moves the velocity only")
        reach = self.step_length * steps_ago
        slack = self.step_length * 0.5 * steps_ago * (steps_ago + 1) * np.abs(
            portable.matmul(path.normals, self.process_noise.generators[2:])).sum(axis=1)
        normals = np.hstack([path.normals, -reach * path.normals])
        return Strips(normals, path.values, path.radii + slack)

    def reach_m(self, steps: int = 1, state: Zonotope | None = None) -> float:
        """v_max dt ``steps``: how far a path point can move in ``steps`` steps, whatever its
        state (``state`` is ignored)."""
        return self.max_speed * self.step_length * steps

    def reach_during_m(self, distance_m: float, speed_mps: float,
                       state: Zonotope | None = None) -> float:
        """v_max ``distance_m`` / ``speed_mps``: how far a path point can move while something
        at ``speed_mps`` covers ``distance_m`` (the paper policy's "near the crossing";
        ``state`` is ignored)."""
        return self.max_speed * distance_m / speed_mps

    def earliest_arrival_s(self, distance_m: np.ndarray, state: Zonotope | None = None,
                           separation: Separation | None = None,
                           of_path: bool = False) -> np.ndarray:
        """:meth:`path_gap_m` / v_max for each distance d (m): the earliest time a pedestrian
        whose path s (``of_path``), or whose position p = s + e, lies d from a zone can be in
        it (``state`` and ``separation`` are ignored).

        The path moves at most v_max per second and the position in the zone is within eps of
        its path, so from a path region the path covers at least d - eps; from a position,
        within eps of its path, at least d - 2 eps. The straight-line distance never exceeds
        the walk on walkable ground, so this is an under-estimate: sound (docs/controller.md,
        "Earliest arrival"; docs/method.md, the motion model).
        """
        return self.path_gap_m(distance_m, of_path) / self.max_speed

    def path_gap_m(self, distance_m: np.ndarray, of_path: bool = False) -> np.ndarray:
        """max(0, d - eps) from a path region (``of_path``), max(0, d - 2 eps) from a
        position (the protocol's :meth:`~MotionModel.path_gap_m`)."""
        return np.maximum(0.0, distance_m - (1.0 if of_path else 2.0) * self.jitter)

    def predict(self, estimate: Zonotope, steps: int = 1) -> Zonotope:
        """Predicted state set after ``steps`` steps: F Z (+) Q, repeated (Definition 1)."""
        for _ in range(steps):
            estimate = _linear_map(self.transition, estimate) + self.process_noise
        return estimate

    def path_set(self, estimate: Zonotope) -> Zonotope:
        """C Z: the set of the path's 2-D position (no jitter; see :meth:`position`), kept
        for the newest estimates as :meth:`position` is."""
        return self._paths.get(id(estimate), (estimate,),
                               lambda: _linear_map(self.position_matrix, estimate))

    def position(self, estimate: Zonotope) -> Zonotope:
        """The set of the simulated 2-D position: C Z (+) box(jitter).

        A step asks for the same estimate's position set several times (screen, fusion,
        records): the newest ones are kept, by the estimate's identity (zonotopes are
        read-only), so each is computed once and its cached volume is shared.
        """
        return self._positions.get(id(estimate), (estimate,),
                                   lambda: self._position(estimate))

    def _position(self, estimate: Zonotope) -> Zonotope:
        path = self.path_set(estimate)
        return path if self.jitter == 0.0 else path + self.jitter_box

    @cached_property
    def jitter_box(self) -> Zonotope:
        """box(jitter) = <0, jitter I> (2-D), built once."""
        return Zonotope(np.zeros(2), np.eye(2) * self.jitter)

    def path_strips(self, measured: Strips) -> Strips:
        """Position strips about p (m, 2) turned into strips about the path s: radii r_j widened
        by jitter * ||h_j||.

        No re-validation: ``measured`` is validated (finite, r > 0, h_j != 0) and the jitter is
        finite and >= 0, so the widened radii are > 0; only their finiteness is checked (a norm
        may overflow).
        """
        norms = np.sqrt((measured.normals * measured.normals).sum(axis=1))  # np.linalg.norm's
        widened = measured.radii + self.jitter * norms
        if not np.isfinite(widened).all():
            raise ValueError("strip normals too large: the widened radii overflow")
        return Strips.unchecked(measured.normals, measured.values, widened)

    def state_strips(self, path: Strips) -> Strips:
        """Path strips (m, 2) as strips about the state: normals H C (m, n).

        ``path.pullback(C)`` without its checks: C = [I 0] (checked with the model), so H C
        holds H's entries and zeros, exactly -- finite and with nonzero rows as H's.
        """
        return Strips.unchecked(portable.matmul(path.normals, self.position_matrix), path.values,
                                path.radii)

    def initial_set(self, strips: Strips, gain_method: str) -> Zonotope:
        """A first estimate from path strips (m, 2), at least two with independent normals.

        The first two independent strips intersect exactly in the parallelogram
        <H^-1 y, H^-1 diag(r)>; the others are intersected with it by Proposition 1.
        Velocity components (constant-velocity model) start as the box |v| <= v_max.
        """
        i, j = _independent_pair(strips.normals)
        position = _parallelogram(strips, i, j)
        if len(strips) > 2:
            rest = np.ones(len(strips), dtype=bool)
            rest[[i, j]] = False
            position = intersect_strips(position, strips.select(rest), gain_method)
        if self.dim == 2:
            return position
        return self._with_velocity_box(position)

    def _with_velocity_box(self, position: Zonotope) -> Zonotope:
        """The 4-D state set ``position`` (2-D) x box(v_max) (constant-velocity model):
        center (4,), generators (4, e + 2); finite from finite parts, so unchecked."""
        center = np.concatenate([position.center, np.zeros(2)])
        generators = np.block(
            [
                [position.generators, np.zeros((2, 2))],
                [np.zeros((2, position.n_generators)), np.eye(2) * self.max_speed],
            ]
        )
        return Zonotope.unchecked(center, generators)


def _parallelogram(strips: Strips, i: int, j: int) -> Zonotope:
    """The intersection of strips i and j (independent normals) of ``strips`` (m, 2):
    ⟨H^-1 y, H^-1 diag(r)⟩ with H (2, 2) their normals, y and r (2,) their values and radii.

    Only finiteness is checked (as the validated constructor would: H^-1 may overflow); the
    rest holds for validated strips.
    """
    pair = strips if len(strips) == 2 else strips.select(np.array([i, j]))
    inverse = portable.inverse_2x2(pair.normals)
    center, generators = portable.matmul(inverse, pair.values), inverse * pair.radii[np.newaxis, :]
    if not (np.isfinite(center).all() and np.isfinite(generators).all()):
        raise ValueError("zonotope center and generators must be finite")
    return Zonotope.unchecked(center, generators)


def _linear_map(matrix: np.ndarray, estimate: Zonotope) -> Zonotope:
    """M Z = ⟨Mc, MG⟩ (eq. linmap) for a model matrix M (m, n), as ``M @ Z`` computes it, without
    its per-call checks: the model's matrices are finite and shaped for its states."""
    return Zonotope.unchecked(portable.matmul(matrix, estimate.center),
                              portable.matmul(matrix, estimate.generators))


def _independent_pair(normals: np.ndarray, tol: float = 1e-6) -> tuple[int, int]:
    """Indices of the first two rows of ``normals`` (m, 2) that are not parallel:
    |det [h_i; h_j]| = |h_i0 h_j1 - h_i1 h_j0| > ``tol`` (the 2x2 closed form)."""
    rows = normals.tolist()
    for i, (a, b) in enumerate(rows):
        for j in range(i + 1, len(rows)):
            c, d = rows[j]
            if abs(a * d - b * c) > tol:
                return i, j
    raise ValueError("a track needs two position strips with independent normals")

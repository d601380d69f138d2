"""Does the simulated world keep the ``bounded-acceleration`` model's pedestrian assumption?
Pure geometry and a convex solver (Clarabel), no SUMO.

The model (:mod:`sse_cosim.estimation.motion.bounded_acceleration`) assumes that every
pedestrian's position is p_k = s_k + e_k: a path s whose mean velocities
v_k = (s_(k+1) - s_k) / dt keep the speed and acceleration bounds, plus a jitter. In the
path's points alone, for every k,

    (J) ||s_k - p_k|| <= eps,
    (V) ||s_(k+1) - s_k|| <= v dt                      (||v_k|| <= v),
    (A) ||s_(k+2) - 2 s_(k+1) + s_k|| <= a dt^2         (||v_(k+1) - v_k|| <= a dt),

all as discs (the estimator's boxes and octagon hold them: a walk that keeps the discs keeps
its model). The world keeps the assumption up to step k exactly while one path s_0..s_k
keeps (J), (V) and (A) for every index up to k at once -- a *witness* -- and this module
decides that.

Why not per axis. Splitting each disc into a box of half its radius times sqrt(2) per axis
makes the problem two independent ones in the (s_i, v_i) plane, but a box inscribed in the
speed disc allows only v / sqrt(2) along an axis: a walker at 2 m/s along the paper road
(the crowd's) breaks it with any jitter, and the jitter measurement's walkers at v = 2.5 m/s
along any axis do too. On a lone walker at 1.5 m/s over the paper road's zebra (WC to CW,
ramped) the boxes need 0.28 m where the discs need 0.19 m (the least jitter of each, the
boxes' by a linear program). So the check keeps the discs, and their coupling.

The witness. Each pedestrian keeps a witness of its walk so far, and each step extends it:

1. **Greedy** (most steps, a few float operations): the witness takes the walk's step,
   less :data:`PULL` times its offset from the walk (so it drifts back to the walk's centre
   after a jump), cut to the acceleration disc about its own last step and to the speed
   disc; else the step toward the new position, cut the same way. The first candidate that
   keeps (J), (V) and (A) -- checked in floating point on the stored points -- is taken.
2. **Window**: else the last :data:`WINDOW` points are solved again, as a second-order cone
   program (SOCP) over (J), (V), (A) with the two witness points before them fixed.
3. **Walk**: else the whole walk since the pedestrian's set started is solved.
4. Else the step is a break.

Soundness. Every witness point is accepted only after (J), (V) and (A) are checked on it in
floating point against the model's own radii -- the solver's answers too (the programs use
radii smaller by :data:`SHRINK_M`, so that a solution within the solver's tolerances keeps
the model's): the check reports no break only while a verified witness exists. The
comparisons are of squared norms of differences of stored coordinates in a local frame (the
walk's first position subtracted), so rounding moves them by a few units in the last place
of those coordinates: below 1e-12 m for walks within 1 km of their start. We state the
tolerance as :data:`TOLERANCE_M` = 1e-6 m, as :mod:`sse_cosim.world.assumptions` does: a
walk the check passes keeps the model with every bound widened by 1e-6 m.

Completeness. A break is reported only when the program over the whole walk since the
pedestrian's set started has no solution (Clarabel reports it infeasible or fails to
converge) with every radius shrunk by :data:`SHRINK_M`; the window and the greedy step only
spare that program. The program's own tolerances are about 1e-8 in its scaled units, so a
break means no path keeps the model with its bounds shrunk by SHRINK_M (1e-6 m), up to the
solver's tolerances. After a break the pedestrian's set starts afresh at its position
(velocity free), as in :mod:`sse_cosim.world.assumptions`.

Cost. A pedestrian walking within the bounds (a smooth walk, the witness on or near it)
costs the greedy step only. Where SUMO re-places a walker (a lane change on a walking area)
the greedy step fails for a step or a few; the window's program (about 120 cones) took 1.2
ms on that walk, the whole walk's (27 s) 17 ms. In the crowd scene (21 pedestrians, 33 s)
the check took 1.5 s of the world's 2.0 s with 603 windows and no whole walk solved (a
world-only run, timed around ``SumoWorld._check_motion``). The jitter a walk needs
(:func:`needed_jitter`) is one program: the least eps over all paths, exact up to the
solver's tolerance (rounded up to 1 mm and verified), no bisection.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sparse

from sse_cosim.world.assumptions import MotionBreak, WalkCheck

TOLERANCE_M = 1e-6
SHRINK_M = 1e-6  # the programs' radii are the model's less this (m)
WINDOW = 40  # witness points the window's program solves again
PULL = 0.1  # share of its offset from the walk the greedy witness takes back per step
_FIXED = 2  # witness points before a window that it continues: (V) and (A) reach back two


@dataclass(frozen=True)
class AccelerationBounds:
    """The bounded-acceleration model's pedestrian assumption: speed bound (m/s),
    acceleration bound (m/s²), jitter (m), step length (s)."""

    speed_mps: float
    accel_mps2: float
    jitter_m: float
    step_s: float

    @property
    def step_m(self) -> float:
        """(V)'s radius v dt (m): the longest path step."""
        return self.speed_mps * self.step_s

    @property
    def change_m(self) -> float:
        """(A)'s radius a dt² (m): the largest change of two consecutive path steps."""
        return self.accel_mps2 * self.step_s * self.step_s


@dataclass(frozen=True)
class _Program:
    """A walk's SOCP: ``positions`` (n, 2) the walk's positions whose path points are the
    variables, continuing the ``fixed`` path points (f, 2), f <= 2; ``jitter`` (n,) each
    point's (J) radius, NaN where it is the variable t the program minimises; ``step_m`` and
    ``change_m`` the radii of (V) and (A), None to leave that bound out."""

    positions: np.ndarray
    fixed: np.ndarray
    jitter: np.ndarray
    step_m: float | None
    change_m: float | None


def keeps(points: np.ndarray, positions: np.ndarray, bounds: AccelerationBounds) -> bool:
    """Whether the path ``points`` (m, 2), whose last n points go with ``positions`` (n, 2)
    (the first m - n are kept points before them), keeps (J) for those n points and (V) and
    (A) for every step and pair of steps that reaches one of them: squared norms against the
    model's squared radii."""
    n, m = len(positions), len(points)
    first = m - n
    gaps = points[first:] - positions
    steps = np.diff(points[max(first - 1, 0):], axis=0)
    changes = np.diff(points[max(first - 2, 0):], n=2, axis=0)
    return bool(_squares(gaps).max(initial=0.0) <= bounds.jitter_m ** 2
                and _squares(steps).max(initial=0.0) <= bounds.step_m ** 2
                and _squares(changes).max(initial=0.0) <= bounds.change_m ** 2)


def solve_path(positions: np.ndarray, fixed: np.ndarray,
               bounds: AccelerationBounds) -> np.ndarray | None:
    """A path (n, 2) for ``positions`` (n, 2) continuing the ``fixed`` points (f, 2), f <= 2,
    that keeps the model (verified by :func:`keeps`), or None if the program finds none."""
    if len(positions) == 0:
        return np.empty((0, 2))
    radius = max(bounds.jitter_m - SHRINK_M, 0.0)
    program = _Program(positions, fixed, np.full(len(positions), radius),
                       bounds.step_m - SHRINK_M, bounds.change_m - SHRINK_M)
    found = _solve(program)
    if found is None:
        return None
    path, _ = found
    return path if keeps(np.vstack([fixed, path]), positions, bounds) else None


def needed_jitter(positions: np.ndarray, bounds: AccelerationBounds) -> float:
    """The least jitter (m, rounded up to 1 mm) with which a path keeps the speed and
    acceleration bounds of ``bounds`` along the walk ``positions`` (k, 2): the program's
    least eps, its path verified at the rounded value. Raises RuntimeError if the solver
    fails (it does not on walks of metres in steps of centimetres)."""
    program = _Program(positions, np.empty((0, 2)), np.full(len(positions), np.nan),
                       bounds.step_m - SHRINK_M, bounds.change_m - SHRINK_M)
    found = _solve(program)
    if found is None:
        raise RuntimeError("the least-jitter program found no path: the solver failed")
    path, least = found
    jitter = math.ceil((least + SHRINK_M) * 1000.0 - 1e-9) / 1000.0
    at = AccelerationBounds(bounds.speed_mps, bounds.accel_mps2, jitter, bounds.step_s)
    if not keeps(path, positions, at):
        raise RuntimeError(f"the least-jitter path does not keep {jitter} m: the solver's "
                           "tolerance exceeded the margin")
    return jitter


def nearest_distance(positions: np.ndarray, bounds: AccelerationBounds) -> float:
    """How far (m) the last of ``positions`` (k, 2) lies from the nearest path point that a
    path keeping the model along the walk before it reaches (> eps: a break)."""
    jitter = np.full(len(positions), bounds.jitter_m - SHRINK_M)
    jitter[-1] = np.nan
    found = _solve(_Program(positions, np.empty((0, 2)), jitter, bounds.step_m - SHRINK_M,
                            bounds.change_m - SHRINK_M))
    return math.nan if found is None else found[1]


def broken_bounds(positions: np.ndarray, bounds: AccelerationBounds) -> str:
    """Which bound the walk ``positions`` (k, 2) breaks within the jitter, as words for "its
    walk breaks ...": 'the acceleration bound' (it keeps the speed bound alone), 'the speed
    bound' (it keeps the acceleration bound alone), 'the two bounds together (each alone
    holds)' or 'each bound alone'."""
    radius = np.full(len(positions), bounds.jitter_m - SHRINK_M)
    empty = np.empty((0, 2))
    speed_alone = _solve(_Program(positions, empty, radius, bounds.step_m - SHRINK_M, None))
    accel_alone = _solve(_Program(positions, empty, radius, None, bounds.change_m - SHRINK_M))
    if speed_alone is not None and accel_alone is not None:
        return "the two bounds together (each alone holds)"
    if speed_alone is not None:
        return "the acceleration bound"
    if accel_alone is not None:
        return "the speed bound"
    return "each bound alone"


def _squares(vectors: np.ndarray) -> np.ndarray:
    return (vectors * vectors).sum(axis=1)


def _solve(program: _Program) -> tuple[np.ndarray, float] | None:
    """Solve ``program``: its path (n, 2) and its t (the least value; 0.0 without one), or
    None unless Clarabel reports a solution. Coordinates are shifted to the first point for
    the solver and back."""
    import clarabel

    origin = program.fixed[0] if len(program.fixed) else program.positions[0]
    fixed, positions = program.fixed - origin, program.positions - origin
    n = len(positions)
    free_t = bool(np.isnan(program.jitter).any())
    columns = 2 * n + int(free_t)
    matrix, rhs, cones = _cones(fixed, positions, program, columns)
    cost = np.zeros(columns)
    if free_t:
        cost[-1] = 1.0
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    solver = clarabel.DefaultSolver(sparse.csc_matrix((columns, columns)), cost, matrix, rhs,
                                    [clarabel.SecondOrderConeT(3)] * cones, settings)
    solution = solver.solve()
    if solution.status not in (clarabel.SolverStatus.Solved,
                               clarabel.SolverStatus.AlmostSolved):
        return None
    x = np.asarray(solution.x)
    return x[:2 * n].reshape(n, 2) + origin, float(x[-1]) if free_t else 0.0


def _cones(fixed: np.ndarray, positions: np.ndarray, program: _Program,
           columns: int) -> tuple[sparse.csc_matrix, np.ndarray, int]:
    """The program's constraints A z + u = b, each u = (r, w) in the 3-D second-order cone
    ||w|| <= r: for a condition ||sum_i c_i x_i + d|| <= r over path points x (fixed or
    variable), w = -(sum c_i x_i + d), so A has c_i at the variable points' columns and
    b = -(sum over fixed points c_i x_i) - d; its radius row has b = r (or -1 at t's column
    where r is t). Returns A (3 R, columns), b (3 R,) and R."""
    f, n = len(fixed), len(positions)
    m = f + n
    families = [(np.arange(f, m)[:, None], np.array([1.0]), -positions, program.jitter)]
    if program.step_m is not None:
        start = max(f - 1, 0)
        index = np.arange(start, m - 1)[:, None] + np.arange(2)
        families.append((index, np.array([-1.0, 1.0]), np.zeros((len(index), 2)),
                         np.full(len(index), program.step_m)))
    if program.change_m is not None:
        start = max(f - 2, 0)
        index = np.arange(start, max(m - 2, start))[:, None] + np.arange(3)
        families.append((index, np.array([1.0, -2.0, 1.0]), np.zeros((len(index), 2)),
                         np.full(len(index), program.change_m)))
    rows, cols, data, rhs = [], [], [], []
    base = 0
    for index, coefs, offset, radii in families:
        count = len(index)
        cone = base + np.arange(count)
        coef = np.broadcast_to(coefs, index.shape)
        variable = index >= f
        # the radius rows: r, or t's column with -1
        rhs_cone = np.zeros((count, 3))
        rhs_cone[:, 0] = np.where(np.isnan(radii), 0.0, radii)
        free = np.flatnonzero(np.isnan(radii))
        rows.append(3 * cone[free])
        cols.append(np.full(len(free), columns - 1))
        data.append(np.full(len(free), -1.0))
        known = np.where(variable[..., None], 0.0, fixed[np.minimum(index, max(f - 1, 0))]
                         if f else 0.0)
        rhs_cone[:, 1:] = -(coef[..., None] * known).sum(axis=1) - offset
        at, slot = np.nonzero(variable)
        for axis in (0, 1):
            rows.append(3 * cone[at] + 1 + axis)
            cols.append(2 * (index[at, slot] - f) + axis)
            data.append(coef[at, slot])
        rhs.append(rhs_cone.ravel())
        base += count
    matrix = sparse.csc_matrix((np.concatenate(data), (np.concatenate(rows),
                                                       np.concatenate(cols))),
                               shape=(3 * base, columns))
    return matrix, np.concatenate(rhs), base


@dataclass
class _Walk:
    """One pedestrian's walk since its set last started: its first position (the local
    frame's origin), its positions and its witness path, both relative to it."""

    origin: np.ndarray
    positions: list[tuple[float, float]] = field(default_factory=list)
    path: list[tuple[float, float]] = field(default_factory=list)


class AccelerationCheck(WalkCheck):
    """Keeps a witness path of every pedestrian's walk (see the module docstring).

    One that broke starts afresh at its position (:class:`WalkCheck`). ``diagnose``: whether
    a break is given its needed jitter and the bounds it broke (a run that stops on it) or not
    (a study that counts breaks).
    """

    def __init__(self, bounds: AccelerationBounds, diagnose: bool = True) -> None:
        super().__init__()
        self.bounds = bounds
        self.diagnose = diagnose

    def _advance(self, pid: str, walk: _Walk, time: float, point: np.ndarray) -> MotionBreak | None:
        self._full[pid].append(point)
        local = (float(point[0] - walk.origin[0]), float(point[1] - walk.origin[1]))
        walk.positions.append(local)
        if self._greedy(walk) or self._solved(walk):
            return None
        found = self._break(pid, walk, time)
        self._start(pid, point, self._full[pid][:-1])
        return found

    def _start(self, pid: str, point: np.ndarray, full: list[np.ndarray]) -> None:
        self._walks[pid] = _Walk(origin=point, positions=[(0.0, 0.0)], path=[(0.0, 0.0)])
        self._full[pid] = [*full, point]

    def _greedy(self, walk: _Walk) -> bool:
        """Extend the witness by one of the greedy steps (module docstring) if one keeps the
        model; whether one did."""
        (px, py), (qx, qy) = walk.positions[-2], walk.positions[-1]
        sx, sy = walk.path[-1]
        before = None
        if len(walk.path) >= 2:
            before = (sx - walk.path[-2][0], sy - walk.path[-2][1])
        for tx, ty in ((qx - px - PULL * (sx - px), qy - py - PULL * (sy - py)),
                       (qx - sx, qy - sy)):
            if before is not None:
                tx, ty = _into_disc(tx, ty, before[0], before[1], self.bounds.change_m)
            tx, ty = _into_disc(tx, ty, 0.0, 0.0, self.bounds.step_m)
            nx, ny = sx + tx, sy + ty
            if self._keeps_step(walk, nx, ny, qx, qy):
                walk.path.append((nx, ny))
                return True
        return False

    def _keeps_step(self, walk: _Walk, nx: float, ny: float, qx: float, qy: float) -> bool:
        """(J), (V) and (A) for the new point (nx, ny) of the witness and position (qx, qy),
        on the stored values."""
        sx, sy = walk.path[-1]
        b = self.bounds
        if (nx - qx) ** 2 + (ny - qy) ** 2 > b.jitter_m ** 2:
            return False
        if (nx - sx) ** 2 + (ny - sy) ** 2 > b.step_m ** 2:
            return False
        if len(walk.path) < 2:
            return True
        rx, ry = walk.path[-2]
        return (nx - 2.0 * sx + rx) ** 2 + (ny - 2.0 * sy + ry) ** 2 <= b.change_m ** 2

    def _solved(self, walk: _Walk) -> bool:
        """Solve the window again, then the whole walk (module docstring); whether a witness
        was found (it replaces the old one's points)."""
        total = len(walk.positions)
        starts = [0] if total <= WINDOW else [total - WINDOW, 0]
        positions = np.array(walk.positions)
        path = np.array(walk.path)
        for start in starts:
            found = solve_path(positions[start:], path[max(start - _FIXED, 0):start],
                               self.bounds)
            if found is not None:
                walk.path[start:] = [(float(x), float(y)) for x, y in found]
                return True
        return False

    def _break(self, pid: str, walk: _Walk, time: float) -> MotionBreak:
        """The break at the walk's last position."""
        positions = np.array(walk.positions)
        moved = positions[-1] - positions[-2]
        change = None
        if len(positions) >= 3:
            second = positions[-1] - 2.0 * positions[-2] + positions[-3]
            change = float(np.sqrt((second * second).sum())) / self.bounds.step_s
        needed = broke = None
        if self.diagnose:
            needed = needed_jitter(np.array(self._full[pid]), self.bounds)
            broke = broken_bounds(positions, self.bounds)
        return MotionBreak(person=pid, time=time,
                           distance_m=nearest_distance(positions, self.bounds),
                           jitter_m=self.bounds.jitter_m,
                           step_m=float(np.sqrt((moved * moved).sum())), needed_jitter_m=needed,
                           velocity_change_mps=change, broke=broke)


def _into_disc(x: float, y: float, cx: float, cy: float, radius: float) -> tuple[float, float]:
    """(x, y) moved onto the disc of ``radius`` about (cx, cy) if it lies outside it."""
    dx, dy = x - cx, y - cy
    norm = math.hypot(dx, dy)
    if norm <= radius:
        return x, y
    scale = radius / norm
    return cx + dx * scale, cy + dy * scale

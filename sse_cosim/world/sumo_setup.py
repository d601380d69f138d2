"""What every SUMO session of the project shares: SUMO's options, its configuration file and how
a person's position is read.

A scenario's run (:class:`sse_cosim.world.sumo.SumoWorld`) and a probe of lone walkers
(:func:`sse_cosim.world.walk_probe.walk_alone`) both start SUMO through
:func:`write_config`, so a walker moves in a probe exactly as in a run: the striping pedestrian
model, no dawdling, stripes of :data:`~sse_cosim.world.demand.STRIPE_WIDTH_M` (where the plan
expects a walk to begin), the step length, nobody teleported,
collisions reported (junctions included). Both read a walking person's centre with
:func:`person_centre`, and both ramp their walkers' speeds with :class:`SpeedRamp` when the
estimator's motion model bounds the acceleration.
"""

from __future__ import annotations

import contextlib
import io
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

from sse_cosim.files import write_text_atomic
from sse_cosim.world.demand import STRIPE_WIDTH_M

with contextlib.redirect_stdout(io.StringIO()):
    # libsumo's import prints a note about the installed pyarrow's version; keep stdout clean.
    import libsumo

CONFIG_FILE_NAME = "sumo.sumocfg"
LOG_FILE_NAME = "sumo.log"
LIBSUMO_ERRORS: tuple[type[BaseException], ...] = (
    libsumo.TraCIException, libsumo.FatalTraCIError, RuntimeError)


def sumo_options(step_length_s: float, seed: int) -> dict[str, dict[str, str]]:
    """SUMO's options of every session, by configuration section (without the input files):
    time from 0 in steps of ``step_length_s``; nobody teleported; collisions warned about and
    kept, at junctions too; the striping pedestrian model without dawdling; SUMO's seed."""
    return {
        "time": {"begin": "0", "step-length": f"{step_length_s:.10g}"},
        "processing": {
            "time-to-teleport": "-1",
            "collision.action": "warn",
            "collision.check-junctions": "true",
            "pedestrian.model": "striping",
            "pedestrian.striping.dawdling": "0",
            "pedestrian.striping.stripe-width": f"{STRIPE_WIDTH_M:g}",
        },
        "report": {"no-step-log": "true", "duration-log.disable": "true",
                   "error-log": LOG_FILE_NAME},
        "random_number": {"seed": str(seed)},
    }


def write_config(folder: Path, net_path: Path, route_files: Sequence[Path], step_length_s: float,
                 seed: int, comment: str) -> Path:
    """Write ``folder/sumo.sumocfg`` for ``net_path`` and ``route_files`` with
    :func:`sumo_options`; SUMO's warnings go to ``folder/sumo.log``. Paths are written relative
    to ``folder`` (where SUMO resolves them: no machine path in a results folder)."""
    options = {
        "input": {"net-file": relative(net_path, folder),
                  "route-files": ",".join(relative(p, folder) for p in route_files)},
        **sumo_options(step_length_s, seed),
    }
    lines = ['<?xml version="1.0" encoding="UTF-8"?>', f"<!-- {comment} -->", "<configuration>"]
    for section, values in options.items():
        lines.append(f"    <{section}>")
        lines += [f"        <{k} value={quoteattr(v)}/>" for k, v in values.items()]
        lines.append(f"    </{section}>")
    lines += ["</configuration>", ""]
    return write_text_atomic(folder / CONFIG_FILE_NAME, "\n".join(lines))


def relative(path: Path, folder: Path) -> str:
    """``path`` relative to ``folder``."""
    return os.path.relpath(Path(path).resolve(), Path(folder).resolve())


@dataclass(frozen=True)
class SpeedRamp:
    """Keeps SUMO's walkers within an acceleration bound where they speed up or slow down.

    SUMO's striping model walks a person at its full speed from its first step (15 m/s² at
    1.5 m/s and 0.1 s steps). Its speed in a step is at most the one ``person.setSpeed`` set
    last, and a setting before a step applies to that step: so before every step each
    walker's speed is set to min(its walking speed, its speed now + ``accel_mps2`` x
    ``step_s``), and no walker speeds up faster than that. (SUMO's speed is along its lane;
    where it turns or changes its stripe, and where something stops it, the jitter and the
    world's check cover the rest.) A walker that has not walked yet has speed 0: its first
    step is ``accel_mps2`` x ``step_s``. A walker told to slow down (a scenario pedestrian's
    pause, :class:`~sse_cosim.world.walker_pause.Pause`) slows by at most as much a step.
    """

    accel_mps2: float
    step_s: float

    def apply(self, walkers: Mapping[str, tuple[float, float]]) -> None:
        """Set the speed of every person of ``walkers`` (id -> (the speed it is to walk at,
        its speed now), m/s) for the next step: that speed, within ``accel_mps2`` x ``step_s``
        of its speed now."""
        rise = self.accel_mps2 * self.step_s
        for pid, (wanted, now) in walkers.items():
            libsumo.person.setSpeed(pid, max(min(wanted, now + rise), now - rise, 0.0))


def heading(nav_angle_deg: float) -> float:
    """SUMO's navigational angle (deg, 0 = north, clockwise) as a heading (rad, CCW from east),
    in [-pi, pi)."""
    return math.radians((90.0 - nav_angle_deg + 180.0) % 360.0 - 180.0)


def person_centre(x: float, y: float, nav_angle_deg: float,
                  length_m: float) -> tuple[float, float]:
    """A walking person's centre (network coordinates): SUMO gives its front ``(x, y)``, so the
    centre lies half its ``length_m`` behind, against its angle."""
    h = heading(nav_angle_deg)
    half = 0.5 * length_m
    return float(x) - half * math.cos(h), float(y) - half * math.sin(h)


def message(exc: BaseException) -> str:
    """An exception's text on one line."""
    text = " ".join(str(exc).split())
    return text or type(exc).__name__

"""Optional per-stage wall-clock timing of the simulation loop (benchmarks, profiling).

``simulate(..., timer=StageTimer())`` calls :meth:`StageTimer.lap` after each stage of a step;
each call charges the time since the previous one to the named stage. Without a timer the loop
uses :class:`NoTimer`, whose calls do nothing (no clock is read).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

STAGES = ("sumo", "geometry", "local_fusion", "sharing_fusion", "occupancy", "control", "output")
"""The loop's stages in order: SUMO step and snapshot; sensors (line of sight, regions, strips);
every node's observer; V2X and the bus's fusion; negative information (polygons); picture,
speed level and the command back to SUMO; the step callback (recorder, outputs)."""


@dataclass
class StageTimer:
    """Accumulated seconds per stage and the number of steps timed."""

    totals: dict[str, float] = field(default_factory=lambda: dict.fromkeys(STAGES, 0.0))
    steps: int = 0
    _last: float = 0.0

    def start(self) -> None:
        """Start a step: the next :meth:`lap` measures from now."""
        self._last = time.perf_counter()

    def lap(self, stage: str) -> None:
        """Charge the time since the previous lap (or :meth:`start`) to ``stage``."""
        now = time.perf_counter()
        self.totals[stage] = self.totals.get(stage, 0.0) + now - self._last
        self._last = now

    def end_step(self, stage: str) -> None:
        """Charge the last stage of a step and count the step."""
        self.lap(stage)
        self.steps += 1

    def per_step_us(self) -> dict[str, float]:
        """Mean microseconds per step of each stage."""
        n = max(self.steps, 1)
        return {name: 1e6 * total / n for name, total in self.totals.items()}


class NoTimer:
    """The loop's timer when nobody asked for one: every call does nothing."""

    def start(self) -> None:
        """Nothing to start."""

    def lap(self, stage: str) -> None:
        """Nothing to charge."""

    def end_step(self, stage: str) -> None:
        """Nothing to count."""

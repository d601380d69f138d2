"""Checked assumptions: what the estimator and the controller assume of the simulated world,
one module each, every one checked at every step (:mod:`sse_cosim.world.checks.base`).

A check is one module here: a :class:`WorldCheck` whose ``name`` a study may list in
``breaks_assumptions`` (the scenario schema's ``Assumption``), and whose ``build`` makes it for
a run. Registering it is one entry in :data:`CHECKS`; the SUMO adapter runs them all through
one :class:`Ledger` (stop in one line, or count in a study that declares it).
"""

from __future__ import annotations

from sse_cosim.world.checks.base import (
    KEPT_BREAKS,
    Break,
    CheckSetup,
    Ledger,
    StepFacts,
    WorldCheck,
)
from sse_cosim.world.checks.ground import GroundCheck
from sse_cosim.world.checks.lanes import PlannedLanesCheck
from sse_cosim.world.checks.lights import LightsCheck
from sse_cosim.world.checks.motion import MotionCheck
from sse_cosim.world.checks.odometer import OdometerCheck

CHECKS: dict[str, type[WorldCheck]] = {  # one entry each
    check.name: check
    for check in (MotionCheck, GroundCheck, LightsCheck, PlannedLanesCheck, OdometerCheck)
}


def ledger(setup: CheckSetup, source: str) -> Ledger:
    """Every registered check that ``setup``'s run gives something to check, in one ledger."""
    built = [check.build(setup) for check in CHECKS.values()]
    return Ledger([c for c in built if c is not None], setup.scenario.breaks_assumptions,
                  source)


__all__ = ["CHECKS", "KEPT_BREAKS", "Break", "CheckSetup", "Ledger", "StepFacts", "WorldCheck",
           "ledger"]

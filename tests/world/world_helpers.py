"""Shared helpers of the world tests (imported as ``world_helpers``).

libsumo runs one simulation per process, but after ``close()`` a new one starts cleanly in the
same process and gives the same results as a fresh process (checked by
``test_restart_in_process_matches_fresh_process``), so the SUMO tests run in the pytest process
one after the other; only that check spawns a process.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from sse_cosim.scenario.loader import load_scenario
from sse_cosim.scenario.model import Scenario

REPO = Path(__file__).resolve().parents[2]
SCENARIOS_DIR = REPO / "scenarios"
SOURCES_DIR = REPO / "sumo_net"
# the paper's six (s1_... to s3_...), not crowd.toml
PAPER_SCENARIOS = sorted(p.stem for p in SCENARIOS_DIR.glob("s[0-9]_*.toml"))


def scenario(name: str, **overrides: object) -> Scenario:
    """A paper scenario by file stem, with dotted overrides."""
    return load_scenario(SCENARIOS_DIR / f"{name}.toml", overrides or None)


@dataclass
class Run:
    """The snapshots of one SUMO run and what the world reported."""

    snapshots: list
    pedestrian_plans: dict
    teleports: int
    bus_arrived: bool
    route_length: float  # the bus's
    roadmap: object


def run_world(sc: Scenario, run_dir: Path, name: str = "test", steps: int | None = None) -> Run:
    """Step the scenario for ``steps`` steps (default: its whole duration)."""
    from sse_cosim.world.sumo import SumoWorld

    sim = sc.simulation
    n = steps if steps is not None else round(sim.duration_s / sim.step_length_s)
    with SumoWorld(sc, run_dir, name) as world:
        snapshots = [world.step() for _ in range(n)]
        return Run(snapshots, world.pedestrian_plans, world.teleports, world.arrived("bus"),
                   world.route_length("bus"), world.roadmap)

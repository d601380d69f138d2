"""Campaign files and fake planners shared by the safety tests."""

from __future__ import annotations

from pathlib import Path

from sse_cosim.scenario.model import Scenario

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"
NOISE = "sensors.*[node!=bus].noise_bound_m"

PARAMS = f"""
[[params]]
path = "pedestrians.pedestrian.steps_onto_crossing_s"
name = "step_s"
values = [8.0, 12.0]

[[params]]
path = "pedestrians.pedestrian.walking_speed_mps"
name = "walk_mps"
values = [1.0, 2.5]

[[params]]
path = "parked.truck.end_pos_m"
name = "truck_m"
values = [186.0, 192.0]

[[params]]
path = "{NOISE}"
name = "noise_m"
values = [[0.5, 0.5], [1.5, 1.5]]
"""
BEHIND = """
[start_behind_truck]
name = "behind_m"
values = [1.0, 5.0]
"""


def campaign_file(tmp_path: Path, params: str = PARAMS, behind: str = BEHIND,
                  extra: str = "", scenarios: tuple[str, ...] = ("s1", "s2")) -> Path:
    """A campaign file in ``tmp_path`` over the repository's pedestrian scenarios."""
    files = ", ".join(f'"{SCENARIOS / f"{s}_pedestrian.toml"}"' for s in scenarios)
    path = tmp_path / "campaign.toml"
    path.write_text(f"scenarios = [{files}]\nseeds = [1, 2]\n{extra}\n{params}\n{behind}",
                    encoding="utf-8")
    return path


def slow_walkers_cannot(scenario: Scenario, source: str) -> str | None:
    """A fake planner: a pedestrian slower than 2 m/s is refused."""
    speed = scenario.pedestrians["pedestrian"].walking_speed_mps
    if speed < 2.0:
        return f"too slow ({speed:g} m/s)"
    return None


def everything_feasible(scenario: Scenario, source: str) -> str | None:
    return None

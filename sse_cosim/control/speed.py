"""Speed levels from the situational picture (paper Section IV).

The paper lists nominal (100 %), cautious "30 %", slow "50 %" and very slow "80 %" of the
nominal speed. Read as *fractions* the levels would speed up as the danger grows, so we read
them as *reductions*: cautious 0.7, slow 0.5 and very slow 0.2 of nominal (configurable;
``docs/controller.md`` discusses the other reading). The rules, most severe first:

1. a pedestrian region in the swept path within the stopping distance: emergency brake;
2. a pedestrian region within ``path_margin_m`` of the path ahead: very slow;
3. the crossing ahead, with a pedestrian region near it or with hidden walkable area near
   it that may hold an undetected pedestrian: slow;
4. such hidden area in the bus's own view while the crossing is farther off: cautious;
5. otherwise nominal.

"Near the crossing" is a reachability radius (``SceneContext.reach_radius``): a hidden place
matters only if a pedestrian starting there could reach the crossing before the bus, at its
nominal speed, has cleared it. "Hidden" is what the bus's sensors cannot see and no node
has seen recently enough (``estimation.occupancy.UnobservedArea``).
"""

from __future__ import annotations

from enum import IntEnum

from sse_cosim.control.picture import Picture
from sse_cosim.scenario.model import Controller


class SpeedLevel(IntEnum):
    """Ordered by severity."""

    NOMINAL = 0
    CAUTIOUS = 1
    SLOW = 2
    VERY_SLOW = 3
    EMERGENCY = 4

    @property
    def label(self) -> str:
        return self.name.lower().replace("_", " ")


def choose_level(picture: Picture, config: Controller) -> SpeedLevel:
    """The speed level the rules above give for ``picture``."""
    if picture.pedestrian_in_stopping_distance:
        return SpeedLevel.EMERGENCY
    if picture.pedestrian_near_path:
        return SpeedLevel.VERY_SLOW
    hidden_near_crossing = picture.unresolved_occluded_m2 > config.occlusion_threshold_m2
    if picture.crossing_ahead and (picture.pedestrian_near_crossing or hidden_near_crossing):
        return SpeedLevel.SLOW
    if hidden_near_crossing:
        return SpeedLevel.CAUTIOUS
    return SpeedLevel.NOMINAL


def with_fallback(level: SpeedLevel, inconsistent: bool, config: Controller) -> SpeedLevel:
    """``level``, made at least ``config.inconsistent_level`` while the picture is inconsistent.

    A flagged source means some node broke its bounds: before the flag (the detection delay)
    the fused set may have missed the pedestrian, and after it the picture rests on the
    assumption of a single fault. The floor (default slow, docs/faults.md) covers that; the
    rules above still apply on top of it.
    """
    if not inconsistent:
        return level
    return max(level, SpeedLevel[config.inconsistent_level.upper().replace(" ", "_")])


def level_speed(level: SpeedLevel, nominal_mps: float, config: Controller) -> float:
    """Commanded speed (m/s) of a level; an emergency brake commands a stop."""
    factors = {
        SpeedLevel.NOMINAL: 1.0,
        SpeedLevel.CAUTIOUS: config.cautious_factor,
        SpeedLevel.SLOW: config.slow_factor,
        SpeedLevel.VERY_SLOW: config.very_slow_factor,
        SpeedLevel.EMERGENCY: 0.0,
    }
    return nominal_mps * factors[level]

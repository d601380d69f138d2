"""The bus's second fusion level: its own and the received estimates (Proposition 2)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from sse_cosim.estimation.motion import MotionModel
from sse_cosim.estimation.observer import Track
from sse_cosim.estimation.settings import EstimatorSettings
from sse_cosim.sets import Zonotope, fuse


def fuse_at_bus(
    own: Mapping[str, Track],
    received: Mapping[str, Mapping[str, Zonotope]],
    fusion_method: str,
    settings: EstimatorSettings,
    model: MotionModel,
) -> dict[str, Zonotope]:
    """One fused state set per pedestrian known to the bus or to any sender.

    Every input contains the pedestrian, so their intersection does, and each fusion method
    over-approximates that intersection: the fused set is sound. Order reduction may enlarge
    it, so the bus keeps whichever is smaller in position area: the reduced fusion or the
    smallest input. The fused set is therefore never larger than the smallest set it fuses.
    """
    fused: dict[str, Zonotope] = {}
    for person_id in sorted(own.keys() | received.keys()):
        inputs = [own[person_id].estimate] if person_id in own else []
        inputs += [received[person_id][s] for s in sorted(received.get(person_id, {}))]
        fused[person_id] = fuse_sets(inputs, fusion_method, settings, model)
    return fused


def fuse_sets(
    inputs: Sequence[Zonotope], fusion_method: str, settings: EstimatorSettings,
    model: MotionModel,
) -> Zonotope:
    """Fuse (Prop. 2), reduce, and keep the smaller in position area of that and the
    smallest input."""
    if len(inputs) == 1:
        return inputs[0]
    reduced = settings.reduce(fuse(list(inputs), fusion_method))
    return min([reduced, *inputs], key=lambda z: model.position(z).volume())


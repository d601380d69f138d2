"""The bus's estimation at one step, over what reached it: screen, fuse, flag.

The second fusion level of paper Fig. 3. Its inputs are every node's local tracks (the
first level, :class:`~sse_cosim.estimation.observer.LocalObservers`), the senders' newest
messages brought to the current step (:mod:`sse_cosim.estimation.v2x`) and the regions seen
without each pedestrian (negative information). The bus screens them
(:mod:`sse_cosim.estimation.bus_screen`), fuses what it keeps (Proposition 2,
:mod:`sse_cosim.estimation.bus_fusion`) and flags what it left out
(:mod:`sse_cosim.estimation.flags`). The co-simulation and the SUMO-free fault tests both
run this one object.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

from sse_cosim.estimation.bus_fusion import fuse_at_bus
from sse_cosim.estimation.bus_screen import BusScreen, BusScreener
from sse_cosim.estimation.flags import StepFlags, step_flags
from sse_cosim.estimation.motion import MotionModel
from sse_cosim.estimation.observer import Track
from sse_cosim.estimation.occupancy import ClearRegion
from sse_cosim.estimation.settings import EstimatorSettings
from sse_cosim.estimation.v2x import SharedPicture
from sse_cosim.regions import RegionKind
from sse_cosim.sets import Zonotope


@dataclass(frozen=True)
class BusEstimate:
    """What the bus knows of every pedestrian at one step.

    ``screen``: what it fused and whom it flagged; ``fused``: pedestrian id (or fused track,
    :mod:`~sse_cosim.estimation.anonymous_fusion`) -> fused state set; ``flags``: per sensor
    and node, and whether its picture is inconsistent; ``inputs``: the same keys -> source
    -> the sets fused into it; ``in_view``: the keys of ``fused`` whose pedestrian some node
    detects now (the vehicle itself, or a sender in its newest message).
    """

    screen: BusScreen
    fused: dict[str, Zonotope]
    flags: StepFlags
    inputs: dict[str, dict[str, Zonotope]]
    in_view: frozenset[str] = frozenset()


class BaseFusionCentre:
    """What either fusion centre of an automated vehicle is built with (``node`` its id): the
    motion model, the estimator's settings, the fusion method and the sensors."""

    def __init__(self, model: MotionModel, settings: EstimatorSettings, fusion_method: str,
                 sensors: Iterable[str], node: str, kind: RegionKind) -> None:
        self.node = node
        self.model = model
        self.kind = kind
        self.settings = settings
        self.fusion_method = fusion_method
        self.sensors = list(sensors)


class FusionCentre(BaseFusionCentre):
    """An automated vehicle's screen, fusion and flags (``node`` its id), with the screen's
    probation kept across steps."""

    def __init__(self, model: MotionModel, settings: EstimatorSettings, fusion_method: str,
                 sensors: Iterable[str], node: str, kind: RegionKind) -> None:
        super().__init__(model, settings, fusion_method, sensors, node, kind)
        self._screener = BusScreener(model, kind, node)

    def step(
        self,
        tracks: Mapping[str, Mapping[str, Track]],
        shared: SharedPicture,
        clear: Mapping[str, Sequence[ClearRegion]],
        detected: frozenset[str],
    ) -> BusEstimate:
        """Screen, fuse and flag one step.

        ``tracks``: node -> pedestrian id -> local track (the vehicle's own among them);
        ``shared``: what the senders' newest messages say, brought to this step; ``clear``:
        pedestrian id -> regions seen without it; ``detected``: pedestrians some node
        detects now.
        """
        own = tracks[self.node]
        screen = self._screener.screen({pid: t.estimate for pid, t in own.items()},
                                       shared.estimates, clear, detected)
        fused = fuse_at_bus({pid: own[pid] for pid in screen.own}, screen.received,
                            self.fusion_method, self.settings, self.model)
        flags = step_flags(self.sensors, tracks, screen, bool(shared.inconsistent), self.node)
        inputs = {pid: screen.inputs(pid, own[pid].estimate if pid in own else None)
                  for pid in fused}
        return BusEstimate(screen, fused, flags, inputs, frozenset(fused.keys() & detected))

"""V2X sharing: nodes send the bus their estimates and visible regions, late or never.

A message leaves a node at step k and arrives at step k + latency unless it is dropped
(probability ``drop_probability``, drawn from the scenario's seeded generator) or the sender
is farther than ``range_m`` from the bus when sending. The bus keeps the newest message per
sender; its estimates are predicted forward to the current step before they are fused: exactly
over the link's latency (Definition 1, as every message arrives), and beyond it, while the
sender stays silent (out of range, its messages dropped or late, or gone), one step at a time
by the link's ``coast`` (for the automated vehicles: predicted, bounded and reduced, as the
sender itself carries a track it does not see), so a silent step costs one coast per estimate
and the sets keep a bounded size however long the silence. Visible regions are used at the
step they were seen (:mod:`sse_cosim.estimation.occupancy`).

Ended tracks. A node's message lists the tracks it ended at every step from ``ended_since``
to its own (:class:`~sse_cosim.estimation.observer.AnonymousNodeObserver`). When a sender's
newest message j' replaces its newest j < j', the bus hands to its unobserved area every
track listed in j' that ended after j, and, if j' does not list every step after j (the bus
missed too many messages in a row), every track of j as well (ended at j). Proof that the
bus then holds every pedestrian P of the sender's ended tracks (in a track of the sender's
newest message, or in the unobserved area): while j is the newest, P's set is one of j's
tracks or was handed over (induction); a track ended at e in (j, j'] held P at e only if P
was in one of j's tracks at j (the sender's tracks hold every pedestrian they held, until
they hand it over) or P was not the sender's at j, and then the bus never took it out of its
unobserved area through the sender's views after j (it had not received them). So handing
over j' 's listed tracks, or all of j's tracks (which hold P at j, hence the ended ones'
pedestrians from j on), keeps P. A sender's first message hands nothing over: the bus took no
pedestrian out of its unobserved area through that sender's views before.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from sse_cosim.estimation.motion import MotionModel
from sse_cosim.estimation.occupancy import ClearRegion, EndedTrack
from sse_cosim.regions import Region
from sse_cosim.scenario.model import V2X
from sse_cosim.sets import Zonotope


@dataclass(frozen=True)
class Message:
    """What a node shares: its estimates (state sets by pedestrian id) and what it sees.

    ``detected`` names the pedestrians its sensors saw when sending: for any other
    pedestrian, ``visible_region`` is a place it was not (negative information).
    ``inconsistent``: the sender's own sources disagreed (it left a sensor out, or its
    estimates are hulls of hypotheses; :mod:`sse_cosim.estimation.correction`). ``ended``:
    every track the sender ended at a step from ``ended_since`` to ``sent_step`` (module
    docstring).
    """

    sender: str
    sent_step: int
    estimates: dict[str, Zonotope]
    visible_region: Region
    detected: frozenset[str] = frozenset()
    inconsistent: bool = False
    ended: tuple[EndedTrack, ...] = ()
    ended_since: int = 0


@dataclass(frozen=True)
class SharedPicture:
    """Received information brought to the current step."""

    estimates: dict[str, dict[str, Zonotope]]  # pedestrian id -> sender -> state set
    regions: dict[str, Region]  # sender -> visible region when sent
    ages: dict[str, int]  # sender -> steps since it sent
    detected: dict[str, frozenset[str]]  # sender -> pedestrians it saw
    inconsistent: frozenset[str] = frozenset()  # senders whose own sources disagreed

    def clear_of(self, person_id: str) -> list[ClearRegion]:
        """Regions seen by senders that did not detect ``person_id`` (negative information)."""
        return [
            ClearRegion(region, self.ages[sender])
            for sender, region in self.regions.items()
            if person_id not in self.detected[sender]
        ]


class V2XLink:
    """Every node's link to one automated vehicle, with the scenario's range, latency and
    losses."""

    def __init__(self, config: V2X, rng: np.random.Generator,
                 coast: Callable[[Zonotope], Zonotope] | None = None) -> None:
        """``coast``: one silent step of a received estimate (module docstring); None: the
        exact prediction by one step at any age (Definition 1; the sets grow by the
        process noise's generators each step)."""
        self.config = config
        self.rng = rng
        self.coast = coast
        self._in_flight: list[tuple[int, Message]] = []
        self.latest: dict[str, Message] = {}
        self._handed: list[EndedTrack] = []  # ended tracks delivered, not yet taken
        # sender -> (its newest message's step, the step its estimates are brought to, them)
        self._coasted: dict[str, tuple[int, int, dict[str, Zonotope]]] = {}

    def send(self, message: Message, distance_to_bus: float, extra_latency_steps: int = 0) -> bool:
        """Queue ``message``; False if out of range or dropped. ``extra_latency_steps`` delay
        it beyond the link's latency (an injected fault)."""
        if distance_to_bus > self.config.range_m:
            return False
        if self.rng.random() < self.config.drop_probability:
            return False
        arrival = message.sent_step + self.config.latency_steps + extra_latency_steps
        self._in_flight.append((arrival, message))
        return True

    def deliver(self, step: int) -> list[Message]:
        """Hand the bus every message due by ``step`` (returned); it keeps the newest per
        sender, and the tracks a new newest message hands over wait for :meth:`take_ended`."""
        due = [m for arrival, m in self._in_flight if arrival <= step]
        self._in_flight = [(a, m) for a, m in self._in_flight if a > step]
        for message in sorted(due, key=lambda m: m.sent_step):
            kept = self.latest.get(message.sender)
            if kept is None or message.sent_step > kept.sent_step:
                self.latest[message.sender] = message
                if kept is not None:
                    self._handed += _handed_over(kept, message)
        return due

    def take_ended(self) -> list[EndedTrack]:
        """The tracks handed over by the messages delivered since the last call (module
        docstring), each at the step it ended."""
        taken, self._handed = self._handed, []
        return taken

    def picture(self, step: int, model: MotionModel) -> SharedPicture:
        """The newest message of every sender, predicted to ``step``."""
        estimates: dict[str, dict[str, Zonotope]] = {}
        latest = sorted(self.latest.items())
        for sender, message in latest:
            for person_id, estimate in self._brought(sender, message, step, model).items():
                estimates.setdefault(person_id, {})[sender] = estimate
        return SharedPicture(
            estimates,
            regions={sender: m.visible_region for sender, m in latest},
            ages={sender: step - m.sent_step for sender, m in latest},
            detected={sender: m.detected for sender, m in latest},
            inconsistent=frozenset(sender for sender, m in latest if m.inconsistent),
        )

    def _brought(self, sender: str, message: Message, step: int, model: MotionModel
                 ) -> dict[str, Zonotope]:
        """``message``'s estimates at ``step``: predicted exactly up to its arrival on time
        (``sent_step`` + latency), then coasted one step at a time, from where the previous
        step left them (module docstring)."""
        on_time = message.sent_step + self.config.latency_steps
        if step <= on_time:
            return _predicted(message, step, model)
        kept = self._coasted.get(sender)
        if kept is None or kept[0] != message.sent_step or kept[1] > step:
            kept = (message.sent_step, on_time, _predicted(message, on_time, model))
        coast = self.coast or model.predict
        estimates = kept[2]
        for _ in range(step - kept[1]):
            estimates = {pid: coast(z) for pid, z in estimates.items()}
        self._coasted[sender] = (message.sent_step, step, estimates)
        return estimates


def _predicted(message: Message, step: int, model: MotionModel) -> dict[str, Zonotope]:
    """``message``'s estimates predicted exactly to ``step`` (Definition 1)."""
    return {pid: model.predict(z, step - message.sent_step)
            for pid, z in message.estimates.items()}


def _handed_over(kept: Message, newest: Message) -> list[EndedTrack]:
    """The tracks the sender's ``newest`` message hands over when it replaces ``kept``: those
    it lists as ended after ``kept`` was sent, and every track of ``kept`` if it does not list
    every step since (module docstring)."""
    ended = [t for t in newest.ended if t.step > kept.sent_step]
    if newest.ended_since > kept.sent_step + 1:
        ended += [EndedTrack(kept.sent_step, z) for z in kept.estimates.values()]
    return ended

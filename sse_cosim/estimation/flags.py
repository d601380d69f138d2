"""What the trace shows of the consistency checks at one step: flags per sensor and node, and
whether the bus's picture is inconsistent (the controller's fallback, docs/faults.md)."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Protocol

from sse_cosim.estimation.bus_screen import CONFLICT, BusScreen


class ScreenedTrack(Protocol):
    """The part of an observer's track the flags need."""

    flagged: frozenset[str]
    conflict: bool


def disagrees(tracks: Iterable[ScreenedTrack]) -> bool:
    """Whether a node's own sources disagreed at this step: it left a sensor out, or one of
    its estimates is a hull of hypotheses."""
    return any(t.conflict or t.flagged for t in tracks)


@dataclass(frozen=True)
class StepFlags:
    """One step's flags: per sensor (left out), per node (``excluded``/``conflict``/""),
    and whether the bus's own picture is inconsistent (the controller's fallback)."""

    sensors: dict[str, bool] = field(default_factory=dict)
    nodes: dict[str, str] = field(default_factory=dict)
    inconsistent: bool = False


def step_flags(
    sensors: Iterable[str],
    tracks: Mapping[str, Mapping[str, ScreenedTrack]],
    screen: BusScreen,
    remote_inconsistency: bool,
    own_node: str,
) -> StepFlags:
    """Flags of every sensor and node; ``remote_inconsistency``: a sender reported that its
    own sources disagreed (the newest message of some sender says so); ``own_node``: the
    screening vehicle's id.

    A node is ``excluded`` when the bus left one of its estimates out, in ``conflict`` when
    its own sensors and prediction disagree unattributably or it is a suspect of such a
    disagreement at the bus. The bus's picture is inconsistent when anything the bus knows
    of is flagged: its own tracks, the screen, or an inconsistency reported by a sender.
    """
    left_out = {s for node_tracks in tracks.values() for t in node_tracks.values()
                for s in t.flagged}
    at_bus = screen.flags()
    nodes = {}
    for node, node_tracks in tracks.items():
        in_conflict = any(t.conflict for t in node_tracks.values())
        nodes[node] = at_bus.get(node) or (CONFLICT if in_conflict else "")
    own = tracks.get(own_node, {})
    inconsistent = bool(at_bus) or remote_inconsistency or disagrees(own.values())
    return StepFlags({s: s in left_out for s in sensors}, nodes, inconsistent)

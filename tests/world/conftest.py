"""Fixtures of the world tests; helpers live in world_helpers.py."""

from __future__ import annotations

from pathlib import Path

import pytest
from world_helpers import SOURCES_DIR

from sse_cosim.world.network import build_network


@pytest.fixture(scope="session")
def net_path() -> Path:
    """The network built from the repository's sources (cached in sumo_net/build/)."""
    return build_network(SOURCES_DIR)

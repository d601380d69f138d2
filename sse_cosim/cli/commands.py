"""Sub-commands of ``sse-cosim``; each is a thin layer over ``sse_cosim.runner`` and friends."""

from __future__ import annotations

from sse_cosim.cli.main import cli

__all__ = ["cli"]

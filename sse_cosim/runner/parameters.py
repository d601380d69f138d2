"""Dotted scenario parameters given on the command line: ``PATH=VALUE``."""

from __future__ import annotations

import tomllib
from typing import Any

from sse_cosim.errors import UserError


def parse_value(text: str) -> Any:
    """A TOML value (number, boolean, list, quoted string); anything else is a plain string."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def parse_assignment(text: str, option: str) -> tuple[str, Any]:
    """``"sensors.bus_front.range_m=40"`` -> ``("sensors.bus_front.range_m", 40)``."""
    path, sep, value = text.partition("=")
    if not sep or not path.strip() or not value.strip():
        raise UserError("command line", option, f"{text!r} is not PATH=VALUE",
                        "write it like sensors.bus_front.range_m=40")
    return path.strip(), parse_value(value.strip())

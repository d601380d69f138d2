"""Sensor kinds by name; a scenario sensor's ``kind`` picks one (default ``camera``).

A kind is one module here: its schema (a :class:`SensorConfig` with ``kind: Literal[name]``
and its own fields) whose ``build()`` returns a :class:`SensorKind`. Registering it is one
entry in :data:`CONFIGS`; the scenario schema, its field table and its error messages follow.
"""

from __future__ import annotations

from typing import Annotated, Any, Union, get_args

from pydantic import BeforeValidator, Discriminator, Tag

from sse_cosim.scenario.base import TAG_MARK
from sse_cosim.sensors.kinds.base import SensorConfig, SensorKind, SensorMount
from sse_cosim.sensors.kinds.camera import Camera, CameraConfig
from sse_cosim.sensors.kinds.range_bearing import RangeBearing, RangeConfig

DEFAULT_KIND = "camera"
CONFIGS: dict[str, type[SensorConfig]] = {
    get_args(config.model_fields["kind"].annotation)[0]: config  # its Literal's one value
    for config in (CameraConfig, RangeConfig)  # the registration: one entry per kind
}


def _tag(kind: str) -> str:
    return f"kind{TAG_MARK}{kind}"


def _kind_of(value: Any) -> str:
    """The kind named by a sensor table (default: camera) or a validated sensor."""
    if isinstance(value, dict):
        return str(value.get("kind", DEFAULT_KIND))
    return str(getattr(value, "kind", DEFAULT_KIND))


def _kind_fields_only(value: Any) -> Any:
    """Refuse an unknown kind, and a field of another kind, naming the fix."""
    if not isinstance(value, dict):
        return value
    kind = _kind_of(value)
    if kind not in CONFIGS:
        raise ValueError(f"kind: unknown sensor kind {kind!r}; use one of {', '.join(CONFIGS)}")
    for name in value:
        owners = [k for k, config in CONFIGS.items() if name in config.model_fields]
        if owners and kind not in owners:
            raise ValueError(f"{name}: only used with kind = {owners[0]!r}, this sensor is a "
                             f"{kind!r}; remove it, or set kind = {owners[0]!r}")
    return value


Sensor = Annotated[
    Union[tuple(Annotated[config, Tag(_tag(kind))] for kind, config in CONFIGS.items())],  # noqa: UP007
    Discriminator(lambda value: _tag(_kind_of(value))),
    BeforeValidator(_kind_fields_only),
]
"""A scenario sensor: the schema of its kind (a tagged union over :data:`CONFIGS`)."""

__all__ = [
    "CONFIGS",
    "Camera",
    "CameraConfig",
    "RangeBearing",
    "RangeConfig",
    "Sensor",
    "SensorConfig",
    "SensorKind",
    "SensorMount",
]

"""Building blocks of the scenario schema, shared by :mod:`.model` and the sensor kinds'
own schemas (:mod:`sse_cosim.sensors.kinds`), which the model imports."""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field

PositiveFloat = Annotated[float, Field(gt=0)]
NonNegativeFloat = Annotated[float, Field(ge=0)]
TAG_MARK = "="  # a union tag ("kind=range") holds it; field names never do (see loader)


class StrictModel(BaseModel):
    """Base model: unknown keys are errors, so are infinite and NaN numbers (TOML has them:
    ``inf``, ``nan``; no field means one), and values are checked on assignment too."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True, frozen=False,
                              allow_inf_nan=False)

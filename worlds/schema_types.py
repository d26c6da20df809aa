"""The world file's field types: checked numbers, vectors and ranges, and the models' base.

Each type validates before pydantic's own checks, so a bad value reports what was expected and
what was received (:func:`worlds.world_errors.field_problem`). :mod:`worlds.world_schema` and
:mod:`worlds.trial_schema` build their models from them.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from typing import Annotated, Any

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field

from worlds.world_errors import Shown, field_problem, show_value


def vector3(value: Any) -> Any:
    """Check for exactly 3 finite numbers before pydantic's own tuple validation."""
    if isinstance(value, str | bytes) or not isinstance(value, Sequence):
        raise field_problem("a list of exactly 3 numbers [x, y, z]", value)
    if len(value) != 3:
        raise field_problem(
            "a list of exactly 3 numbers [x, y, z]",
            Shown(f"{len(value)} items {show_value(value)}"),
        )
    for i, item in enumerate(value):
        check_finite(item, i)
    return tuple(float(item) for item in value)


def check_finite(item: Any, index: int) -> None:
    """Raise unless ``item`` (at ``index`` of a list) is a finite int or float, not a bool."""
    if isinstance(item, bool) or not isinstance(item, int | float):
        raise field_problem("a number", item, index)
    try:
        finite = math.isfinite(item)
    except OverflowError:  # an int too large for a float
        finite = False
    if not finite:
        raise field_problem("a finite number", item, index)


#: Largest magnitude of any number in a world file: far beyond anything the physics can mean
#: (a 1e308 m position validated, then turned into NaN in the first physics step).
LIMIT = 1e6
#: Largest magnitude of a position or an extent, m: a tabletop world is metres across.
LIMIT_M = 100.0
Finite = Annotated[float, Field(strict=True, allow_inf_nan=False, ge=-LIMIT, le=LIMIT)]
Positive = Annotated[float, Field(strict=True, allow_inf_nan=False, gt=0, le=LIMIT)]
NonNegative = Annotated[float, Field(strict=True, allow_inf_nan=False, ge=0, le=LIMIT)]
PositiveInt = Annotated[int, Field(strict=True, gt=0, le=10**9)]
NonNegativeInt = Annotated[int, Field(strict=True, ge=0, le=2**63 - 1)]
Metres = Annotated[float, Field(strict=True, allow_inf_nan=False, ge=-LIMIT_M, le=LIMIT_M)]
PositiveMetres = Annotated[float, Field(strict=True, allow_inf_nan=False, gt=0, le=LIMIT_M)]
Name = Annotated[str, Field(strict=True, min_length=1)]
Text = Annotated[str, Field(strict=True)]
#: A skill's name or label in a library: letters, digits, '_' or '-', not starting with a digit.
SKILL_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_-]*")

Vector3 = Annotated[tuple[Metres, Metres, Metres], BeforeValidator(vector3)]
"""Three finite numbers ``[x, y, z]``, within 100 (a position, m)."""

FiniteVector3 = Annotated[tuple[Finite, Finite, Finite], BeforeValidator(vector3)]
"""Three finite numbers ``[x, y, z]``, within 1e6 (a force, N, or a torque, N m)."""

Degrees = Annotated[float, Field(strict=True, allow_inf_nan=False, ge=-720.0, le=720.0)]
Angles3 = Annotated[tuple[Degrees, Degrees, Degrees], BeforeValidator(vector3)]
"""Three finite angles ``[roll, pitch, yaw]``, degrees, within two turns either way."""

PositiveVector3 = Annotated[
    tuple[PositiveMetres, PositiveMetres, PositiveMetres], BeforeValidator(vector3)
]
"""Three finite numbers ``[x, y, z]``, each greater than 0 and at most 100 (extents, m)."""


def range_of(value: Any) -> Any:
    """Check for exactly 2 finite numbers ``[low, high]`` with ``low <= high``."""
    if isinstance(value, str | bytes) or not isinstance(value, Sequence) or len(value) != 2:
        raise field_problem("a list of exactly 2 numbers [low, high]", value)
    for i, item in enumerate(value):
        check_finite(item, i)
    if value[0] > value[1]:
        raise field_problem("low <= high", value)
    return (float(value[0]), float(value[1]))


Range = Annotated[tuple[Finite, Finite], BeforeValidator(range_of)]
"""Two finite numbers ``[low, high]``, low <= high: values are drawn uniformly between them."""


def optional_range_of(value: Any) -> Any:
    """A :data:`Range`, or None (left to a default)."""
    return None if value is None else range_of(value)


OptionalRange = Annotated[tuple[Finite, Finite] | None, BeforeValidator(optional_range_of)]
"""A :data:`Range`, or None for a default given elsewhere."""


class FileModel(BaseModel):
    """Base of every world file model: unknown keys are errors and values are immutable."""

    model_config = ConfigDict(extra="forbid", frozen=True)

"""What a skill's stored parameters and arrays may hold, per kind: one table and one check.

A library file is data from anywhere; a NaN weight, ``alpha: 1e308`` or ``demo_tau: 0`` would
load and then crash a run (or quietly make the DMP do nothing). :func:`check_skill_data`
holds every stored number to what the physics can mean: finite, in range, the right shape.
The bounds are generous (orders of magnitude beyond the shipped skills), so they refuse
nonsense, never a real teaching.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from skills.pose_model import DURATION_RANGE_S, MAX_POSITION_M
from skills.scaling import Scaling
from skills.skill import SkillKind

#: Any stored number, whatever its parameter: beyond this nothing in the physics can mean it.
ANY_BOUND = 1e9
#: The most elements one stored array may have (a 10 000-basis DMP has 30 000 weights).
MAX_ARRAY_SIZE = 1_000_000
#: How far a stored quaternion's norm may be from 1.
UNIT_TOLERANCE = 1e-3


class SkillDataError(ValueError):
    """A stored parameter or array out of what it may hold; names the field."""

    def __init__(self, field: str, expected: str, got: Any) -> None:
        self.field, self.expected, self.got = field, expected, got
        super().__init__(f"{field}: expected {expected}, got {got}")


@dataclass(frozen=True)
class Number:
    """A scalar parameter in ``[low, high]`` (open at an end if asked), in ``unit``."""

    low: float
    high: float
    unit: str = ""
    open_low: bool = False
    integer: bool = False
    required: bool = True
    open_high: bool = False

    def describe(self) -> str:
        kind = "an integer" if self.integer else "a number"
        left = "(" if self.open_low else "["
        right = ")" if self.open_high else "]"
        unit = f" {self.unit}" if self.unit else ""
        return f"{kind} in {left}{self.low:g}, {self.high:g}{right}{unit}"

    def admits(self, value: float) -> bool:
        above = value > self.low if self.open_low else value >= self.low
        below = value < self.high if self.open_high else value <= self.high
        return bool(np.isfinite(value)) and above and below


@dataclass(frozen=True)
class Choice:
    """A text parameter, one of ``options``."""

    options: tuple[str, ...]
    required: bool = True


@dataclass(frozen=True)
class ArraySpec:
    """An array of ``shape`` (``"n"`` is the skill's ``n_basis``) with entries in bounds."""

    shape: tuple[int | str, ...]
    low: float
    high: float
    unit: str = ""
    open_low: bool = False
    unit_norm: bool = False


_SCALINGS = Choice(tuple(s.value for s in Scaling))
_GAIN = Number(0.0, 1e7)

PARAMS: Mapping[SkillKind, Mapping[str, Number | Choice]] = {
    SkillKind.LEARNT_DMP: {
        "alpha": Number(0.0, 1e4, open_low=True),
        "alpha_s": Number(0.0, 100.0, open_low=True),
        "n_basis": Number(1, 10_000, integer=True),
        "overlap": Number(0.0, 1.0, open_low=True, open_high=True),
        "regularisation": Number(0.0, 1e6),
        "position_scaling": _SCALINGS,
        "orientation_scaling": _SCALINGS,
        "min_amplitude": Number(0.0, 100.0, "m"),
        "min_rotation": Number(0.0, 10.0, "rad"),
        # What fit_pose learns from (a millisecond to an hour).
        "demo_tau": Number(*DURATION_RANGE_S, "s"),
    },
    SkillKind.OBSTACLE_STEERING: {
        "gamma": _GAIN,
        "beta": Number(0.0, 1e3),
        "k": Number(0.0, 1e6),
    },
    SkillKind.POTENTIAL_FIELD: {
        "gain": _GAIN,
        "beta": Number(0.0, 1e3, open_low=True),
        "influence": Number(0.0, 10.0, "m", open_low=True),
    },
    SkillKind.WORKSPACE_REPULSION: {
        "gain": _GAIN,
        "margin": Number(0.0, 1.0, "m", open_low=True),
    },
    SkillKind.GRASP_MAINTENANCE: {
        "stiffness": Number(0.0, 1e6, "N/m per kg", open_low=True, required=False),
        "damping": Number(0.0, 1e5, "N s/m per kg", required=False),
        "rotational_stiffness": Number(0.0, 1e6, open_low=True, required=False),
        "squeeze_force_n": Number(0.0, 1e3, "N", open_low=True, required=False),
    },
    SkillKind.FORCE_TRACKING: {},
}

_POSITION = ArraySpec((3,), -MAX_POSITION_M, MAX_POSITION_M, "m")
_QUATERNION = ArraySpec((4,), -1.0 - UNIT_TOLERANCE, 1.0 + UNIT_TOLERANCE, unit_norm=True)
_WEIGHTS = ArraySpec(("n", 3), -ANY_BOUND, ANY_BOUND)

ARRAYS: Mapping[SkillKind, Mapping[str, ArraySpec]] = {
    SkillKind.LEARNT_DMP: {
        "centres": ArraySpec(("n",), 0.0, 1.0),  # phase values, s in (0, 1]
        "widths": ArraySpec(("n",), 0.0, 1e18, open_low=True),
        "position_weights": _WEIGHTS,
        "orientation_weights": _WEIGHTS,
        "position_reference": ArraySpec((3,), -100.0, 100.0, "m"),
        "orientation_reference": ArraySpec((3,), -100.0, 100.0, "rad"),
        "demo_start_position": _POSITION,
        "demo_goal_position": _POSITION,
        "demo_start_orientation": _QUATERNION,
        "demo_goal_orientation": _QUATERNION,
    },
    SkillKind.GRASP_MAINTENANCE: {"reference_object": ArraySpec((3,), -10.0, 10.0, "m")},
}


def check_skill_data(kind: SkillKind, params: Mapping[str, Any], arrays: Mapping[str, Any]) -> None:
    """Raise :class:`SkillDataError` naming ``params.<key>`` or ``arrays.<key>`` if out of bounds.

    Parameters
    ----------
    kind : SkillKind
    params : Mapping[str, float | int | str | bool]
        Scalar parameters; those of the kind's table are required (unless marked optional)
        and held to their range; any other number must be finite and within ``ANY_BOUND``.
    arrays : Mapping[str, ndarray]
        A learnt DMP must have exactly its table's arrays; every array must be numeric,
        finite, of its table's shape and within its bounds.
    """
    table = PARAMS.get(kind, {})
    for key, spec in table.items():
        if spec.required and key not in params:
            raise SkillDataError(f"params.{key}", _describe(spec), "nothing (missing)")
    for key, value in params.items():
        _check_param(key, value, table.get(key))
    n_basis = int(params.get("n_basis", 0)) if kind is SkillKind.LEARNT_DMP else 0
    shapes = ARRAYS.get(kind, {})
    if kind is SkillKind.LEARNT_DMP:
        missing = sorted(set(shapes) - set(arrays))
        if missing:
            raise SkillDataError(f"arrays.{missing[0]}", "an array", "nothing (missing)")
        extra = sorted(set(arrays) - set(shapes))
        if extra:
            known = ", ".join(shapes)
            raise SkillDataError(f"arrays.{extra[0]}", f"one of {known}", "an unknown array")
    for key, value in arrays.items():
        _check_array(key, value, shapes.get(key), n_basis)


def _describe(spec: Number | Choice) -> str:
    if isinstance(spec, Choice):
        return "one of " + ", ".join(spec.options)
    return spec.describe()


def _check_param(key: str, value: Any, spec: Number | Choice | None) -> None:
    field = f"params.{key}"
    if isinstance(spec, Choice):
        if not isinstance(value, str) or value not in spec.options:
            raise SkillDataError(field, _describe(spec), repr(value))
        return
    numeric = isinstance(value, int | float | np.integer | np.floating) and not isinstance(
        value, bool
    )
    if spec is None:
        # A parameter no table names (a user's own): text and flags pass, numbers are bounded.
        if numeric and not finite_within(value, ANY_BOUND):
            raise SkillDataError(
                field, f"a finite number within +-{ANY_BOUND:g}", short_repr(value)
            )
        return
    if not numeric or (spec.integer and not _is_integer(value)):
        raise SkillDataError(field, spec.describe(), short_repr(value))
    if not (finite_within(value, ANY_BOUND) and spec.admits(float(value))):
        raise SkillDataError(field, spec.describe(), short_repr(value))


def finite_within(value: float | int, bound: float) -> bool:
    """Whether ``value`` is a finite number of magnitude at most ``bound`` (no OverflowError)."""
    if isinstance(value, int | np.integer):
        return abs(int(value)) <= bound
    return bool(np.isfinite(value)) and abs(float(value)) <= bound


def _is_integer(value: float | int) -> bool:
    return isinstance(value, int | np.integer) or (
        bool(np.isfinite(value)) and float(value).is_integer()
    )


def short_repr(value: Any) -> str:
    """``repr(value)``, cut to 60 characters (a 400-digit integer is not a message)."""
    text = repr(value)
    return text if len(text) <= 60 else f"{text[:28]}...{text[-28:]} ({len(text)} characters)"


def _check_array(key: str, value: Any, spec: ArraySpec | None, n_basis: int) -> None:
    field = f"arrays.{key}"
    arr = np.asarray(value)
    if arr.dtype.kind not in "biuf":
        raise SkillDataError(field, "a numeric array", f"dtype {arr.dtype}")
    if arr.size > MAX_ARRAY_SIZE:
        raise SkillDataError(field, f"at most {MAX_ARRAY_SIZE} entries", arr.size)
    if not np.all(np.isfinite(arr)):
        bad = int(np.flatnonzero(~np.isfinite(arr.ravel()))[0])
        raise SkillDataError(field, "finite numbers", f"{arr.ravel()[bad]} at flat index {bad}")
    if spec is None:
        if arr.size and float(np.max(np.abs(arr))) > ANY_BOUND:
            raise SkillDataError(field, f"entries within +-{ANY_BOUND:g}", np.max(np.abs(arr)))
        return
    shape = tuple(n_basis if d == "n" else d for d in spec.shape)
    if arr.shape != shape:
        raise SkillDataError(field, f"shape {shape}", arr.shape)
    low = arr <= spec.low if spec.open_low else arr < spec.low
    out = low | (arr > spec.high)
    if np.any(out):
        bad = int(np.flatnonzero(out.ravel())[0])
        left = "(" if spec.open_low else "["
        unit = f" {spec.unit}" if spec.unit else ""
        raise SkillDataError(
            field,
            f"entries in {left}{spec.low:g}, {spec.high:g}]{unit}",
            f"{arr.ravel()[bad]} at flat index {bad}",
        )
    if spec.unit_norm and abs(float(np.linalg.norm(arr)) - 1.0) > UNIT_TOLERANCE:
        raise SkillDataError(field, "a unit quaternion", f"norm {np.linalg.norm(arr):.6g}")

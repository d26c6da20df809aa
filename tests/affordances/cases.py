"""Objects and robots shared by the affordance tests."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from affordances import (
    PAPER_ROBOT,
    ObjectContext,
    ParamValue,
    RobotCapabilities,
    make_object_context,
)
from skills.vocabulary import EndEffector

ROBOT: RobotCapabilities = PAPER_ROBOT
STRONG_ROBOT: RobotCapabilities = replace(PAPER_ROBOT, squeeze_force_n=150.0)
#: The paper's robot with hands: flat palms that also close fingers, so one-arm grasps too.
HANDED_ROBOT: RobotCapabilities = replace(
    PAPER_ROBOT, end_effectors=frozenset({EndEffector.FLAT_PALM, EndEffector.GRIPPER})
)


def number(value: ParamValue) -> float:
    """A numeric skill parameter (fails the test if it is text)."""
    assert isinstance(value, float), value
    return value


def parcel(**overrides: Any) -> ObjectContext:
    """The paper's parcel: 0.20 x 0.30 x 0.15 m cardboard box, 1 kg, friction 0.8, robust."""
    values: dict[str, Any] = {
        "name": "parcel",
        "category": "parcel",
        "shape": "box",
        "dimensions": (0.20, 0.30, 0.15),
        "mass_kg": 1.0,
        "material": "cardboard",
        "friction": 0.8,
        "fragility": "robust",
        "position": (0.4, 0.0, 0.075),
        "goals": [(0.4, 0.25, 0.075)],
    }
    values.update(overrides)
    return make_object_context(**values)


def heavy_box(**overrides: Any) -> ObjectContext:
    """A 12 kg cardboard crate, 0.40 x 0.30 x 0.30 m."""
    return parcel(
        **{"name": "crate", "category": "crate", "dimensions": (0.4, 0.3, 0.3), "mass_kg": 12.0}
        | overrides
    )


def small_box(**overrides: Any) -> ObjectContext:
    """A 0.3 kg wooden cube, 6 cm across."""
    values: dict[str, Any] = {
        "name": "cube",
        "category": "block",
        "dimensions": (0.06, 0.06, 0.06),
        "mass_kg": 0.3,
        "material": "wood",
        "friction": 0.5,
        "fragility": "normal",
        "position": (0.4, -0.2, 0.03),
        "goals": [(0.45, -0.1, 0.03)],
    }
    return parcel(**values | overrides)


def wine_glass(**overrides: Any) -> ObjectContext:
    """A full, fragile glass: cylinder r = 4 cm, h = 12 cm, 0.25 kg."""
    values: dict[str, Any] = {
        "name": "glass",
        "category": "glass",
        "shape": "cylinder",
        "dimensions": (0.04, 0.12),
        "mass_kg": 0.25,
        "material": "glass",
        "friction": 0.6,
        "fragility": "fragile",
        "state": ["full"],
        "position": (0.35, 0.15, 0.06),
        "goals": [(0.45, 0.1, 0.06)],
    }
    return parcel(**values | overrides)


def open_bottle(**overrides: Any) -> ObjectContext:
    """An open plastic bottle: cylinder r = 3.5 cm, h = 25 cm, 0.6 kg."""
    values: dict[str, Any] = {
        "name": "bottle",
        "category": "bottle",
        "shape": "cylinder",
        "dimensions": (0.035, 0.25),
        "mass_kg": 0.6,
        "material": "plastic",
        "friction": 0.5,
        "fragility": "normal",
        "state": ["open"],
        "position": (0.35, -0.15, 0.125),
        "goals": [(0.4, -0.05, 0.125)],
    }
    return parcel(**values | overrides)


def tray(**overrides: Any) -> ObjectContext:
    """A 1.5 kg plastic tray with items on it, 0.45 x 0.30 x 0.03 m."""
    values: dict[str, Any] = {
        "name": "tray",
        "category": "tray",
        "dimensions": (0.45, 0.30, 0.03),
        "mass_kg": 1.5,
        "material": "plastic",
        "friction": 0.5,
        "fragility": "normal",
        "state": ["contains_items"],
        "position": (0.45, 0.0, 0.015),
    }
    return parcel(**values | overrides)

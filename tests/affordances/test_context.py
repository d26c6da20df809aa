"""Contexts and robot capabilities validate at construction and name the bad field."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import pytest

from affordances import (
    PAPER_ROBOT,
    Fragility,
    ObjectState,
    Obstacle,
    RobotCapabilities,
    Shape,
    make_object_context,
)
from skills.vocabulary import EndEffector
from tests.affordances.cases import parcel


def test_plain_values_become_enums_and_tuples() -> None:
    context = parcel(
        state=["open"],
        obstacles=[
            {"name": "ball", "position": [0.4, 0.1, 0.1], "radius": 0.05},
            {"name": "crate", "position": [0.6, 0.0, 0.1], "size": [0.2, 0.2, 0.1]},
        ],
    )
    assert context.shape is Shape.BOX
    assert context.fragility is Fragility.ROBUST
    assert context.state == frozenset({ObjectState.OPEN})
    assert context.goals == ((0.4, 0.25, 0.075),)
    assert context.obstacles[0] == Obstacle("ball", (0.4, 0.1, 0.1), 0.05)
    assert context.obstacles[1].radius == pytest.approx(0.5 * math.sqrt(0.09))


def test_free_vocabulary_is_lower_cased() -> None:
    assert parcel(category=" Parcel ", material="CardBoard").category == "parcel"


@pytest.mark.parametrize(
    ("overrides", "match"),
    [
        ({"mass_kg": -1.0}, r"mass_kg: expected > 0 kg, got -1\.0"),
        ({"mass_kg": math.nan}, r"mass_kg: expected a finite number, got nan"),
        ({"mass_kg": "heavy"}, r"mass_kg: expected a number, got 'heavy'"),
        ({"friction": -0.1}, r"friction: expected >= 0, got -0\.1"),
        ({"dimensions": (0.2, 0.3)}, r"dimensions: expected 3 values for a box \(x, y, z\)"),
        ({"dimensions": (0.2, 0.0, 0.1)}, r"dimensions\.y: expected > 0 m, got 0\.0"),
        ({"shape": "cone"}, r"shape: expected one of box, cylinder, sphere, mesh, got 'cone'"),
        ({"fragility": "brittle"}, r"fragility: expected one of robust, normal, fragile"),
        ({"state": ["open", "closed"]}, r"state: 'open' and 'closed' exclude each other"),
        ({"state": ["wet"]}, r"state: expected one of open, closed"),
        ({"position": (0.1, 0.2)}, r"position: expected 3 numbers \(x, y, z\), got 2"),
        ({"position": (0.1, math.inf, 0.0)}, r"position\[1\]: expected a finite number, got inf"),
        ({"yaw": math.nan}, r"yaw: expected a finite number"),
        ({"goals": [(0.1, 0.2, 0.3), (0.1, 0.2)]}, r"goals\[1\]: expected 3 numbers"),
        ({"goal_yaw": math.inf}, r"goal_yaw: expected a finite number"),
        ({"category": ""}, r"category: expected a non-empty string"),
        (
            {"obstacles": [{"name": "a", "position": (0, 0, 0), "radius": -1}]},
            r"Obstacle 'a'\.radius: expected > 0 m, got -1\.0",
        ),
        (
            {"obstacles": [{"name": "a", "position": (0, 0, 0)}]},
            r"obstacles\[0\] 'a': expected exactly one of 'radius' or 'size'",
        ),
        (
            {
                "obstacles": [
                    {"name": "a", "position": (0, 0, 0), "radius": 0.1},
                    {"name": "a", "position": (1, 0, 0), "radius": 0.1},
                ]
            },
            r"obstacles: duplicate names \['a'\]",
        ),
    ],
)
def test_bad_context_names_the_field(overrides: dict[str, Any], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        parcel(**overrides)


def test_cylinder_and_sphere_dimensions() -> None:
    cylinder = make_object_context("c", "can", "cylinder", (0.03, 0.1), 0.3, "steel", 0.4)
    assert cylinder.dimensions == (0.03, 0.1)
    with pytest.raises(ValueError, match=r"expected 1 values for a sphere \(radius\)"):
        make_object_context("s", "ball", "sphere", (0.03, 0.1), 0.3, "rubber", 0.9)


@pytest.mark.parametrize(
    ("overrides", "match"),
    [
        ({"payload_per_arm_kg": 0.0}, r"payload_per_arm_kg: expected > 0 kg, got 0\.0"),
        ({"palm_size_m": (0.1, 0.09)}, r"palm_size_m: expected 3 numbers"),
        ({"palm_size_m": (0.1, -0.09, 0.02)}, r"palm_size_m\[1\]: expected > 0 m"),
        ({"min_span_m": 0.7}, r"min_span_m: expected < max_span_m = 0\.6, got 0\.7"),
        ({"squeeze_force_n": math.nan}, r"squeeze_force_n: expected a finite number"),
        ({"palm_friction": -0.5}, r"palm_friction: expected >= 0, got -0\.5"),
    ],
)
def test_bad_robot_names_the_field(overrides: dict[str, Any], match: str) -> None:
    with pytest.raises(ValueError, match=rf"RobotCapabilities\.{match}"):
        replace(PAPER_ROBOT, **overrides)


def test_robot_palm_width_is_the_middle_palm_size() -> None:
    robot = RobotCapabilities(
        7.0, (0.12, 0.09, 0.02), 0.6, 0.15, 40.0, 0.8, frozenset({EndEffector.FLAT_PALM})
    )
    assert robot.palm_width_m == 0.09

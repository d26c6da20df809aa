"""Hard constraints: friction, squeeze force, faces and the number of arms."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import pytest
from numpy.testing import assert_allclose

from affordances import (
    ReasonerConfig,
    combined_friction,
    required_squeeze_force,
    spare_grip_acceleration,
)
from affordances.context import RobotCapabilities
from affordances.object_geometry import FaceAxis, bounding_radius, grip_width, parallel_face_pairs
from affordances.physics import assess
from skills.turns import wrap_angle
from skills.vocabulary import AffordanceElement, Arm, GraspType
from tests.affordances.cases import (
    HANDED_ROBOT,
    ROBOT,
    heavy_box,
    open_bottle,
    parcel,
    small_box,
    tray,
)


def test_friction_combines_as_bullet_does() -> None:
    assert combined_friction(0.8, 0.8) == pytest.approx(0.64)
    assert combined_friction(5.0, 4.0) == 10.0


def test_required_squeeze_force() -> None:
    # 2 * mu * F = k * m * g
    assert_allclose(required_squeeze_force(12.0, 0.64, 1.5, 9.81), 137.953125)
    assert required_squeeze_force(1.0, 0.0, 1.5, 9.81) == math.inf


def test_spare_grip_acceleration_is_the_same_law_as_the_required_force() -> None:
    # Squeezing with the force that holds k times the weight leaves (k - 1) g to accelerate.
    box, g, k = parcel(), 9.81, 1.5
    mu = combined_friction(box.friction, ROBOT.palm_friction)
    need = required_squeeze_force(box.mass_kg, mu, k, g)
    assert_allclose(spare_grip_acceleration(box, ROBOT, need, g), (k - 1.0) * g, rtol=1e-12)
    # The paper's 1 kg parcel and palms, 15 N each: (2 * 0.64 * 15 - 9.81) / 1
    assert_allclose(spare_grip_acceleration(box, ROBOT, 15.0, g), 2.0 * 0.64 * 15.0 - 9.81)
    assert spare_grip_acceleration(box, ROBOT, 0.0, g) == pytest.approx(-g)


def test_face_pairs_per_shape() -> None:
    box = parallel_face_pairs(parcel())
    assert [(p.axis, p.separation_m, p.contact_height_m) for p in box] == [
        (FaceAxis.X, 0.2, 0.15),
        (FaceAxis.Y, 0.3, 0.15),
    ]
    (pair,) = parallel_face_pairs(open_bottle())
    assert (pair.axis, pair.separation_m, pair.contact_height_m) == (FaceAxis.DIAMETER, 0.07, 0.25)
    ball = parcel(shape="sphere", dimensions=(0.1,))
    assert parallel_face_pairs(ball) == ()
    assert parallel_face_pairs(parcel(shape="mesh")) == ()


def test_sizes() -> None:
    assert grip_width(parcel()) == 0.2
    assert grip_width(open_bottle()) == 0.07
    assert_allclose(bounding_radius(parcel()), 0.5 * math.sqrt(0.2**2 + 0.3**2 + 0.15**2))
    assert_allclose(bounding_radius(open_bottle()), math.hypot(0.035, 0.125))


def test_arms_needed_and_elements() -> None:
    config = ReasonerConfig()
    assert assess(small_box(), ROBOT, config).arms_needed == 1
    wide = assess(parcel(), ROBOT, config)
    assert wide.arms_needed == 2
    assert {AffordanceElement.WIDE, AffordanceElement.LIGHT} <= wide.elements
    assert AffordanceElement.GRASPABLE_LATERAL in wide.elements
    heavy = assess(heavy_box(), ROBOT, config)
    assert heavy.arms_needed == 2 and AffordanceElement.HEAVY in heavy.elements
    assert [o.grasp for o in heavy.options] == [GraspType.TWO_ARM_SUPPORT]
    assert assess(heavy_box(mass_kg=14.5), ROBOT, config).arms_needed == 0


def test_span_limits_the_squeeze() -> None:
    config = ReasonerConfig()
    # both face pairs 0.7 m apart: wider than the 0.6 m span
    big = assess(parcel(dimensions=(0.7, 0.7, 0.2)), ROBOT, config)
    assert [o.grasp for o in big.options] == [GraspType.TWO_ARM_SUPPORT]
    assert any("outside the palms' span 0.15..0.6 m" in line for line in big.because)


def test_lateral_palms_face_the_robot_sides() -> None:
    (lateral, _) = assess(parcel(yaw=math.pi / 2), ROBOT, ReasonerConfig()).options
    # rotated by 90 deg, the 0.20 m faces now face left and right
    assert lateral.grasp == GraspType.TWO_PALM_LATERAL
    left, right = lateral.palms
    assert_allclose(left, (0.4, 0.1, 0.075), atol=1e-12)
    assert_allclose(right, (0.4, -0.1, 0.075), atol=1e-12)


def test_tray_keeps_level_and_open_bottle_upright() -> None:
    config = ReasonerConfig()
    assert [s.action.value for s in assess(tray(), ROBOT, config).skills] == ["keep_level"]
    assert [s.action.value for s in assess(open_bottle(), ROBOT, config).skills] == ["keep_upright"]


def test_wrap_angle() -> None:
    wrapped = [wrap_angle(a) for a in (0.5, 3 * math.pi, -3.5)]
    assert_allclose(wrapped, [0.5, -math.pi, 2 * math.pi - 3.5])


def _turned(point: tuple[float, float, float], heading: float) -> tuple[float, float, float]:
    c, s = math.cos(heading), math.sin(heading)
    return (c * point[0] - s * point[1], s * point[0] + c * point[1], point[2])


@pytest.mark.parametrize("heading_deg", [90.0, 180.0, -45.0])
@pytest.mark.parametrize(
    ("make", "robot"),
    [(parcel, ROBOT), (small_box, HANDED_ROBOT), (tray, ROBOT)],
    ids=["lateral", "one_arm", "support"],
)
def test_a_robot_turned_with_its_world_reasons_the_same_grasps(
    heading_deg: float, make: Any, robot: RobotCapabilities
) -> None:
    """Left is the robot's left: the world turned about z, robot and all, turns the palms
    with it and changes nothing else (the arm on the object's side, the faces squeezed)."""
    heading = math.radians(heading_deg)
    # The object on the robot's right, its goal ahead on the left; turned 20 degrees.
    at, goal = (0.45, -0.12, 0.075), (0.5, 0.2, 0.075)
    before = assess(make(position=at, goals=[goal], yaw=0.35), robot, ReasonerConfig())
    turned = make(position=_turned(at, heading), goals=[_turned(goal, heading)], yaw=0.35 + heading)
    after = assess(turned, replace(robot, base_pose=(0.0, 0.0, heading)), ReasonerConfig())
    assert before.options and [o.grasp for o in after.options] == [o.grasp for o in before.options]
    for a, b in zip(after.options, before.options, strict=True):
        assert a.arms == b.arms
        assert_allclose(a.palms, [_turned(p, heading) for p in b.palms], atol=1e-12)
    assert after.elements == before.elements
    assert after.because == before.because


def test_a_robot_standing_elsewhere_picks_the_arm_on_its_own_side() -> None:
    """An object at world y > 0 is on the right of a robot standing further left."""
    box = small_box(position=(0.45, 0.1, 0.03), goals=[(0.45, 0.1, 0.03)])
    here = assess(box, HANDED_ROBOT, ReasonerConfig())
    moved = assess(box, replace(HANDED_ROBOT, base_pose=(0.0, 0.3, 0.0)), ReasonerConfig())
    one_arm = [o for o in here.options if o.grasp == GraspType.ONE_ARM_SIDE]
    assert one_arm and one_arm[0].arms == (Arm.LEFT,)
    (side,) = [o for o in moved.options if o.grasp == GraspType.ONE_ARM_SIDE]
    assert side.arms == (Arm.RIGHT,)
    assert side.palms[0][1] < 0.1  # on the object's face toward the robot's right

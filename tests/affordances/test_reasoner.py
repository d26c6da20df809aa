"""Decisions of the reasoner on the objects of the brief, and how rules shape them."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

import pytest
from numpy.testing import assert_allclose

from affordances import (
    AffordanceReasoner,
    ObjectContext,
    RobotCapabilities,
    SemanticAction,
    needs_both_arms,
    reason,
    rule_set,
)
from affordances.config import ReasonerConfig
from affordances.physics import assess
from skills.vocabulary import Action, EndEffector, GraspType, Space
from tests.affordances.cases import (
    HANDED_ROBOT,
    ROBOT,
    STRONG_ROBOT,
    heavy_box,
    number,
    open_bottle,
    parcel,
    small_box,
    tray,
    wine_glass,
)

ONE_ARM = (GraspType.ONE_ARM_SIDE, GraspType.ONE_ARM_TOP)


@dataclass(frozen=True)
class Case:
    """An object, a robot and the decision expected of the top-ranked action."""

    name: str
    make: Callable[[], ObjectContext]
    robot: RobotCapabilities
    grasps: tuple[GraspType, ...]
    required: tuple[Action, ...]
    forbidden: tuple[Action, ...] = ()


CASES = [
    Case(
        "paper parcel",
        parcel,
        ROBOT,
        (GraspType.TWO_PALM_LATERAL,),
        (Action.TRANSPORT, Action.HOLD_LATERAL),
        (Action.KEEP_UPRIGHT, Action.KEEP_LEVEL),
    ),
    Case(
        "heavy box, 40 N palms: friction cannot carry it",
        heavy_box,
        ROBOT,
        (GraspType.TWO_ARM_SUPPORT,),
        (Action.TRANSPORT, Action.HOLD_FORCE),
        (Action.HOLD_LATERAL,),
    ),
    Case(
        "heavy box, 150 N palms: squeeze possible, support from below still preferred",
        heavy_box,
        STRONG_ROBOT,
        (GraspType.TWO_ARM_SUPPORT,),
        (Action.TRANSPORT, Action.HOLD_FORCE),
    ),
    Case(
        "small light box, hands",
        small_box,
        HANDED_ROBOT,
        ONE_ARM,
        (Action.TRANSPORT,),
        (Action.HOLD_LATERAL,),
    ),
    Case(
        "full fragile glass, hands",
        wine_glass,
        HANDED_ROBOT,
        ONE_ARM,
        (Action.TRANSPORT, Action.KEEP_UPRIGHT),
        (Action.HOLD_LATERAL,),
    ),
    Case(
        "open bottle, hands",
        open_bottle,
        HANDED_ROBOT,
        (GraspType.ONE_ARM_SIDE,),
        (Action.TRANSPORT, Action.KEEP_UPRIGHT),
    ),
    Case(
        "tray with items",
        tray,
        ROBOT,
        (GraspType.TWO_ARM_SUPPORT,),
        (Action.TRANSPORT, Action.KEEP_LEVEL, Action.HOLD_FORCE),
        (Action.HOLD_LATERAL,),
    ),
]


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_top_action(case: Case) -> None:
    actions = reason(case.make(), case.robot)
    top = actions[0]
    assert top.grasp in case.grasps, top
    for action in case.required:
        assert action in top.actions, f"{action} missing from {top.actions}"
    for action in case.forbidden:
        assert action not in top.actions, f"{action} unexpected in {top.actions}"
    scores = [a.score for a in actions]
    assert scores == sorted(scores, reverse=True)


def _only(actions: tuple[SemanticAction, ...], grasp: GraspType) -> SemanticAction:
    return next(a for a in actions if a.grasp == grasp)


def test_paper_parcel_squeezes_its_y_faces_with_the_needed_force() -> None:
    top = reason(parcel(), ROBOT)[0]
    hold = top.skill(Action.HOLD_LATERAL)
    assert hold is not None and hold.space == Space.RELATIVE
    # F = k m g / (2 mu) = 1.5 * 1.0 * 9.81 / (2 * 0.8 * 0.8)
    assert_allclose(number(hold.params["required_force_n"]), 1.5 * 9.81 / 1.28, rtol=1e-12)
    assert_allclose(number(hold.params["span_m"]), 0.30)
    assert hold.params["squeeze_axis"] == "y"
    transport = top.skill(Action.TRANSPORT)
    assert transport is not None and transport.space == Space.ABSOLUTE
    assert transport.params["arms"] == ("left", "right")
    assert "hard: mass 1 kg <= payload 7 kg per arm" in top.because
    assert "rule parcel_lateral (+2): category parcel" in top.because


def test_heavy_box_reports_why_it_cannot_be_squeezed() -> None:
    top = reason(heavy_box(), ROBOT)[0]
    assert needs_both_arms(top)
    assert any("mass 12 kg > payload 7 kg per arm" in line for line in top.because)
    # 1.5 * 12 * 9.81 / (2 * 0.64) = 138 N per palm, more than the 40 N the palms have
    assert any("needs 138 N per palm > 40 N available" in line for line in top.because)
    assert all(a.grasp != GraspType.TWO_PALM_LATERAL for a in reason(heavy_box(), ROBOT))


def test_heavy_box_with_strong_palms_can_be_squeezed_with_the_needed_force() -> None:
    lateral = _only(reason(heavy_box(), STRONG_ROBOT), GraspType.TWO_PALM_LATERAL)
    hold = lateral.skill(Action.HOLD_LATERAL)
    assert hold is not None
    assert_allclose(number(hold.params["squeeze_force_n"]), 1.5 * 12.0 * 9.81 / 1.28, rtol=1e-12)
    assert any("needs 138 N per palm <= 150 N available" in line for line in lateral.because)
    # a heavy object held by friction also gets its squeeze force regulated (default rule)
    hold_force = lateral.skill(Action.HOLD_FORCE)
    assert hold_force is not None and hold_force.weight == 0.5


def test_too_heavy_for_both_arms_gives_none_with_reason() -> None:
    actions = reason(heavy_box(mass_kg=15.0), ROBOT)
    assert [a.grasp for a in actions] == [GraspType.NONE]
    assert actions[0].skills == ()
    assert any("cannot lift" in line for line in actions[0].because)


def test_small_box_uses_the_arm_on_its_side() -> None:
    right = reason(small_box(), HANDED_ROBOT)[0].skill(Action.TRANSPORT)
    left = reason(small_box(position=(0.4, 0.2, 0.03)), HANDED_ROBOT)[0].skill(Action.TRANSPORT)
    assert right is not None and right.params["arms"] == ("right",)
    assert left is not None and left.params["arms"] == ("left",)


def test_fragile_glass_is_never_squeezed_and_says_so() -> None:
    actions = reason(wine_glass(), HANDED_ROBOT)
    assert all(Action.HOLD_LATERAL not in a.actions for a in actions)
    assert "hard: no squeeze: fragile object" in actions[0].because
    assert "hard: full: keep upright" in actions[0].because
    transport = actions[0].skill(Action.TRANSPORT)
    assert transport is not None and transport.params["max_speed"] == pytest.approx(0.08)


def test_fragile_wide_box_is_supported_not_squeezed() -> None:
    actions = reason(parcel(fragility="fragile"), ROBOT)
    assert actions[0].grasp == GraspType.TWO_ARM_SUPPORT
    assert all(a.grasp != GraspType.TWO_PALM_LATERAL for a in actions)


def test_tray_is_too_thin_to_squeeze() -> None:
    top = reason(tray(), ROBOT)[0]
    assert any("0.03 m tall < 0.045 m" in line for line in top.because)


def test_sphere_has_no_parallel_faces() -> None:
    ball = parcel(name="ball", category="ball", shape="sphere", dimensions=(0.12,))
    actions = reason(ball, ROBOT)
    assert [a.grasp for a in actions] == [GraspType.TWO_ARM_SUPPORT]
    assert any("sphere has no parallel faces" in line for line in actions[0].because)


def test_goal_yaw_adds_rotate_z_with_the_signed_difference() -> None:
    top = reason(parcel(yaw=0.1, goal_yaw=0.6), ROBOT)[0]
    rotate = top.skill(Action.ROTATE_Z)
    assert rotate is not None and rotate.space == Space.ABSOLUTE
    assert_allclose(number(rotate.params["delta_yaw_rad"]), 0.5, atol=1e-12)
    assert reason(parcel(yaw=0.1, goal_yaw=0.11), ROBOT)[0].skill(Action.ROTATE_Z) is None


def test_skills_are_listed_absolute_first() -> None:
    top = reason(tray(goal_yaw=1.0), ROBOT)[0]
    spaces = [s.space for s in top.skills]
    assert spaces == sorted(spaces, key=lambda s: s != Space.ABSOLUTE)


def test_user_rule_file_adds_to_the_defaults(tmp_path: Path) -> None:
    path = tmp_path / "mine.yaml"
    path.write_text(
        "version: 1\n"
        "rules:\n"
        "  - name: parcels_from_below\n"
        "    when: {category: parcel, mass_kg: {lt: 5}}\n"
        "    effects:\n"
        "      - {grasp: two_arm_support, weight: 10}\n"
        "      - {param: max_speed, value: 0.05}\n"
        "      - {param: squeeze_force_n, value: 100}\n",
        encoding="utf-8",
    )
    reasoner = AffordanceReasoner(ROBOT, rules=rule_set([path]))
    actions = reasoner.rank(parcel())
    assert actions[0].grasp == GraspType.TWO_ARM_SUPPORT
    assert actions[0].score == pytest.approx(10.0)
    assert "rule parcels_from_below (+10): category parcel, mass_kg 1 < 5" in actions[0].because
    lateral = _only(actions, GraspType.TWO_PALM_LATERAL)
    assert lateral.score == pytest.approx(3.0)
    # the later rule wins over default_speed; the squeeze force is clamped to the 40 N available
    transport, hold = lateral.skill(Action.TRANSPORT), lateral.skill(Action.HOLD_LATERAL)
    assert transport is not None and transport.params["max_speed"] == pytest.approx(0.05)
    assert hold is not None and hold.params["squeeze_force_n"] == pytest.approx(40.0)
    assert any("clamped to 40 N" in line for line in lateral.because)


def test_user_rule_file_can_replace_the_defaults(tmp_path: Path) -> None:
    path = tmp_path / "only.yaml"
    path.write_text(
        "version: 1\nrules:\n  - name: side\n    effects: [{grasp: one_arm_side, weight: 1}]\n",
        encoding="utf-8",
    )
    actions = reason(parcel(), ROBOT, rules=rule_set([path], include_default=False))
    # no rule scores two-arm grasps, so they tie at 0 and keep the grasp order
    assert [a.grasp for a in actions] == [GraspType.TWO_PALM_LATERAL, GraspType.TWO_ARM_SUPPORT]
    assert all(a.score == 0.0 for a in actions)
    top = actions[0]
    assert top.actions == (Action.TRANSPORT, Action.HOLD_LATERAL)
    assert not any(line.startswith("rule ") for line in top.because)


def _box(width: float, length: float, height: float, mass: float, category: str) -> ObjectContext:
    return parcel(name="box", category=category, dimensions=(width, length, height), mass_kg=mass)


@pytest.mark.parametrize("category", ["parcel", "box"])
@pytest.mark.parametrize(
    ("size", "mass"),
    [((0.15, 0.25, 0.10), 0.5), ((0.16, 0.30, 0.15), 2.0)],
    ids=["0.15 m, 0.5 kg", "0.16 m, 2 kg"],
)
def test_flat_palms_squeeze_small_light_boxes_first(
    size: tuple[float, float, float], mass: float, category: str
) -> None:
    actions = reason(_box(*size, mass, category), ROBOT)
    assert [a.grasp for a in actions] == [GraspType.TWO_PALM_LATERAL, GraspType.TWO_ARM_SUPPORT]
    hold = actions[0].skill(Action.HOLD_LATERAL)
    assert hold is not None
    assert_allclose(number(hold.params["span_m"]), size[1])
    # F = k m g / (2 mu) with mu = 0.8 x 0.8
    assert_allclose(number(hold.params["squeeze_force_n"]), 1.5 * mass * 9.81 / 1.28, rtol=1e-12)
    assert "hard: no one_arm_top: needs a gripper, the robot has flat palms" in actions[0].because


def test_flat_palms_refuse_one_arm_grasps_with_the_reason() -> None:
    hard = assess(_box(0.15, 0.25, 0.10, 0.5, "box"), ROBOT, ReasonerConfig())
    assert [(r.grasp, r.why) for r in hard.refused] == [
        (GraspType.ONE_ARM_SIDE, "needs a gripper, the robot has flat palms"),
        (GraspType.ONE_ARM_TOP, "needs a gripper, the robot has flat palms"),
    ]


def test_nothing_the_palms_can_make_gives_none_naming_every_grasp() -> None:
    # a 6 cm cube is narrower than the palms' smallest span (0.15 m) and no gripper can close
    cube = small_box()
    actions = reason(cube, ROBOT)
    assert [a.grasp for a in actions] == [GraspType.NONE]
    assert assess(cube, ROBOT, ReasonerConfig()).no_grasp_reason() == (
        "two_palm_lateral: faces 0.06 m, 0.06 m apart, outside the palms' span 0.15..0.6 m; "
        "two_arm_support: 0.06 m across < the palms' smallest span 0.15 m; "
        "one_arm_side: needs a gripper, the robot has flat palms; "
        "one_arm_top: needs a gripper, the robot has flat palms"
    )


def test_a_gripper_alone_cannot_make_palm_grasps() -> None:
    grippers = replace(ROBOT, end_effectors=frozenset({EndEffector.GRIPPER}))
    hard = assess(parcel(), grippers, ReasonerConfig())
    assert hard.options == ()
    assert str(hard.refused[0]) == "two_palm_lateral: needs flat palms, the robot has grippers"
    # the parcel (0.20 m) is wider than one hand (0.18 m)
    assert str(hard.refused[2]) == (
        "one_arm_side: width 0.2 m > one-hand limit 0.18 m (2 x palm width 0.09 m)"
    )


def test_a_rule_file_still_reorders_the_palm_grasps(tmp_path: Path) -> None:
    rules = tmp_path / "support.yaml"
    rules.write_text(
        "version: 1\nrules:\n  - name: support_small\n"
        "    effects: [{grasp: two_arm_support, weight: 10}]\n"
    )
    actions = reason(_box(0.15, 0.25, 0.10, 0.5, "parcel"), ROBOT, rules=rule_set([rules]))
    assert [a.grasp for a in actions] == [GraspType.TWO_ARM_SUPPORT, GraspType.TWO_PALM_LATERAL]


def test_a_rule_file_vetoes_a_grasp_and_says_which_rule(tmp_path: Path) -> None:
    rules = tmp_path / "veto.yaml"
    rules.write_text(
        "version: 1\nrules:\n  - name: no_squeeze\n    when: {mass_kg: {lt: 1.0}}\n"
        "    effects: [{grasp: two_palm_lateral, veto: true}]\n"
    )
    box = _box(0.15, 0.25, 0.10, 0.5, "parcel")
    actions = reason(box, ROBOT, rules=rule_set([rules]))
    assert [a.grasp for a in actions] == [GraspType.TWO_ARM_SUPPORT]
    rules.write_text(
        "version: 1\nrules:\n  - name: no_palms\n    when: {mass_kg: {lt: 1.0}}\n"
        "    effects:\n      - {grasp: two_palm_lateral, veto: true}\n"
        "      - {grasp: two_arm_support, veto: true}\n"
    )
    [none] = reason(box, ROBOT, rules=rule_set([rules]))
    assert none.grasp == GraspType.NONE
    assert none.because[-2:] == (
        "rule no_palms vetoes two_palm_lateral: mass_kg 0.5 < 1",
        "rule no_palms vetoes two_arm_support: mass_kg 0.5 < 1",
    )

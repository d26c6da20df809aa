"""Semantic vocabulary shared by skills, the affordance reasoner and the planner.

A skill carries an :class:`Action` label (what it does) and the :class:`AffordanceElement`
labels it serves (which object properties make it relevant), after the paper's Fig. 4b.
"""

from __future__ import annotations

from enum import Enum, StrEnum


class Space(StrEnum):
    """The space a skill acts in (paper Sec. 2.2): the object's pose or each palm's pose in {O}."""

    ABSOLUTE = "absolute"
    RELATIVE = "relative"


class Arm(StrEnum):
    """One of the two arms; ``LEFT`` is on the robot's +y side."""

    LEFT = "left"
    RIGHT = "right"


#: Both arms, left then right: the order of every per-arm array.
ARMS: tuple[Arm, Arm] = (Arm.LEFT, Arm.RIGHT)


class Action(StrEnum):
    """What a skill does, as named in the library, the rule files and the trees."""

    APPROACH = "approach"
    GRASP_LATERAL = "grasp_lateral"
    TRANSPORT = "transport"
    ROTATE_Z = "rotate_z"
    ROTATE_GRASP_AXIS = "rotate_grasp_axis"
    AVOID_OBSTACLE = "avoid_obstacle"
    AVOID_LINKS = "avoid_links"
    HOLD_LATERAL = "hold_lateral"
    HOLD_FORCE = "hold_force"
    KEEP_UPRIGHT = "keep_upright"
    KEEP_LEVEL = "keep_level"
    LIMIT_REPULSION = "limit_repulsion"
    RELEASE = "release"
    RETREAT = "retreat"
    INSERT = "insert"


class AffordanceElement(StrEnum):
    """Object and scene facts a skill serves (context elements of the affordance map)."""

    GRASPABLE_LATERAL = "graspable_lateral"
    PARALLEL_FACES = "parallel_faces"
    HEAVY = "heavy"
    LIGHT = "light"
    WIDE = "wide"
    FRAGILE = "fragile"
    OPEN = "open"
    FULL = "full"
    HOT = "hot"
    CONTAINS_ITEMS = "contains_items"
    OBSTACLE_NEAR_PATH = "obstacle_near_path"
    OBSTACLE_NEAR_LINKS = "obstacle_near_links"
    ON_SURFACE = "on_surface"
    ROTATABLE = "rotatable"
    IN_FIXTURE = "in_fixture"


class GraspType(StrEnum):
    """The grasps the reasoner can choose (the leaf that closes one is planner.leaves.Grasp)."""

    TWO_PALM_LATERAL = "two_palm_lateral"
    TWO_ARM_SUPPORT = "two_arm_support"
    ONE_ARM_TOP = "one_arm_top"
    ONE_ARM_SIDE = "one_arm_side"
    NONE = "none"


class EndEffector(StrEnum):
    """What an arm ends in, which fixes the grasps it can make.

    ``FLAT_PALM`` is a rigid plate: it presses on a face or carries from below, and cannot
    close around anything, so it takes part in two-arm grasps only. ``GRIPPER`` closes
    fingers (or jaws) around an object, which the one-arm top and side grasps need.
    """

    FLAT_PALM = "flat_palm"
    GRIPPER = "gripper"


def _check_unique(enum_cls: type[Enum]) -> None:
    values = [m.value for m in enum_cls]
    if len(values) != len(set(values)):
        raise RuntimeError(f"{enum_cls.__name__}: duplicate values")


for _cls in (Space, Arm, Action, AffordanceElement, GraspType, EndEffector):
    _check_unique(_cls)

"""Stage 1: hard physics constraints on how the object can be held.

Which grasps the robot's end-effectors can make, and of those which the object's weight,
width and faces allow: a two-palm lateral squeeze on a pair of parallel faces
(:mod:`affordances.object_geometry`) that its friction lets carry the weight
(:mod:`affordances.grip_physics`), two palms under it, or one hand. Each grasp kept says why;
each refused one says why not, with the numbers.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from types import MappingProxyType

from affordances.actions import DEFAULT_SPACE, GRASP_ORDER, SkillSelection
from affordances.config import ReasonerConfig
from affordances.context import (
    Fragility,
    ObjectContext,
    ObjectState,
    RobotCapabilities,
    Shape,
    Vector3,
)
from affordances.grip_physics import palm_contact_friction, required_squeeze_force
from affordances.object_geometry import (
    FaceAxis,
    FacePair,
    axis_in_world,
    grip_width,
    horizontal_extents,
    object_height,
    parallel_face_pairs,
)
from skills.turns import wrap_angle
from skills.vocabulary import Action, AffordanceElement, Arm, EndEffector, GraspType

#: The end-effector each grasp needs on the arms it uses. Both two-arm grasps are palm grasps:
#: the lateral one presses two palms on opposite faces, the support one carries the object
#: on two upturned palms; neither closes anything around the object. The one-arm grasps hold
#: with one hand alone, so they need fingers or jaws that close around the object.
GRASP_END_EFFECTOR: Mapping[GraspType, EndEffector] = MappingProxyType(
    {
        GraspType.TWO_PALM_LATERAL: EndEffector.FLAT_PALM,
        GraspType.TWO_ARM_SUPPORT: EndEffector.FLAT_PALM,
        GraspType.ONE_ARM_SIDE: EndEffector.GRIPPER,
        GraspType.ONE_ARM_TOP: EndEffector.GRIPPER,
    }
)

_NEEDS_WORDS = {EndEffector.FLAT_PALM: "flat palms", EndEffector.GRIPPER: "a gripper"}

_STATE_ELEMENTS = {
    ObjectState.OPEN: AffordanceElement.OPEN,
    ObjectState.FULL: AffordanceElement.FULL,
    ObjectState.HOT: AffordanceElement.HOT,
    ObjectState.CONTAINS_ITEMS: AffordanceElement.CONTAINS_ITEMS,
}


@dataclass(frozen=True)
class GraspOption:
    """A grasp that passes the hard constraints.

    Attributes
    ----------
    grasp : GraspType
        The grasp type.
    arms : tuple of Arm
        Arms used, in :class:`~skills.vocabulary.Arm` order.
    palms : tuple of tuple of float, each shape (3,)
        Palm centre of each arm (same order as ``arms``) in {W} at the start pose, metres.
    skills : tuple of SkillSelection
        Skills the grasp needs physically (transport, grasp maintenance).
    because : tuple of str
        Reasons specific to this grasp.
    """

    grasp: GraspType
    arms: tuple[Arm, ...]
    palms: tuple[Vector3, ...]
    skills: tuple[SkillSelection, ...]
    because: tuple[str, ...]


@dataclass(frozen=True)
class Refusal:
    """A grasp the hard stage refused, and why in a few words with the numbers.

    Attributes
    ----------
    grasp : GraspType
        The refused grasp.
    why : str
        E.g. ``needs a gripper, the robot has flat palms``.
    """

    grasp: GraspType
    why: str

    def __str__(self) -> str:
        return f"{self.grasp.value}: {self.why}"


@dataclass(frozen=True)
class HardAssessment:
    """Everything stage 1 decides about an object.

    Attributes
    ----------
    arms_needed : int
        Arms the object's weight and width call for: 2 when it is heavier than one arm's
        payload or wider than one hand, else 1; 0 when even both arms cannot lift it. Which
        grasps the robot can make is ``options``.
    elements : frozenset of AffordanceElement
        Object facts the rules can match.
    options : tuple of GraspOption
        Grasps the robot's end-effectors can make that pass the physics, in
        :data:`~affordances.actions.GRASP_ORDER`.
    skills : tuple of SkillSelection
        Skills every grasp needs (orientation constraints, ``rotate_z``).
    because : tuple of str
        Reasons shared by every grasp, including why other grasps were rejected.
    refused : tuple of Refusal
        Every grasp not in ``options``, in :data:`~affordances.actions.GRASP_ORDER`.
    """

    arms_needed: int
    elements: frozenset[AffordanceElement]
    options: tuple[GraspOption, ...]
    skills: tuple[SkillSelection, ...]
    because: tuple[str, ...]
    refused: tuple[Refusal, ...] = ()

    def no_grasp_reason(self) -> str:
        """Why no grasp is feasible, one clause per grasp: ``two_palm_lateral: ...; ...``."""
        return "; ".join(str(r) for r in self.refused)


def _offset(position: Vector3, direction: Vector3, distance: float) -> Vector3:
    return (
        position[0] + distance * direction[0],
        position[1] + distance * direction[1],
        position[2] + distance * direction[2],
    )


def _left_right(
    position: Vector3, direction: Vector3, half_span: float, near_arm: Arm
) -> tuple[Vector3, Vector3]:
    """Palms at +-half_span along ``direction`` as (left, right); the left one is on the +y side.

    When both palms have the same y (faces seen front and back), ``near_arm`` takes the palm
    nearer the robot (smaller x), so a mirrored scene gives the mirrored assignment.
    """
    a = _offset(position, direction, half_span)
    b = _offset(position, direction, -half_span)
    if a[1] != b[1]:
        return (a, b) if a[1] > b[1] else (b, a)
    near, far = (a, b) if a[0] <= b[0] else (b, a)
    return (near, far) if near_arm == Arm.LEFT else (far, near)


def _fmt(value: float) -> str:
    return f"{value:.3g}" if math.isfinite(value) else "inf"


def _best_lateral_pair(pairs: Sequence[FacePair], yaw: float) -> FacePair:
    # Palms come from the robot's left and right, so squeeze the faces whose normal is
    # closest to world y; then the narrower span (less reach); then x before y.
    def key(pair: FacePair) -> tuple[float, float, str]:
        alignment = abs(axis_in_world(pair.axis, yaw)[1])
        return (-round(alignment, 9), pair.separation_m, pair.axis.value)

    return min(pairs, key=key)


def assess_lateral(
    context: ObjectContext, robot: RobotCapabilities, config: ReasonerConfig
) -> tuple[GraspOption | None, tuple[str, ...]]:
    """Check the two-palm lateral squeeze.

    Palms hold anything whose faces lie between their smallest and largest span, are tall
    enough to lie flat on, and that friction can carry: neither a light nor a narrow object
    is refused for being light or narrow.

    Returns
    -------
    option : GraspOption or None
        The grasp with its ``hold_lateral`` skill, or ``None`` if a constraint fails.
    because : tuple of str
        The reasons, with the numbers.
    """
    option, because, _ = _lateral(context, robot, config)
    return option, because


def _lateral(
    context: ObjectContext, robot: RobotCapabilities, config: ReasonerConfig
) -> tuple[GraspOption | None, tuple[str, ...], str]:
    """:func:`assess_lateral` and, when it refuses, why in a few words (else ``""``)."""
    if context.fragility == Fragility.FRAGILE:
        return None, ("hard: no squeeze: fragile object",), "fragile object"
    pairs = parallel_face_pairs(context)
    if not pairs:
        why = (
            "a sphere has no parallel faces"
            if context.shape == Shape.SPHERE
            else "no two sides of its hull a palm can press, across x or y"
        )
        return None, (f"hard: no lateral squeeze: {why}",), why
    min_height = config.min_contact_height_factor * robot.palm_width_m
    span = f"{_fmt(robot.min_span_m)}..{_fmt(robot.max_span_m)} m"
    in_span = [p for p in pairs if robot.min_span_m <= p.separation_m <= robot.max_span_m]
    if not in_span:
        seps = ", ".join(f"{_fmt(p.separation_m)} m" for p in pairs)
        why = f"faces {seps} apart, outside the palms' span {span}"
        return None, (f"hard: no lateral squeeze: {why}",), why
    tall = [p for p in in_span if p.contact_height_m >= min_height]
    if not tall:
        why = (
            f"faces {_fmt(in_span[0].contact_height_m)} m tall "
            f"< {_fmt(min_height)} m for a flat palm contact"
        )
        return None, (f"hard: no lateral squeeze: {why}",), why
    pair = _best_lateral_pair(tall, context.yaw)
    mu = palm_contact_friction(context, robot)
    need = required_squeeze_force(context.mass_kg, mu, config.safety_factor, config.gravity)
    friction_note = (
        f"mu = {_fmt(context.friction)} x {_fmt(robot.palm_friction)} = {_fmt(mu)}, "
        f"k = {_fmt(config.safety_factor)}, m = {_fmt(context.mass_kg)} kg"
    )
    if need > robot.squeeze_force_n:
        why = (
            f"needs {_fmt(need)} N per palm > {_fmt(robot.squeeze_force_n)} N available "
            f"({friction_note})"
        )
        return None, (f"hard: no lateral squeeze: {why}",), why
    direction = axis_in_world(pair.axis, context.yaw)
    left, right = _left_right(
        context.position, direction, 0.5 * pair.separation_m, choose_arm(context)
    )
    hold = SkillSelection(
        Action.HOLD_LATERAL,
        DEFAULT_SPACE[Action.HOLD_LATERAL],
        1.0,
        {
            "squeeze_force_n": need,
            "required_force_n": need,
            "span_m": pair.separation_m,
            "squeeze_axis": pair.axis.value,
        },
    )
    because = (
        f"hard: faces {_fmt(pair.separation_m)} m apart along {pair.axis.value}, "
        f"within the palms' span {span}",
        f"hard: squeeze needs {_fmt(need)} N per palm <= {_fmt(robot.squeeze_force_n)} N "
        f"available ({friction_note})",
    )
    option = GraspOption(
        GraspType.TWO_PALM_LATERAL,
        (Arm.LEFT, Arm.RIGHT),
        (left, right),
        (_transport((Arm.LEFT, Arm.RIGHT)), hold),
        because,
    )
    return option, because, ""


def assess_support(
    context: ObjectContext, robot: RobotCapabilities, config: ReasonerConfig
) -> tuple[GraspOption | None, tuple[str, ...]]:
    """Check holding the object from below with both palms, spread left and right.

    Returns
    -------
    option : GraspOption or None
        The grasp with its ``hold_force`` skill, or ``None`` if the object is too narrow.
    because : tuple of str
        The reasons, with the numbers.
    """
    option, because, _ = _support(context, robot, config)
    return option, because


def _support(
    context: ObjectContext, robot: RobotCapabilities, config: ReasonerConfig
) -> tuple[GraspOption | None, tuple[str, ...], str]:
    """:func:`assess_support` and, when it refuses, why in a few words (else ``""``)."""
    ex, ey = horizontal_extents(context)
    if context.shape in (Shape.BOX, Shape.MESH):
        along_x = abs(math.sin(context.yaw)) > abs(math.cos(context.yaw)) + 1e-9
        axis, extent = (FaceAxis.X, ex) if along_x else (FaceAxis.Y, ey)
    else:
        axis, extent = FaceAxis.DIAMETER, ex
    if extent < robot.min_span_m:
        why = f"{_fmt(extent)} m across < the palms' smallest span {_fmt(robot.min_span_m)} m"
        return None, (f"hard: no two-arm support: {why}",), why
    span = min(max(extent - robot.palm_width_m, robot.min_span_m), robot.max_span_m)
    bottom = (
        context.position[0],
        context.position[1],
        context.position[2] - 0.5 * object_height(context),
    )
    direction = axis_in_world(axis, context.yaw)
    left, right = _left_right(bottom, direction, 0.5 * span, choose_arm(context))
    load = 0.5 * context.mass_kg * config.gravity
    hold = SkillSelection(
        Action.HOLD_FORCE,
        DEFAULT_SPACE[Action.HOLD_FORCE],
        1.0,
        {"load_per_palm_n": load, "span_m": span},
    )
    because = (
        f"hard: two palms {_fmt(span)} m apart under the object ({_fmt(extent)} m across), "
        f"{_fmt(load)} N each",
    )
    option = GraspOption(
        GraspType.TWO_ARM_SUPPORT,
        (Arm.LEFT, Arm.RIGHT),
        (left, right),
        (_transport((Arm.LEFT, Arm.RIGHT)), hold),
        because,
    )
    return option, because, ""


def choose_arm(context: ObjectContext) -> Arm:
    """The arm on the object's side (left is +y); at y = 0 the goals' side, then the right."""
    y = context.position[1]
    if y == 0.0 and context.goals:
        y = sum(g[1] for g in context.goals) / len(context.goals)
    return Arm.LEFT if y > 0.0 else Arm.RIGHT


def one_arm_options(context: ObjectContext) -> tuple[GraspOption, ...]:
    """Side and top grasps with the arm on the object's side."""
    arm = choose_arm(context)
    ex, ey = horizontal_extents(context)
    c, s = abs(math.cos(context.yaw)), abs(math.sin(context.yaw))
    half_y = 0.5 * (c * ey + s * ex) if context.shape in (Shape.BOX, Shape.MESH) else 0.5 * ey
    sign = 1.0 if arm == Arm.LEFT else -1.0
    x, y, z = context.position
    side = (x, y + sign * half_y, z)
    top = (x, y, z + 0.5 * object_height(context))
    note = f"hard: {arm.value} arm, on the object's side"
    return (
        GraspOption(GraspType.ONE_ARM_SIDE, (arm,), (side,), (_transport((arm,)),), (note,)),
        GraspOption(GraspType.ONE_ARM_TOP, (arm,), (top,), (_transport((arm,)),), (note,)),
    )


def _transport(arms: tuple[Arm, ...]) -> SkillSelection:
    return SkillSelection(
        Action.TRANSPORT,
        DEFAULT_SPACE[Action.TRANSPORT],
        1.0,
        {"arms": tuple(a.value for a in arms)},
    )


def _common_skills(
    context: ObjectContext, config: ReasonerConfig
) -> tuple[list[SkillSelection], list[str]]:
    skills: list[SkillSelection] = []
    because: list[str] = []
    upright = sorted(s.value for s in context.state & {ObjectState.OPEN, ObjectState.FULL})
    if upright:
        skills.append(SkillSelection(Action.KEEP_UPRIGHT, DEFAULT_SPACE[Action.KEEP_UPRIGHT]))
        because.append(f"hard: {' and '.join(upright)}: keep upright")
    if ObjectState.CONTAINS_ITEMS in context.state:
        skills.append(SkillSelection(Action.KEEP_LEVEL, DEFAULT_SPACE[Action.KEEP_LEVEL]))
        because.append("hard: contains items: keep level")
    # Each move turns from the yaw the last one left: the largest of those turns decides.
    goal_yaws = context.goal_yaws or ((context.goal_yaw,) if context.goal_yaw is not None else ())
    turns = [wrap_angle(b - a) for a, b in zip((context.yaw, *goal_yaws), goal_yaws, strict=False)]
    if turns:
        delta = max(turns, key=abs)
        if abs(delta) > config.yaw_tolerance_rad:
            skills.append(
                SkillSelection(
                    Action.ROTATE_Z, DEFAULT_SPACE[Action.ROTATE_Z], 1.0, {"delta_yaw_rad": delta}
                )
            )
            because.append(
                f"hard: goal yaw differs by {_fmt(math.degrees(delta))} deg: rotate about z"
            )
    # A goal that turns the object about the grasp axis (on its side) needs the turn learnt
    # for it: the largest turn of any move decides, as for yaw.
    flips = [a for a in context.goal_grasp_turns if abs(a) > config.yaw_tolerance_rad]
    if flips:
        flip = max(flips, key=abs)
        skills.append(
            SkillSelection(
                Action.ROTATE_GRASP_AXIS,
                DEFAULT_SPACE[Action.ROTATE_GRASP_AXIS],
                1.0,
                {"delta_grasp_axis_rad": flip},
            )
        )
        because.append(
            f"hard: goal turns the object {_fmt(math.degrees(flip))} deg about the grasp axis: "
            "rotate about it"
        )
    # A goal inside a fixture's walls is reached by lowering into it under compliance (the
    # learnt insertion), not by the carry's set-down.
    fixtures = sorted({f for f in context.goal_fixtures if f})
    if fixtures:
        skills.append(SkillSelection(Action.INSERT, DEFAULT_SPACE[Action.INSERT]))
        because.append(f"hard: goal in fixture {', '.join(map(repr, fixtures))}: insert into it")
    return skills, because


def _end_effector_refusals(robot: RobotCapabilities) -> dict[GraspType, str]:
    """The grasps the robot's end-effectors cannot make, and why."""
    has = robot.describe_end_effectors()
    return {
        grasp: f"needs {_NEEDS_WORDS[needed]}, the robot has {has}"
        for grasp, needed in GRASP_END_EFFECTOR.items()
        if needed not in robot.end_effectors
    }


def in_robot_frame(context: ObjectContext, base_pose: Vector3) -> ObjectContext:
    """``context`` seen from a robot whose frame stands at ``base_pose`` ``(x, y, heading)``
    in {W}: positions (the object's, its goals', the obstacles') and yaws in the robot's
    frame (:attr:`RobotCapabilities.base_pose`)."""
    x0, y0, heading = base_pose
    c, s = math.cos(heading), math.sin(heading)

    def local(p: Vector3) -> Vector3:
        dx, dy = p[0] - x0, p[1] - y0
        return (c * dx + s * dy, -s * dx + c * dy, p[2])

    return replace(
        context,
        position=local(context.position),
        yaw=context.yaw - heading,
        obstacles=tuple(replace(o, position=local(o.position)) for o in context.obstacles),
        goals=tuple(local(g) for g in context.goals),
        goal_yaw=None if context.goal_yaw is None else context.goal_yaw - heading,
        goal_yaws=tuple(y - heading for y in context.goal_yaws),
    )


def _to_world(point: Vector3, base_pose: Vector3) -> Vector3:
    """A point of the robot's frame at ``base_pose`` in {W} (:func:`in_robot_frame`'s inverse)."""
    x0, y0, heading = base_pose
    c, s = math.cos(heading), math.sin(heading)
    return (x0 + c * point[0] - s * point[1], y0 + s * point[0] + c * point[1], point[2])


def assess(
    context: ObjectContext, robot: RobotCapabilities, config: ReasonerConfig
) -> HardAssessment:
    """Apply the hard constraints: which grasps the robot can make, and which constraints.

    A grasp is offered when the robot's end-effectors can make it
    (:data:`GRASP_END_EFFECTOR`) and the physics allows it: two palms need the object's faces
    within their span and friction to carry it (:func:`assess_lateral`), or the object wide
    enough to rest on both (:func:`assess_support`); one arm needs the object within its
    payload and one hand's width. Every other grasp is in ``refused`` with its reason.

    Parameters
    ----------
    context : ObjectContext
        The object.
    robot : RobotCapabilities
        The robot.
    config : ReasonerConfig
        Safety factor, gravity and the one-hand limit.

    Returns
    -------
    HardAssessment
        Feasible grasps and the reasons; the options' palms in {W}.
    """
    if any(robot.base_pose):
        # Left and right, near and far, are the robot's: reason in its frame.
        pose = robot.base_pose
        hard = assess(
            in_robot_frame(context, pose), replace(robot, base_pose=(0.0, 0.0, 0.0)), config
        )
        options = tuple(
            replace(o, palms=tuple(_to_world(p, pose) for p in o.palms)) for o in hard.options
        )
        return replace(hard, options=options)
    mass, payload = context.mass_kg, robot.payload_per_arm_kg
    width = grip_width(context)
    hand_limit = config.one_hand_width_factor * robot.palm_width_m
    heavy, wide = mass > payload, width > hand_limit
    because: list[str] = []
    if heavy:
        because.append(
            f"hard: mass {_fmt(mass)} kg > payload {_fmt(payload)} kg per arm: both arms"
        )
    else:
        because.append(f"hard: mass {_fmt(mass)} kg <= payload {_fmt(payload)} kg per arm")
    width_note = (
        f"{_fmt(width)} m {{}} one-hand limit {_fmt(hand_limit)} m "
        f"({_fmt(config.one_hand_width_factor)} x palm width {_fmt(robot.palm_width_m)} m)"
    )
    if wide:
        because.append(f"hard: width {width_note.format('>')}: both arms")
    else:
        because.append(f"hard: width {width_note.format('<=')}")

    elements = {AffordanceElement.HEAVY if heavy else AffordanceElement.LIGHT}
    if wide:
        elements.add(AffordanceElement.WIDE)
    if parallel_face_pairs(context):
        elements.add(AffordanceElement.PARALLEL_FACES)
    if context.fragility == Fragility.FRAGILE:
        elements.add(AffordanceElement.FRAGILE)
    elements.update(_STATE_ELEMENTS[s] for s in context.state if s in _STATE_ELEMENTS)
    if any(context.goal_fixtures):
        elements.add(AffordanceElement.IN_FIXTURE)

    lateral, lateral_notes, lateral_why = _lateral(context, robot, config)
    if lateral is not None:
        elements.add(AffordanceElement.GRASPABLE_LATERAL)
    skills, common_notes = _common_skills(context, config)
    arms_needed = 2 if heavy or wide else 1

    refused = _end_effector_refusals(robot)
    if mass > 2.0 * payload:
        cannot = f"mass {_fmt(mass)} kg > both arms' payload {_fmt(2.0 * payload)} kg"
        because.append(f"hard: {cannot}: cannot lift")
        refused = {g: refused.get(g, cannot) for g in GRASP_END_EFFECTOR}
        return HardAssessment(
            0, frozenset(elements), (), tuple(skills), tuple(because), _refusals(refused)
        )

    candidates: list[GraspOption] = []
    if GraspType.TWO_PALM_LATERAL not in refused:
        if lateral is None:
            because.extend(lateral_notes)
            refused[GraspType.TWO_PALM_LATERAL] = lateral_why
        else:
            candidates.append(lateral)
    if GraspType.TWO_ARM_SUPPORT not in refused:
        support, support_notes, support_why = _support(context, robot, config)
        if support is None:
            because.extend(support_notes)
            refused[GraspType.TWO_ARM_SUPPORT] = support_why
        else:
            candidates.append(support)
    one_arm = [g for g in (GraspType.ONE_ARM_SIDE, GraspType.ONE_ARM_TOP) if g not in refused]
    if one_arm and (heavy or wide):
        why = (
            f"mass {_fmt(mass)} kg > payload {_fmt(payload)} kg per arm"
            if heavy
            else f"width {width_note.format('>')}"
        )
        refused.update({g: why for g in one_arm})
    elif one_arm:
        because.append("hard: one arm suffices")
        candidates.extend(o for o in one_arm_options(context) if o.grasp in one_arm)
    for grasp, why in refused.items():
        if GRASP_END_EFFECTOR[grasp] not in robot.end_effectors or grasp in one_arm:
            because.append(f"hard: no {grasp.value}: {why}")
    because.extend(common_notes)
    order = {g: i for i, g in enumerate(GRASP_ORDER)}
    options = tuple(sorted(candidates, key=lambda o: order[o.grasp]))
    return HardAssessment(
        arms_needed, frozenset(elements), options, tuple(skills), tuple(because), _refusals(refused)
    )


def _refusals(refused: dict[GraspType, str]) -> tuple[Refusal, ...]:
    order = {g: i for i, g in enumerate(GRASP_ORDER)}
    return tuple(Refusal(g, refused[g]) for g in sorted(refused, key=lambda g: order[g]))

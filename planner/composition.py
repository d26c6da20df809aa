"""From the reasoner's plan to a running composition: which coupling terms, which weights.

The affordance reasoner names skills by label with a weight and parameters
(:class:`affordances.SkillSelection`); the library holds the learnt skills with those labels;
the world supplies what only it knows (obstacles, distances, gravity). This module puts
them together into a :class:`skills.composer.DualArmComposer` for one move, and into the
relative-only compositions that close and open the grasp. Which faces the palms hold is
:mod:`planner.grips`'s, which learnt skill carries the move :mod:`planner.skill_choice`'s,
the closed chain a skill starts from :mod:`planner.held_states`', and each selected skill's
coupling terms :mod:`planner.skill_terms`'.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from affordances import SemanticAction, spare_grip_acceleration
from affordances.context import Shape
from planner.fixture_moves import hover_move
from planner.held_states import held_lateral_geometry, on_measured_object
from planner.port import Move, ObjectSensing, Pose, WorldPort
from planner.skill_choice import (
    carried_skill,
    level_carry_duration,
    level_carry_key,
    transport_skill,
)
from planner.skill_terms import (
    absolute_terms,
    held_spheres,
    hold_terms,
    selection_param,
)
from skills import quaternion as quat
from skills.composer import DualArmComposer, DualArmState
from skills.couplings import Saturated
from skills.couplings.limits import WorkspaceRepulsion
from skills.couplings.potential import PotentialFieldAvoidance
from skills.couplings.steering import ObstacleSteering
from skills.couplings.term import CouplingTerm
from skills.flip import vertical_half_extent
from skills.library import SkillLibrary
from skills.vocabulary import Action, Arm

#: Shortest move duration, s (the demonstrations last about 2 s).
MIN_TAU_S = 2.0
#: Share of the grip's spare force left to avoidance: the learnt motion and the attractor
#: accelerate the object too, and a box slips in two palms before friction is exhausted.
GRIP_MARGIN = 4.0
#: Avoidance fades out below this phase (about 65 % of tau): the attractor finishes the move.
AVOID_FADE_PHASE = 0.05
#: Linear acceleration avoidance may ask whatever the grip could take, m/s^2: a light object
#: in a strong grip could follow more, but the arms carrying it could not track it.
MAX_AVOID_LINEAR = 3.0
#: Angular acceleration avoidance may ask of a two-palm grip, rad/s^2: turning the object
#: turns the palms, whose orientation springs are soft, and tilted palms lose their flat contact.
MAX_AVOID_ANGULAR = 0.2


@dataclass(frozen=True)
class TransportSettings:
    """Numbers a transport uses that are not skill parameters.

    Attributes
    ----------
    max_speed : float
        Peak speed the move's duration is chosen for, m/s.
    lift_m : float
        Height the demonstrated pick-and-place clears, m (counted in the path length).
    """

    max_speed: float = 0.25
    lift_m: float = 0.12


def grip_acceleration_limit(world: WorldPort, name: str, squeeze_force_n: float) -> float:
    """Acceleration (m/s^2) avoidance may add: the grip's spare, over ``GRIP_MARGIN``.

    The spare is what two palms squeezing with ``squeeze_force_n`` N each can accelerate the
    object by once they carry its weight (:func:`affordances.spare_grip_acceleration`, from the
    object's and the robot's declared friction and the world's gravity).
    """
    spare = spare_grip_acceleration(
        world.object_context(name), world.robot_capabilities(), squeeze_force_n, world.gravity()
    )
    return min(max(spare / GRIP_MARGIN, 0.5), MAX_AVOID_LINEAR)


def saturate_avoidance(
    terms: list[tuple[CouplingTerm, float]], max_linear: float
) -> list[tuple[CouplingTerm, float]]:
    """Group the avoidance terms, and the workspace limits, each under one saturation.

    Both grow without bound near what they avoid; the grip bounds what the object can follow,
    and a barrier stiffer than the control rate can integrate would only make it chatter. The
    limits get their own group so that avoidance cannot cancel the table's floor. Learnt
    skills stay as they are.
    """
    avoid_types = (ObstacleSteering, PotentialFieldAvoidance)
    avoid = [(t, w) for t, w in terms if isinstance(t, avoid_types)]
    limits = [(t, w) for t, w in terms if isinstance(t, WorkspaceRepulsion)]
    rest = [(t, w) for t, w in terms if not isinstance(t, (*avoid_types, WorkspaceRepulsion))]
    out = list(rest)
    if avoid:
        out.append((Saturated(avoid, max_linear, MAX_AVOID_ANGULAR, AVOID_FADE_PHASE), 1.0))
    if limits:
        out.append((Saturated(limits, max_linear, MAX_AVOID_ANGULAR), 1.0))
    return out


def move_duration(start: np.ndarray, goal: np.ndarray, settings: TransportSettings) -> float:
    """``tau`` for a move: the path (up, across, down) at ``max_speed`` peak, at least 2 s.

    A minimum-jerk profile peaks at 1.875 times its mean speed, hence the factor.
    """
    path = float(np.linalg.norm(goal - start)) + 2.0 * settings.lift_m
    return max(MIN_TAU_S, 1.875 * path / settings.max_speed)


def reweight(
    plan: SemanticAction, avoid_gain: float = 1.0, transport_weight: float = 1.0
) -> SemanticAction:
    """The plan with its avoidance weights times ``avoid_gain`` and its transport weight times
    ``transport_weight`` (a lower carry: the learnt lift shrinks with the forcing's weight)."""
    if avoid_gain == 1.0 and transport_weight == 1.0:
        return plan
    avoid = (Action.AVOID_OBSTACLE, Action.AVOID_LINKS)
    skills = tuple(
        replace(s, weight=s.weight * avoid_gain)
        if s.action in avoid
        else replace(s, weight=s.weight * transport_weight)
        if s.action is Action.TRANSPORT
        else s
        for s in plan.skills
    )
    return replace(plan, skills=skills)


def static_composition(
    state: DualArmState,
    relative: Mapping[Arm, list[tuple[CouplingTerm, float]]],
    tau: float,
) -> DualArmComposer:
    """Relative skills only: the object's pose is held where it is."""
    obj = state.object
    return DualArmComposer.start(state, obj.position, obj.orientation, tau, relative=relative)


def transport_composition(
    plan: SemanticAction,
    library: SkillLibrary,
    world: WorldPort,
    name: str,
    move: Move,
    state: DualArmState,
    squeeze_force_n: float,
    settings: TransportSettings | None = None,
    avoid_gain: float = 1.0,
    transport_weight: float = 1.0,
    skill: str | None = None,
    hold_gain: float = 1.0,
) -> DualArmComposer:
    """The simultaneous composition of one move, starting from the handed-over state.

    ``squeeze_force_n`` is the grip's force per palm, N, which bounds what avoidance may ask.
    ``avoid_gain`` multiplies the weights of obstacle steering and link-level avoidance;
    ``transport_weight`` multiplies the learnt pick-and-place's (a lower carry). A tree tries
    such variants when a predicted path is not clear. ``hold_gain`` multiplies grasp
    maintenance's (0 carries without it: the palms' relative references stay as handed over,
    for an ablation). ``skill`` names the learnt motion to
    carry the object with (a port's choice), else the move's ``skill``, else the plan's
    transport skill (:func:`transport_skill`; SkillChoiceError if the library has none so
    called).
    """
    state = on_measured_object(world, name, state)
    s = settings or TransportSettings()
    sel = plan.skill(Action.TRANSPORT)
    if sel is not None:
        s = TransportSettings(selection_param(sel, "max_speed", s.max_speed), s.lift_m)
    tau = move_duration(state.object.position, move.goal.position, s)
    key = skill or move.skill or level_carry_key(plan, library)
    if plan.skill(Action.KEEP_LEVEL) is not None:
        tau = max(tau, level_carry_duration(world, name, move))
    geometry = held_lateral_geometry(world, name, state)
    points = box_points(world.object_extents(name))
    carry = transport_skill(library, key) if key else None
    extents = world.object_extents(name)
    rest = min(
        float(vertical_half_extent(extents, state.object.orientation)),
        float(vertical_half_extent(extents, move.goal.orientation)),
    )
    terms = absolute_terms(
        reweight(plan, avoid_gain, transport_weight),
        library,
        world,
        name,
        points,
        carry,
        rest,
        held_spheres(world, state),
    )
    absolute = saturate_avoidance(terms, grip_acceleration_limit(world, name, squeeze_force_n))
    # The handed-over palm poses are the squeezed grip already: hold them as they are.
    relative = hold_terms(plan, library, geometry, 0.0, hold_gain)
    return DualArmComposer.start(
        state,
        move.goal.position,
        move.goal.orientation,
        tau,
        absolute=absolute,
        relative=relative,
    )


@dataclass(frozen=True, eq=False)
class MovePlan:
    """One move composed: what PathClear checked and hands to Transport to run.

    Attributes
    ----------
    object : str
        The held object.
    index : int
        Index of the task's move, from 0.
    move : Move
        The move: its goal and the obstacles present (active since it was composed).
    squeeze_force_n : float
        The grip's force per palm the composition was bounded by, N.
    avoid_gain, transport_weight : float
        The variant of the plan composed (see :func:`transport_composition`).
    hold_gain : float
        The grasp maintenance's gain it was composed with (see :func:`transport_composition`).
    from_state : DualArmState
        The handed-over state it was composed from.
    composer : DualArmComposer
        The composition as built; never stepped itself (use :meth:`fresh`).
    requested_skill : str or None
        The skill a port asked for by name (None: the move's or the plan's).
    skill : str or None
        The learnt transport skill composed (:func:`carried_skill`), None without one.
    above_fixture : bool
        Composed to the hover goal above a fixture move's seated goal
        (:func:`planner.fixture_moves.hover_goal`).
    start : DualArmState
        The composer's first state (``from_state`` with the phase restarted).
    """

    object: str
    index: int
    move: Move
    squeeze_force_n: float
    avoid_gain: float
    transport_weight: float
    from_state: DualArmState
    composer: DualArmComposer
    requested_skill: str | None = None
    skill: str | None = None
    above_fixture: bool = False
    hold_gain: float = 1.0
    start: DualArmState = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "start", self.composer.state)

    def fresh(self) -> DualArmComposer:
        """The composition at its first state, to roll out or run (the terms are shared)."""
        return replace(self.composer, state=self.start)


def squeeze_force(plan: SemanticAction | None, default: float, rated: float = math.inf) -> float:
    """The squeeze force per palm a grasp reaches and a move is composed with, N: the larger of
    the plan's hold-skill force and ``default``, never above the robot's ``rated`` steady
    squeeze (the reasoner refuses an object whose own need exceeds it)."""
    force = default
    if plan is not None:
        sel = plan.skill(Action.HOLD_LATERAL)
        if sel is not None:
            value = sel.params.get("squeeze_force_n")
            if isinstance(value, int | float):
                force = max(float(value), default)
    return min(force, rated)


def compose_move(
    plan: SemanticAction,
    library: SkillLibrary,
    world: WorldPort,
    name: str,
    index: int,
    state: DualArmState,
    squeeze_force_n: float,
    avoid_gain: float = 1.0,
    transport_weight: float = 1.0,
    skill: str | None = None,
    above_fixture: bool = False,
    table_dz: float = 0.0,
    hold_gain: float = 1.0,
) -> MovePlan:
    """Activate move ``index``'s obstacles and compose it from ``state``.

    The one place a move's obstacles are switched on: the composition asks the world for
    the obstacles present, so they must be the move's before it is built. Arguments as
    :func:`transport_composition`'s; ``index`` must be one of ``world.task_moves(name)``.
    ``above_fixture``: a move into a fixture is composed to its hover goal
    (:func:`planner.fixture_moves.hover_goal`); no other move changes. ``table_dz``: the
    table found that much higher than the world states it
    (:func:`planner.leaves.set_down.table_found_dz`): a goal resting the object on the stated
    table goes down with a lower one (:func:`on_found_table`).
    """
    move = on_found_table(world, name, world.task_moves(name)[index], table_dz)
    if above_fixture:
        move = hover_move(world, move)
    world.set_active_obstacles(move.obstacles)
    composer = transport_composition(
        plan,
        library,
        world,
        name,
        move,
        state,
        squeeze_force_n,
        avoid_gain=avoid_gain,
        transport_weight=transport_weight,
        skill=skill,
        hold_gain=hold_gain,
    )
    return MovePlan(
        name,
        index,
        move,
        squeeze_force_n,
        avoid_gain,
        transport_weight,
        state,
        composer,
        skill,
        carried_skill(reweight(plan, avoid_gain, transport_weight), library, skill or move.skill),
        above_fixture,
        hold_gain,
    )


def on_found_table(world: ObjectSensing, name: str, move: Move, table_dz: float) -> Move:
    """``move`` with its goal lowered to a table found ``-table_dz`` m lower than stated when
    the goal rests ``name`` on the table top as the world states it (its lowest point within
    1 mm of it); any other move as it is.

    A carry composed to the stated height over a lower table ends in the air and its low
    carries lift less than they mean to: in Hard mode (tables 2-3 cm lower) the iCub then
    placed 36 of 46 trials, and 46 of 46 with the goal lowered. A table found higher is left
    to the set-down by feel (Transport raises the palms to the surface they meet): raising the
    whole carry with it brought the held object and the forearms nearer what hangs over the
    path, and cost 9 of 151 such iCub trials and 3 of 151 on the iiwas.
    """
    if table_dz >= 0.0 or move.fixture is not None:
        return move
    goal = move.goal
    extents = world.object_extents(name)
    lower, _ = world.workspace_bounds(name)
    stated_top = float(lower[2]) - float(extents[2]) / 2.0
    bottom = float(goal.position[2] - vertical_half_extent(extents, goal.orientation))
    if abs(bottom - stated_top) > 1e-3:
        return move
    lowered = Pose(goal.position + np.array([0.0, 0.0, table_dz]), goal.orientation)
    return replace(move, goal=lowered)


def box_points(extents: np.ndarray) -> np.ndarray:
    """Corners, edge midpoints and face centres of a box centred at the origin, (26, 3)."""
    half = np.asarray(extents, dtype=float) / 2.0
    grid = np.array(np.meshgrid([-1, 0, 1], [-1, 0, 1], [-1, 0, 1], indexing="ij"))
    signs = grid.reshape(3, -1).T
    signs = signs[np.any(signs != 0, axis=1)]
    return signs * half


def goal_error(world: WorldPort, name: str, goal: Pose) -> tuple[float, float]:
    """Position (m) and orientation (rad) error of an object from a goal pose. The orientation
    error is up to the object's symmetry: a cylinder's the angle between its axes (a turn
    about its own axis leaves it as it was), a sphere's none."""
    pose = world.object_pose(name)
    shape = world.object_context(name).shape
    if shape is Shape.SPHERE:
        turned = 0.0
    elif shape is Shape.CYLINDER:
        turned = float(quat.z_axis_angle(pose.orientation, goal.orientation))
    else:
        turned = float(quat.angle_between(pose.orientation, goal.orientation))
    return float(np.linalg.norm(pose.position - goal.position)), turned

"""From the reasoner's plan to a running composition: which coupling terms, which weights.

The affordance reasoner names skills by label with a weight and parameters
(:class:`affordances.SkillSelection`); the library holds the learnt skills with those labels;
the world supplies what only it knows (obstacles, distances, palm stiffness). This module puts
them together into a :class:`skills.composer.DualArmComposer` for one move, and into the
relative-only compositions that close and open the grasp.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from affordances import SemanticAction, SkillSelection
from planner.port import Move, Pose, WorldPort
from skills import quaternion as quat
from skills.composer import DualArmComposer, DualArmState, relative_from_world
from skills.coupling import CouplingTerm
from skills.couplings.grasp import GraspMaintenance
from skills.couplings.potential import PotentialFieldAvoidance
from skills.couplings.steering import ObstacleSteering
from skills.dual_arm import ARMS, GraspGeometry
from skills.labels import Action, Arm, Space
from skills.library import SkillLibrary
from skills.pose_dmp import LearntForcing, PoseState
from skills.skill import Skill, SkillKind

#: Shortest move duration, s (the demonstrations last about 2 s).
MIN_TAU_S = 2.0


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


def lateral_geometry(world: WorldPort, name: str) -> GraspGeometry:
    """The two-palm lateral grasp geometry of an object's box, palms flat on its +-y faces."""
    extents = world.object_extents(name)
    return GraspGeometry.lateral(float(extents[1]), world.palm_thickness())


def move_duration(start: np.ndarray, goal: np.ndarray, settings: TransportSettings) -> float:
    """``tau`` for a move: the path (up, across, down) at ``max_speed`` peak, at least 2 s.

    A minimum-jerk profile peaks at 1.875 times its mean speed, hence the factor.
    """
    path = float(np.linalg.norm(goal - start)) + 2.0 * settings.lift_m
    return max(MIN_TAU_S, 1.875 * path / settings.max_speed)


def scale_avoidance(plan: SemanticAction, gain: float) -> SemanticAction:
    """The plan with its avoidance skills' weights multiplied by ``gain``."""
    if gain == 1.0:
        return plan
    avoid = (Action.AVOID_OBSTACLE, Action.AVOID_LINKS)
    skills = tuple(
        replace(s, weight=s.weight * gain) if s.action in avoid else s for s in plan.skills
    )
    return replace(plan, skills=skills)


def _param(selection: SkillSelection, key: str, default: float) -> float:
    value = selection.params.get(key, default)
    return float(value) if isinstance(value, int | float) else default


def _skill_for(library: SkillLibrary, selection: SkillSelection) -> Skill:
    return library.first(selection.action, selection.space)


def absolute_terms(
    plan: SemanticAction,
    library: SkillLibrary,
    world: WorldPort,
    name: str,
    points_object: np.ndarray,
) -> list[tuple[CouplingTerm, float]]:
    """Coupling terms and weights of the plan's absolute skills.

    Parameters
    ----------
    plan : SemanticAction
    library : SkillLibrary
    world : WorldPort
        For the present obstacles and the distance query of link-level avoidance.
    name : str
        The held object.
    points_object : ndarray, shape (M, 3)
        Arm-link points in the object frame, for link-level avoidance.
    """
    terms: list[tuple[CouplingTerm, float]] = []
    radius = float(np.linalg.norm(world.object_extents(name)) / 2.0)
    for sel in plan.skills:
        if sel.space is not Space.ABSOLUTE or sel.weight == 0.0:
            continue
        if sel.action in (Action.APPROACH, Action.RETREAT, Action.LIMIT_REPULSION):
            continue
        skill = _skill_for(library, sel)
        if skill.kind is SkillKind.LEARNT_DMP:
            terms.append((LearntForcing(skill.pose_model()), sel.weight))
        elif skill.kind is SkillKind.OBSTACLE_STEERING:
            obstacles = world.obstacles()
            steering = ObstacleSteering(
                gamma=float(skill.params["gamma"]) * _param(sel, "obstacle_gain", 1.0),
                beta=float(skill.params["beta"]),
                k=float(skill.params["k"]),
                object_radius=radius,
            ).with_obstacles(
                np.array([o.position for o in obstacles]).reshape(-1, 3),
                np.array([o.radius for o in obstacles]),
            )
            terms.append((steering, sel.weight))
        elif skill.kind is SkillKind.POTENTIAL_FIELD:
            field_term = PotentialFieldAvoidance(
                query=world.distance_query,
                points_object=points_object,
                gain=float(skill.params["gain"]) * _param(sel, "link_gain", 1.0),
                beta=float(skill.params["beta"]),
                influence=float(skill.params["influence"]),
            )
            terms.append((field_term, sel.weight))
    return terms


def hold_terms(
    plan: SemanticAction | None,
    library: SkillLibrary,
    geometry: GraspGeometry,
    squeeze_depth: float,
) -> dict[Arm, list[tuple[CouplingTerm, float]]]:
    """Grasp-maintenance terms per palm: track the grasp geometry, ``squeeze_depth`` inside."""
    weight = 1.0
    stiffness, rot_stiffness = 400.0, 200.0
    if plan is not None:
        sel = plan.skill(Action.HOLD_LATERAL)
        if sel is not None:
            weight = sel.weight
    held = library.by_action(Action.HOLD_LATERAL, Space.RELATIVE)
    if held and held[0].kind is SkillKind.GRASP_MAINTENANCE:
        stiffness = float(held[0].params.get("stiffness", stiffness))
        rot_stiffness = float(held[0].params.get("rotational_stiffness", rot_stiffness))
    return {
        arm: [
            (
                GraspMaintenance(
                    geometry.position(arm),
                    geometry.orientation(arm),
                    squeeze_depth=max(squeeze_depth, 0.0),
                    stiffness=stiffness,
                    rotational_stiffness=rot_stiffness,
                    inward_normal_object=geometry.normal(arm),
                ),
                weight,
            )
        ]
        for arm in ARMS
    }


def opening_terms(
    geometry: GraspGeometry, opening: float
) -> dict[Arm, list[tuple[CouplingTerm, float]]]:
    """Relative terms that move each palm ``opening`` m out of contact along its normal."""
    out = geometry.squeezed(-opening)
    return {
        arm: [
            (
                GraspMaintenance(
                    out.position(arm),
                    out.orientation(arm),
                    squeeze_depth=0.0,
                    inward_normal_object=geometry.normal(arm),
                ),
                1.0,
            )
        ]
        for arm in ARMS
    }


def measured_dual_state(world: WorldPort, name: str) -> DualArmState:
    """The closed chain as measured: object pose, each palm's pose in {O}, all at rest."""
    obj = world.object_pose(name)
    rel = {}
    for arm in ARMS:
        palm = world.palm_pose(arm)
        rel[arm] = relative_from_world(
            obj.position, obj.orientation, palm.position, palm.orientation
        )
    return DualArmState(
        PoseState.at_rest(obj.position, obj.orientation),
        PoseState.at_rest(*rel[Arm.LEFT]),
        PoseState.at_rest(*rel[Arm.RIGHT]),
    )


def static_composition(
    state: DualArmState, relative: Mapping[Arm, list[tuple[CouplingTerm, float]]], tau: float
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
    squeeze_depth: float,
    settings: TransportSettings | None = None,
    avoid_gain: float = 1.0,
) -> DualArmComposer:
    """The simultaneous composition of one move, starting from the handed-over state.

    ``avoid_gain`` multiplies the weights of obstacle steering and link-level avoidance (a
    more cautious composition when a predicted path is not clear).
    """
    s = settings or TransportSettings()
    sel = plan.skill(Action.TRANSPORT)
    if sel is not None:
        s = TransportSettings(_param(sel, "max_speed", s.max_speed), s.lift_m)
    tau = move_duration(state.object.position, move.goal.position, s)
    geometry = lateral_geometry(world, name)
    points = link_points_in_object(world, state.object)
    absolute = absolute_terms(scale_avoidance(plan, avoid_gain), library, world, name, points)
    relative = hold_terms(plan, library, geometry, squeeze_depth)
    return DualArmComposer.start(
        state, move.goal.position, move.goal.orientation, tau, absolute=absolute, relative=relative
    )


def link_points_in_object(world: WorldPort, obj: PoseState) -> np.ndarray:
    """The world's arm-link points expressed in the object frame, (M, 3)."""
    pts = world.link_points()
    inv = quat.conjugate(obj.orientation)
    return quat.rotate(inv, pts - obj.position)


def refresh_link_points(composer: DualArmComposer, world: WorldPort) -> None:
    """Move link-level avoidance onto the arms' current link points (they bend as they move)."""
    points = None
    for i, weighted in enumerate(composer.absolute):
        term: Any = weighted.term
        if isinstance(term, PotentialFieldAvoidance):
            if points is None:
                points = link_points_in_object(world, composer.state.object)
            composer.absolute[i] = type(weighted)(term.with_points(points), weighted.weight)


def goal_error(world: WorldPort, name: str, goal: Pose) -> tuple[float, float]:
    """Position (m) and orientation (rad) error of an object from a goal pose."""
    pose = world.object_pose(name)
    return (
        float(np.linalg.norm(pose.position - goal.position)),
        float(quat.angle_between(pose.orientation, goal.orientation)),
    )

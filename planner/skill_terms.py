"""The coupling terms of a plan's skills, with their weights: the absolute ones a carry composes
(learnt motions, obstacle steering, link-level avoidance, the workspace floor), and the
relative ones that hold, close and open a grasp. :mod:`planner.composition` puts them
together into a move's composition.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from affordances import SemanticAction, SkillSelection
from planner.port import WorldPort
from planner.skill_choice import skill_for
from skills import quaternion as quat
from skills.composer import DualArmState
from skills.couplings import LearntForcing
from skills.couplings.grasp import GraspMaintenance
from skills.couplings.limits import WorkspaceRepulsion
from skills.couplings.potential import PotentialFieldAvoidance
from skills.couplings.steering import ObstacleSteering
from skills.couplings.term import CouplingTerm
from skills.dual_arm import GraspGeometry
from skills.library import SkillLibrary
from skills.skill import Skill, SkillKind
from skills.vocabulary import ARMS, Action, Arm, Space


def selection_param(selection: SkillSelection, key: str, default: float) -> float:
    """A skill selection's numeric parameter ``key``, else ``default``."""
    value = selection.params.get(key, default)
    return float(value) if isinstance(value, int | float) else default


def absolute_terms(
    plan: SemanticAction,
    library: SkillLibrary,
    world: WorldPort,
    name: str,
    points_object: np.ndarray,
    transport: Skill | None = None,
    rest_half_height: float | None = None,
    held: tuple[np.ndarray, np.ndarray] | None = None,
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
        Points attached to the object (its own surface), object frame, for link-level
        avoidance; the arms' link points come through the field's query (:class:`ArmLinks`).
    transport : Skill, optional
        The learnt motion to carry the object with instead of the library's first transport
        skill (weight 1 if the plan selects no transport).
    rest_half_height : float, optional
        The least half height (m) the object rests at over the move (lower than half its z
        extent when the move sets it down on its side): the workspace floor follows it.
    held : (ndarray (K, 3), ndarray (K,)), optional
        Bounding spheres of what moves rigidly with the held object (:func:`held_spheres`),
        object frame, m: link-level avoidance steers them (:func:`held_steering`).
    """
    terms: list[tuple[CouplingTerm, float]] = []
    if transport is not None and plan.skill(Action.TRANSPORT) is None:
        terms.append((LearntForcing(transport.pose_model()), 1.0))
    # The centre-based steering sees the object as a sphere; the smallest half-extent keeps it
    # from treating a flat box as a ball (its faces are covered by the potential field).
    radius = float(np.min(world.object_extents(name)) / 2.0)
    for sel in plan.skills:
        if sel.space is not Space.ABSOLUTE or sel.weight == 0.0:
            continue
        # The insertion is the move's carried motion itself (``transport``), composed by the
        # Insert leaf; a carry to above the fixture does not descend with it.
        if sel.action in (Action.APPROACH, Action.RETREAT, Action.INSERT):
            continue
        skill = skill_for(library, sel, transport)
        if skill.kind is SkillKind.LEARNT_DMP:
            terms.append((LearntForcing(skill.pose_model()), sel.weight))
        elif skill.kind is SkillKind.OBSTACLE_STEERING:
            steering = learnt_steering(
                skill, world, selection_param(sel, "obstacle_gain", 1.0), object_radius=radius
            )
            terms.append((steering, sel.weight))
        elif skill.kind is SkillKind.POTENTIAL_FIELD:
            field_term = PotentialFieldAvoidance(
                query=ArmLinks(world),
                points_object=points_object,
                gain=float(skill.params["gain"]) * selection_param(sel, "link_gain", 1.0),
                beta=float(skill.params["beta"]),
                influence=float(skill.params["influence"]),
            )
            terms.append((field_term, sel.weight))
            hands = held_steering(
                library, world, held, radius, selection_param(sel, "link_gain", 1.0)
            )
            if hands is not None:
                terms.append((hands, sel.weight))
        elif skill.kind is SkillKind.WORKSPACE_REPULSION:
            lower, upper = world.workspace_bounds(name)
            if rest_half_height is not None:
                # The bounds keep the centre half its z extent over the table; a box set down
                # on its side rests lower.
                half_z = float(world.object_extents(name)[2]) / 2.0
                lower = lower - np.array([0.0, 0.0, max(half_z - rest_half_height, 0.0)])
            margin = float(skill.params["margin"])
            # The bound sits a margin below the resting height: the push starts where the
            # object rests on the table (so placing on it is free) and grows without bound
            # below it, where the palms would slide down the object's faces.
            terms.append(
                (
                    WorkspaceRepulsion(
                        lower - np.array([0.0, 0.0, margin]),
                        upper,
                        margin=margin,
                        gain=float(skill.params["gain"]),
                    ),
                    sel.weight,
                )
            )
    return terms


def held_steering(
    library: SkillLibrary,
    world: WorldPort,
    held: tuple[np.ndarray, np.ndarray] | None,
    object_radius: float = 0.0,
    gain: float = 1.0,
) -> ObstacleSteering | None:
    """The link-level avoidance of what is welded to the palms (a hand standing out of the
    grip): it moves rigidly with the held object, so the object's own human-like steering
    law, with the library's learnt gains, steers it around the obstacles it is nearer to
    than the object's sphere of ``object_radius`` (:class:`ObstacleSteering`'s held
    assembly; Park et al.'s field over the link points fades with their speed, and a
    carry's attractor can press a slow hand into an obstacle). None without held spheres or
    a steering skill."""
    steering = [
        s
        for s in library.by_action(Action.AVOID_OBSTACLE, Space.ABSOLUTE)
        if s.kind is SkillKind.OBSTACLE_STEERING
    ]
    if held is None or held[0].shape[0] == 0 or not steering:
        return None
    return learnt_steering(
        steering[0],
        world,
        gain,
        object_radius=object_radius,
        held=held[0],
        held_radii=held[1],
        steer_object=False,
    )


def learnt_steering(
    skill: Skill, world: WorldPort, gain: float = 1.0, **held: object
) -> ObstacleSteering:
    """The obstacle steering ``skill`` learnt (its gamma times ``gain``, beta, k) around the
    world's present obstacles; ``held`` passes :class:`ObstacleSteering`'s object radius and
    held assembly."""
    obstacles = world.obstacles()
    return ObstacleSteering(
        gamma=float(skill.params["gamma"]) * gain,
        beta=float(skill.params["beta"]),
        k=float(skill.params["k"]),
        centres=np.array([o.position for o in obstacles]).reshape(-1, 3),
        radii=np.array([o.radius for o in obstacles]),
        **held,  # type: ignore[arg-type]
    )


def held_spheres(world: WorldPort, state: DualArmState) -> tuple[np.ndarray, np.ndarray]:
    """What is welded to the palms (:meth:`WorldPort.welded_spheres`), placed in the object
    frame by the grip of the handed-over ``state``: centres (K, 3) m and radii (K,) m."""
    centres, radii = [], []
    for arm, palm in ((Arm.LEFT, state.left), (Arm.RIGHT, state.right)):
        local, r = world.welded_spheres(arm)
        centres.append(palm.position + local @ quat.to_matrix(palm.orientation).T)
        radii.append(r)
    return np.concatenate(centres).reshape(-1, 3), np.concatenate(radii)


def hold_terms(
    plan: SemanticAction | None,
    library: SkillLibrary,
    geometry: GraspGeometry,
    squeeze_depth: float,
    gain: float = 1.0,
) -> dict[Arm, list[tuple[CouplingTerm, float]]]:
    """Grasp-maintenance terms per palm: track the grasp geometry, ``squeeze_depth`` inside;
    their weight the plan's ``hold_lateral`` one (1 without) times ``gain``."""
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
                weight * gain,
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


@dataclass(frozen=True)
class ArmLinks:
    """The world's distance query, with the arms' link points as points of its own.

    A potential field on it avoids with the arms' links as well as the points attached to the
    object (:class:`skills.couplings.MovingPoints`): the composition reads the links again
    before each closed-loop step, as the arms bend, and a prediction carries them with the
    object from where they are when it starts.
    """

    world: WorldPort

    def __call__(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Distance (N,) from each point (N, 3) to the nearest obstacle, and its closest point."""
        return self.world.distance_query(points)

    def moving_points(self) -> np.ndarray:
        """The arms' link points now, (M, 3), world frame."""
        return self.world.link_points()


__all__ = [
    "ArmLinks",
    "absolute_terms",
    "held_spheres",
    "held_steering",
    "hold_terms",
    "learnt_steering",
    "opening_terms",
    "selection_param",
]

"""The closed chain a skill starts from: the object's pose and each palm's pose in its frame
({O}), as measured, as a grasp closes, or handed over from the last skill with {O} moved onto
the object as measured; and the grip those palms make.
"""

from __future__ import annotations

from collections.abc import Mapping

from planner.grips import lateral_geometry
from planner.port import ObjectSensing, Pose, WorldPort
from skills.composer import DualArmState, commands_for, relative_from_world
from skills.dual_arm import GraspGeometry
from skills.pose_dmp import PoseState
from skills.turns import held_quarter_turns
from skills.vocabulary import ARMS, Arm


def held_lateral_geometry(world: WorldPort, name: str, state: DualArmState) -> GraspGeometry:
    """The grip of a handed-over state: its palms' poses in {O}, the held faces' normals."""
    nominal = lateral_geometry(world, name, held_quarter_turns(state.left.position))
    return held_geometry(state, nominal)


def on_measured_object(world: ObjectSensing, name: str, state: DualArmState) -> DualArmState:
    """The handed-over state with {O} moved onto the object as measured, the palms' world
    references (and every velocity) unchanged.

    A held box slips a little in two palms, most when it turns; the next move must carry it
    from where it is, not from where the last one commanded it, or the slips of a sequence
    of moves (and of a turn made in steps) add up.
    """
    measured = world.object_pose(name)
    cmd = commands_for(state)
    rel = [
        relative_from_world(
            measured.position, measured.orientation, cmd.positions[i], cmd.orientations[i]
        )
        for i in range(2)
    ]
    return DualArmState(
        state.object._replace(position=measured.position, orientation=measured.orientation),
        state.left._replace(position=rel[0][0], orientation=rel[0][1]),
        state.right._replace(position=rel[1][0], orientation=rel[1][1]),
    )


def held_geometry(state: DualArmState, nominal: GraspGeometry) -> GraspGeometry:
    """The grip as it is: the palms' poses in {O} from a handed-over state, nominal normals."""
    return GraspGeometry(
        state.left.position.copy(),
        state.left.orientation.copy(),
        state.right.position.copy(),
        state.right.orientation.copy(),
        nominal.left_normal,
        nominal.right_normal,
    )


def measured_dual_state(world: WorldPort, name: str) -> DualArmState:
    """The closed chain as measured: object pose, each palm's pose in {O}, all at rest."""
    return _dual_state_at(world.object_pose(name), {arm: world.palm_pose(arm) for arm in ARMS})


def closing_dual_state(world: WorldPort, name: str) -> DualArmState:
    """The closed chain a grasp closes from: the object as measured, a palm that already
    presses it where it was sent (:meth:`~planner.port.PalmControl.palm_target`), any other
    palm as measured; all in {O}, at rest.

    A palm pressing the object is held off its target by the face, and by a biased actuator
    pushing it into the face: moved onto the palm, its reference would let that push go that
    much further at once. Kept where it was sent, the palm's force does not change at the
    first step. A palm not touching the object starts where it is, as every other skill does.
    """
    palms = {
        arm: world.palm_target(arm)
        if world.contact_force(arm, name) > 0.0
        else world.palm_pose(arm)
        for arm in ARMS
    }
    return _dual_state_at(world.object_pose(name), palms)


def _dual_state_at(obj: Pose, palms: Mapping[Arm, Pose]) -> DualArmState:
    rel = {
        arm: relative_from_world(
            obj.position, obj.orientation, palms[arm].position, palms[arm].orientation
        )
        for arm in ARMS
    }
    return DualArmState(
        PoseState.at_rest(obj.position, obj.orientation),
        PoseState.at_rest(*rel[Arm.LEFT]),
        PoseState.at_rest(*rel[Arm.RIGHT]),
    )

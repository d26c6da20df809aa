"""GripTurns: whether the grip the object is held with can make a move's turn about z."""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from py_trees.common import Status
from py_trees.ports import PortInformation

from planner.grips import left_palm_quarter_turns, move_turn, robot_yaw
from planner.leaves.base import WorldLeaf
from planner.port import ObjectSensing, PalmControl
from skills.turns import GRIP_TURN_TOLERANCE_DEG, grip_yaw, yaw_of
from skills.vocabulary import ARMS


class GripTurns(WorldLeaf):
    """The held grip can turn the object to move ``move``'s goal yaw.

    The palms' turn from their natural pose (the grip yaw, :mod:`skills.turns`) must stay
    within the robot's ``max_turn_rad`` (and ``tolerance_deg``) now and at the goal; when it
    would not, the tree lets go and grasps the faces that suit the turn. An object that is not
    held passes: there is no grip to re-grasp for a turn (``IsHeld`` answers for a lost one).
    """

    WORLD_ROLES: ClassVar[tuple[type, ...]] = (ObjectSensing, PalmControl)

    NODE_TYPE: ClassVar[str] = "Condition"
    INPUT_PORTS = {
        "object": PortInformation(str, description="the held object"),
        "move": PortInformation(int, description="index of the task's move, from 0"),
        "min_force_n": PortInformation(
            float, required=False, default_value=2.0, description="least force of a grip, N"
        ),
        "tolerance_deg": PortInformation(
            float,
            required=False,
            default_value=GRIP_TURN_TOLERANCE_DEG,
            description="grip yaw allowed beyond the robot's largest turn, degrees",
        ),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def update(self) -> Status:
        """SUCCESS if the grip can make the turn (or nothing is held); FAILURE otherwise."""
        inputs = self.object_and_move()
        if isinstance(inputs, str):
            return self.fail(inputs)
        name, index = inputs
        world = self.world
        forces = [world.contact_force(arm, name) for arm in ARMS]
        if min(forces) < float(self.get_input("min_force_n")):
            return self.succeed("not held: no grip to turn")
        held = left_palm_quarter_turns(world, name)
        start = grip_yaw(yaw_of(world.object_pose(name).orientation), held, robot_yaw(world))
        end = start + move_turn(world, name, index)
        limit = world.robot_capabilities().max_turn_rad
        text = (
            f"grip turned {np.degrees(start):.0f} deg now, {np.degrees(end):.0f} deg at goal "
            f"{index} (the arms hold +-{np.degrees(limit):.0f})"
        )
        if max(abs(start), abs(end)) <= limit + np.radians(float(self.get_input("tolerance_deg"))):
            return self.succeed(text)
        return self.fail(text + ": re-grasp")

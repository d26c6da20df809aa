"""Approach: bring both palms beside the object's faces through middle set-points."""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from py_trees.ports import PortInformation

from planner.composition import grasp_quarter_turns, lateral_geometry, move_turn, robot_yaw
from planner.leaves.base import grasp_move_port
from planner.leaves.palm_motion import ViaPointLeaf, ViaPointMotion, measured_state
from planner.port import ObjectSensing, PalmControl, Pose, WorldPort
from skills import quaternion as quat
from skills.turns import grip_yaw, wrap_angle, yaw_of
from skills.vocabulary import ARMS, Arm


def pregrasp_poses(
    object_pose: Pose,
    geometry_positions: dict[Arm, np.ndarray],
    geometry_orientations: dict[Arm, np.ndarray],
    normals: dict[Arm, np.ndarray],
    standoff: float,
    rise: float,
) -> dict[Arm, list[Pose]]:
    """Middle set-point (outside and above) then the pre-grasp pose, per palm, world frame."""
    out: dict[Arm, list[Pose]] = {}
    for arm in ARMS:
        outward = -normals[arm]
        rel_pre = geometry_positions[arm] + standoff * outward
        rel_mid = geometry_positions[arm] + 2.0 * standoff * outward
        q = quat.multiply(object_pose.orientation, geometry_orientations[arm])
        pre = object_pose.position + quat.rotate(object_pose.orientation, rel_pre)
        mid = object_pose.position + quat.rotate(object_pose.orientation, rel_mid)
        mid = mid + np.array([0.0, 0.0, rise])
        out[arm] = [Pose(mid, q), Pose(pre, q)]
    return out


#: Turned this far from the palms' natural grip, an object's corners stand in the palms' way.
TURNED_RAD = np.radians(15.0)


def clear_rise(world: WorldPort, name: str, pose: Pose, quarter_turns: int, rise: float) -> float:
    """Height of the middle set-points above the grasp: ``rise``, or, when the object stands
    turned from the palms' natural grip (a re-grasp after a turn), enough for the palms to
    pass above its top (a straight way in from the side would sweep its corners)."""
    grip = wrap_angle(grip_yaw(yaw_of(pose.orientation), quarter_turns, robot_yaw(world)))
    if abs(grip) <= TURNED_RAD:
        return rise
    top = float(world.object_extents(name)[2]) / 2.0  # the grasp is at the centre's height
    # A palm's farthest point from its centre, across its face.
    palm_reach = float(max(world.robot_capabilities().palm_size_m[:2])) / 2.0
    return max(rise, top + palm_reach + 0.02)


class Approach(ViaPointLeaf):
    """Move both palms to ``standoff`` m outside the object's faces via set-points above.

    The faces are the pair that suits move ``move``'s turn (:mod:`skills.turns`), from the
    object's measured yaw: after a turn, the palms meet the faces that now face them.
    """

    WORLD_ROLES: ClassVar[tuple[type, ...]] = (ObjectSensing, PalmControl)

    INPUT_PORTS = {
        "object": PortInformation(str, description="object to approach"),
        "move": grasp_move_port(),
        "standoff_m": PortInformation(
            float,
            required=False,
            default_value=0.04,
            description="gap between palm and face at the end, m",
        ),
        "rise_m": PortInformation(
            float,
            required=False,
            default_value=0.08,
            description="height of the middle set-point above, m",
        ),
        "segment_s": PortInformation(
            float,
            required=False,
            default_value=1.5,
            description="duration scale of each segment, s",
        ),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {}
    MOVING = "approaching"
    ARRIVED = "palms at the pre-grasp poses"

    def initialise(self) -> None:
        """Plan the via-point motion from where the palms are now."""
        self.motion = None
        if self.connected() is not None:
            return
        world = self.world
        name = self.get_input("object")
        turn = move_turn(world, name, int(self.get_input("move")))
        quarter_turns = grasp_quarter_turns(world, name, turn)
        g = lateral_geometry(world, name, quarter_turns)
        pose = world.object_pose(name)
        waypoints = pregrasp_poses(
            pose,
            {a: g.position(a) for a in ARMS},
            {a: g.orientation(a) for a in ARMS},
            {a: g.normal(a) for a in ARMS},
            float(self.get_input("standoff_m")),
            clear_rise(world, name, pose, quarter_turns, float(self.get_input("rise_m"))),
        )
        starts = {a: measured_state(world.palm_pose(a), world.palm_twist(a)) for a in ARMS}
        self.motion = ViaPointMotion(starts, waypoints, float(self.get_input("segment_s")))

"""What the robot touches where a run starts, before anything is stepped.

A robot whose two arms stand inside each other (an ``arm_separation`` below the width of the
iiwas' bases) validated and then failed every run as "arms touched", from the first physics
step. :func:`start_pose_problems` builds the run's scene as it starts (the palms where a run
places them) and asks PyBullet for the arms' closest points: any pair touching or nearer is
refused, naming the field and the links (the run's judge counts a touch).
"""

from __future__ import annotations

import pybullet as pb

from skills.vocabulary import Arm
from worlds.placement import fmt
from worlds.sim_world import SimWorld
from worlds.spec import WorldSpec
from worlds.world_errors import WorldFileProblem
from worlds.world_file import World, as_world_spec


def start_pose_problems(world: World | WorldSpec) -> list[WorldFileProblem]:
    """The arms in each other where a run starts: one problem at ``robot.arm_separation``
    (two bodies, one per arm; a robot of one body has no separation to choose), naming the
    deepest pair of links; empty when they are apart."""
    spec = as_world_spec(world)
    with SimWorld(spec) as sim:
        scene = sim.scene
        if len(set(scene.robot_ids)) < 2:
            return []
        left, right = scene.robot_ids[:2]
        points = pb.getClosestPoints(left, right, 0.0, physicsClientId=scene.client)
        if not points:
            return []
        deepest = min(points, key=lambda p: p[8])
        names = [
            sim.collision.link_name(Arm.LEFT, deepest[3]),
            sim.collision.link_name(Arm.RIGHT, deepest[4]),
        ]
    separation = spec.scene.robot.arm_separation
    depth = -1000.0 * deepest[8]
    how = f"is {fmt(depth)} mm into" if depth >= 0.05 else "touches"
    return [
        WorldFileProblem(
            "robot.arm_separation",
            "arms apart where a run starts (their bases and the palms where a run places them)",
            f"{separation:g} m: the left arm's {names[0]} {how} the right arm's {names[1]}; set "
            "them farther apart",
        )
    ]


__all__ = ["start_pose_problems"]

"""An obstacle that appears where the robot's arms already are.

A move's obstacles are switched on when the move starts. From a task's second move on, the
palms are then holding the object where the move before left it, and an obstacle placed
through an arm there appears inside it: PyBullet would shove the arm out on the next step,
and the run fails at once ("obstacle spawned inside a body"), after seconds of simulation.
:func:`obstacle_hold_problems` finds it before anything is stepped: for each such move it
poses the arms holding the object at the previous goal, in the grip the previous move ends
in (:func:`skills.turns.move_holds`), by inverse kinematics solved to convergence on the
robot's kinematic copy, and asks the FCL mirror whether a palm or an arm link touches each
of the move's obstacles there (:meth:`worlds.sim_world.SimWorld.hold_touches`). Objects the
reasoner would not grasp between two palms on opposite faces are not asked, nor moves after
one that leaves the object off upright (a flip) or seated in a fixture.

The posture is the solver's, not the controller's: a compliant arm settles a few centimetres
off it. The check asks only for touching (no margin), so an obstacle it refuses stands where
the arm is, not merely near it.
"""

from __future__ import annotations

import math

import numpy as np

from affordances.config import ReasonerConfig
from affordances.physics import assess
from skills import quaternion as quat
from skills.turns import (
    GRIP_TURN_TOLERANCE_DEG,
    Hold,
    grip_options,
    grip_yaw,
    move_holds,
    yaw_of,
)
from skills.vocabulary import GraspType
from worlds.adapters import object_contexts, robot_capabilities
from worlds.placement import vec
from worlds.sim_world import SimWorld
from worlds.spec import WorldSpec
from worlds.world_errors import WorldFileProblem
from worlds.world_file import World, as_world_spec

_Z = np.array([0.0, 0.0, 1.0])
#: An object whose z axis is within a degree of the world's stands upright.
_UPRIGHT_COS = math.cos(math.radians(1.0))


def obstacle_hold_problems(world: World | WorldSpec) -> list[WorldFileProblem]:
    """Every obstacle of a move (its task's second or later) that the arms, holding the object
    at the previous goal, touch when it appears; and every goal the arms cannot hold the object
    at without touching one of its move's obstacles, in any grip they reach
    (:func:`goal_hold_touches`).

    Returns
    -------
    list of WorldFileProblem
        Fields are the obstacles' positions (``obstacles[1].position``) and the goals
        (``task[0].moves[2].goal``).
    """
    spec = as_world_spec(world)
    moving = [(i, j) for i, s in enumerate(spec.task) for j, m in enumerate(s.moves) if m.obstacles]
    if not moving:
        return []
    index = {o.name: k for k, o in enumerate(spec.scene.obstacles)}
    robot = robot_capabilities(spec)
    # The holds are the lateral grasp's palms on the held faces: asked only of objects the
    # reasoner would grasp that way.
    lateral = {
        c.name
        for c in object_contexts(spec)
        if any(
            o.grasp is GraspType.TWO_PALM_LATERAL
            for o in assess(c, robot, ReasonerConfig.under(spec.scene.gravity)).options
        )
    }
    asked = {(i, j) for i, j in moving if spec.task[i].object in lateral}
    if not asked:
        return []
    max_turn = robot.max_turn_rad
    robot_yaw = math.radians(spec.scene.robot.base_rpy_deg[2])
    problems: list[WorldFileProblem] = []
    # Where each object stands when a task step takes it up: where the step before of the
    # same object let it go, else where it starts. A step's first move grasps it there, in
    # the move's first grip; a later move goes on from the grip the move before ended in.
    # (An object a step left off upright, or seated in a fixture, is not asked after it: the
    # lateral holds do not say how it is held.)
    left_at = {
        o.name: (np.asarray(o.position, dtype=float), float(o.yaw), True)
        for o in spec.scene.objects
    }
    with SimWorld(spec) as sim:
        for i, step in enumerate(spec.task):
            position, yaw, standing = left_at[step.object]
            held: Hold | None = None
            for j, move in enumerate(step.moves):
                goal = np.asarray(move.goal_position, dtype=float)
                goal_yaw = yaw_of(move.goal_quaternion)
                if j == 0 and standing:
                    held = move_holds(position, yaw, goal, goal_yaw, max_turn, robot_yaw)[0]
                if (i, j) in asked and held is not None:
                    touched = sim.hold_touches(step.object, move.obstacles, held)
                    where = (
                        f"at the goal of its move {j} (task[{i}].moves[{j - 1}])"
                        if j
                        else "where it stands, in the grasp the move starts from"
                    )
                    for name, what in touched.items():
                        problems.append(
                            WorldFileProblem(
                                f"obstacles[{index[name]}].position",
                                f"{name} clear of the arms holding {step.object} {where} when "
                                f"task[{i}].moves[{j}] starts",
                                f"{vec(spec.scene.obstacles[index[name]].position)}: "
                                f"{what}, with {step.object} at {vec(held.position)}",
                            )
                        )
                # Where the lateral holds say how it is held: upright, carried (not seated
                # in a fixture, which the palms may let go of). Else not asked after it.
                upright = quat.rotate(np.asarray(move.goal_quaternion), _Z)[2] > _UPRIGHT_COS
                if (i, j) in asked and upright and move.fixture is None:
                    grips = goal_hold_touches(sim, step.object, move.obstacles, goal, goal_yaw)
                    if grips:
                        problems.append(
                            WorldFileProblem(
                                f"task[{i}].moves[{j}].goal",
                                f"{step.object} held at its goal clear of the move's "
                                "obstacles, in a grip the arms reach",
                                f"{vec(goal)} turned {math.degrees(goal_yaw):.0f} deg: "
                                + "; ".join(grips),
                            )
                        )
                held = (
                    move_holds(position, yaw, goal, goal_yaw, max_turn, robot_yaw)[-1]
                    if upright and move.fixture is None
                    else None
                )
                position, yaw = goal, goal_yaw
            left_at[step.object] = (position, yaw, held is not None)
    return problems


def goal_hold_touches(
    sim: SimWorld, name: str, obstacles: tuple[str, ...], goal: np.ndarray, goal_yaw: float
) -> list[str]:
    """How the robot holding object ``name`` at ``goal`` turned ``goal_yaw`` touches
    ``obstacles``, one line per grip it reaches there (face pairs whose grip yaw is within the
    robot's largest turn and :data:`skills.turns.GRIP_TURN_TOLERANCE_DEG`), e.g. "grip 30 deg:
    the right arm touches ball_left"; empty when any one of those grips touches none. The arms
    are solved to convergence on the kinematic copy: the compliant arm settles a few
    centimetres off that posture, and only touching is asked."""
    limit = robot_capabilities(sim.spec).max_turn_rad + math.radians(GRIP_TURN_TOLERANCE_DEG)
    robot_yaw = math.radians(sim.spec.scene.robot.base_rpy_deg[2])
    lines = []
    for k in grip_options(goal_yaw, 0.0, limit, robot_yaw):
        grip = grip_yaw(goal_yaw, k, robot_yaw)
        touched = sim.hold_touches(name, obstacles, Hold(goal, goal_yaw, grip, k))
        if not touched:
            return []
        lines.append(
            f"grip {math.degrees(grip):.0f} deg: "
            + ", ".join(f"{what} ({o})" for o, what in touched.items())
        )
    return lines


__all__ = ["goal_hold_touches", "obstacle_hold_problems"]

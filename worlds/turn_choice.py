"""Choosing where each turned move of a world makes its turn (:func:`skills.turns.move_holds`).

A move's steps before its last stand at its goal unless the robot, holding the object there in
one of those steps' grips, would come within the carries' margin of one of the move's
obstacles: a 90 degree goal beside a sphere, whose half turn at the goal puts the forearm
reaching round the far face into the sphere, turns elsewhere. (The goal is not refused for
the reach the check's inverse kinematics finds: the arms' compliance reaches holds at the
goal it does not, and the goal is where the move must end anyway.) The places tried after the
goal are the move's start and a grid around the way (:func:`candidate_places`), shortest
detour first; a place must keep the object's footprint on the table and off where the other
objects start, its holds must be reached, and they must keep a wider margin than the goal's,
for the object set down there a few millimetres off. The first such place is taken; a world
where none is keeps the goal (its carries' checks then say why).
The check asks a world (``SimWorld``) for each hold: palms, held object and the arms' links
solved to convergence on its kinematic copy, against the move's obstacles.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence

import numpy as np

from skills import quaternion as quat
from skills.turns import Hold, move_holds, yaw_of
from skills.vocabulary import Arm
from worlds.adapters import robot_capabilities
from worlds.palm_poses import lateral_grasp_palm_poses
from worlds.spec import WorldSpec

__all__ = [
    "PLACE_GRID_M",
    "PLACE_REACH_M",
    "HoldsClear",
    "candidate_places",
    "hold_poses",
    "turn_places",
]

#: ``clear(object, obstacles, holds, elsewhere)``: whether the robot can hold ``object`` in
#: each of ``holds`` clear of ``obstacles`` (``elsewhere``: at a place other than the goal,
#: with its wider margin and its arms reaching each hold).
HoldsClear = Callable[[str, tuple[str, ...], Sequence[Hold], bool], bool]

#: Spacing of the places tried, m.
PLACE_GRID_M = 0.05
#: How far beyond the box spanned by a move's start and goal places are tried, m.
PLACE_REACH_M = 0.10

_Z = np.array([0.0, 0.0, 1.0])


def hold_poses(
    hold: Hold,
    extents: np.ndarray,
    palm_thickness: float,
    robot_yaw: float = 0.0,
    gap: float = 0.0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Palm positions (2, 3) and quaternions (2, 4), left then right, and the object's
    quaternion (4,) of ``hold``: the palms on the held faces, or ``gap`` m outside them (where
    a grasp's way in ends; :func:`lateral_grasp_palm_poses`), the object upright at its yaw.
    ``extents`` (3,) is the box's size along its own axes, m."""
    half_span = float(extents[1] if hold.quarter_turns % 2 == 0 else extents[0]) / 2.0
    palms = lateral_grasp_palm_poses(
        hold.position, half_span, palm_thickness, gap, grip_yaw=hold.grip_yaw + robot_yaw
    )
    positions = np.array([palms[Arm.LEFT][0], palms[Arm.RIGHT][0]])
    quaternions = np.array([palms[Arm.LEFT][1], palms[Arm.RIGHT][1]])
    return positions, quaternions, quat.from_axis_angle(_Z, hold.object_yaw)


def candidate_places(
    spec: WorldSpec, name: str, start: np.ndarray, goal: np.ndarray
) -> Iterator[np.ndarray]:
    """The places other than the goal a move of ``name`` from ``start`` to ``goal`` may turn
    at, in the order tried, each (3,) m at the goal's height: the points of a
    :data:`PLACE_GRID_M` grid over the box spanned by start and goal widened by
    :data:`PLACE_REACH_M` (the start among them), shortest detour first (start to place to
    goal), and of equal detours the nearer the robot first (the less an arm reaches round
    the object). Those that would put the object's footprint off the table or onto another
    object's start are left out."""
    scene = spec.scene
    obj = next(o for o in scene.objects if o.name == name)
    reach = float(np.hypot(obj.shape.extents()[0], obj.shape.extents()[1])) / 2.0
    table = np.asarray(scene.table.position, dtype=float)
    half_table = np.asarray(scene.table.size[:2], dtype=float) / 2.0
    base = np.asarray(scene.robot.base_position, dtype=float)[:2]
    others = [
        (np.asarray(o.position[:2], dtype=float), float(np.hypot(*o.shape.extents()[:2])) / 2.0)
        for o in scene.objects
        if o.name != name
    ]
    a, b = np.asarray(start, dtype=float)[:2], np.asarray(goal, dtype=float)[:2]
    low, high = np.minimum(a, b) - PLACE_REACH_M, np.maximum(a, b) + PLACE_REACH_M
    xs = np.arange(low[0], high[0] + 1e-9, PLACE_GRID_M)
    ys = np.arange(low[1], high[1] + 1e-9, PLACE_GRID_M)
    points = [a] + [np.array([x, y]) for x in xs for y in ys]
    keyed = []
    for k, p in enumerate(points):
        detour = float(np.linalg.norm(p - a) + np.linalg.norm(b - p) - np.linalg.norm(b - a))
        keyed.append((round(detour, 3), round(float(np.linalg.norm(p - base)), 3), k, p))
    for _, _, _, p in sorted(keyed, key=lambda item: item[:3]):
        if np.linalg.norm(p - b) < 1e-9:
            continue  # the goal itself
        on_table = np.all(np.abs(p - table[:2]) <= half_table - reach)
        free = all(np.linalg.norm(p - q) > reach + r for q, r in others)
        if on_table and free:
            yield np.array([p[0], p[1], goal[2]], dtype=float)


def turn_places(spec: WorldSpec, name: str, clear: HoldsClear) -> tuple[np.ndarray | None, ...]:
    """Per move of object ``name`` in ``spec``'s task, where its steps before the last stand:
    None for its goal (a move one grasp makes, or one whose holds at the goal are clear), else
    the first of :func:`candidate_places` whose holds are clear and reached. The holds every
    place shares (the first grasp where it is taken, the last where it lets go) are not
    asked."""
    obj = next(o for o in spec.scene.objects if o.name == name)
    max_turn = robot_capabilities(spec).max_turn_rad
    robot_yaw = math.radians(spec.scene.robot.base_rpy_deg[2])
    position, yaw = np.asarray(obj.position, dtype=float), float(obj.yaw)
    places: list[np.ndarray | None] = []
    for move in spec.moves_of(name):
        goal = np.asarray(move.goal_position, dtype=float)
        goal_yaw = yaw_of(move.goal_quaternion)
        obstacles = tuple(move.obstacles)
        chosen: np.ndarray | None = None
        at_goal = move_holds(position, yaw, goal, goal_yaw, max_turn, robot_yaw)
        if len(at_goal) > 2 and not clear(name, obstacles, at_goal[1:-1], False):
            for place in candidate_places(spec, name, position, goal):
                holds = move_holds(position, yaw, goal, goal_yaw, max_turn, robot_yaw, place)
                if clear(name, obstacles, holds[1:-1], True):
                    chosen = place
                    break
        places.append(chosen)
        position, yaw = goal, goal_yaw
    return tuple(places)

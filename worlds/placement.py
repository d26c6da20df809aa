"""Where a world's bodies start: nothing sunk into the table, nothing inside anything else.

A world file can put two objects in one place, an obstacle through an object, or the parcel
half inside the table. PyBullet then pushes the bodies apart with a jolt on the first step
(or, for a static obstacle, never: the object stays impaled), and the run fails for a reason
that names neither. These checks find it from the numbers alone, before anything is built:

- an object over the table whose bottom is more than :data:`SINK_TOLERANCE_M` below the top;
- two objects interpenetrating at their start poses by more than :data:`OVERLAP_TOLERANCE_M`;
- an obstacle of a move touching, or nearer than :data:`OBSTACLE_GAP_M` to, any object
  where it stands when that move starts (the moved object at its start or its previous goal,
  the others at their start poses or where their own moves left them), or the moved object at
  the move's goal. An obstacle switched on against an object, or standing where the object
  must be set down, makes a contact the judge fails whatever the robot does.

Shapes are compared exactly (FCL, :func:`worlds.fcl_shapes.penetration_depth`), so objects
standing side by side, or one stacked on another, pass.
"""

from __future__ import annotations

from collections.abc import Collection

import numpy as np

from affordances.context import Shape
from skills import quaternion as quat
from skills.flip import vertical_half_extent
from worlds.fcl_shapes import penetration_depth, shape_gap
from worlds.fixture_spec import FixtureSpec
from worlds.spec import ObjectSpec, ObstacleSpec, ShapeSpec, WorldSpec
from worlds.world_errors import WorldFileProblem

#: How far below the table top an object's bottom may start, m (a millimetre of numerical
#: slack; PyBullet resolves that without a jolt).
SINK_TOLERANCE_M = 0.001
#: How deep two bodies may interpenetrate at the start, m (touching is fine).
OVERLAP_TOLERANCE_M = 0.002
#: Least gap between an obstacle and an object where the object stands when a move naming the
#: obstacle starts, and at the move's goal, m: a touching obstacle is a contact.
OBSTACLE_GAP_M = 0.001
#: An object the task does not move that is within this of a moved one, m, with its centre
#: over that object's footprint, rests on it (a ball on a tray): after that object's moves,
#: where it lies is not known.
LOADED_GAP_M = 0.005

#: How far from resting on a face (a box's axis, or a cylinder's, vertical or a cylinder's
#: level) an object may be turned at its start or goal, deg: tilted further it rests on an
#: edge, where it cannot stay.
REST_TILT_DEG = 2.0

Quat = tuple[float, float, float, float]
Vec3 = tuple[float, float, float]
_UPRIGHT: Quat = (0.0, 0.0, 0.0, 1.0)


def fmt(value: float) -> str:
    """A length or angle for a message, to three significant figures."""
    return f"{value:.3g}"


def vec(values: tuple[float, ...] | np.ndarray) -> str:
    """A vector for a message: ``[0.6, 0, 0.675]``."""
    return "[" + ", ".join(fmt(float(v)) for v in values) + "]"


def resting_half_height(obj: ObjectSpec, quaternion: Quat) -> float:
    """Half the object's extent along world z when turned by ``quaternion``, m."""
    return float(vertical_half_extent(obj.shape.extents(), quaternion))


def off_face_deg(shape: ShapeSpec, quaternion: Quat) -> float:
    """How far ``shape`` turned by ``quaternion`` is from resting on a face of its own, deg:
    a box's nearest axis from the vertical; a cylinder's axis from the vertical (standing) or
    the level (lying), the nearer; 0 for a sphere, and for a mesh (not checked: its faces are
    its hull's)."""
    if shape.kind in (Shape.SPHERE, Shape.MESH):
        return 0.0
    rotation = quat.to_matrix(np.asarray(quaternion, dtype=float))
    up = np.abs(rotation[2])  # each body axis's component along world z
    if shape.kind is Shape.CYLINDER:
        standing = float(np.degrees(np.arccos(min(1.0, up[2]))))
        return min(standing, abs(90.0 - standing))
    return float(np.degrees(np.arccos(min(1.0, float(up.max())))))


def face_problem(obj: ObjectSpec, quaternion: Quat) -> tuple[str, str] | None:
    """What a resting pose of ``obj`` should be and what it is, if turned by ``quaternion``
    off every face it could rest on; else None."""
    off = off_face_deg(obj.shape, quaternion)
    if off <= REST_TILT_DEG:
        return None
    faces = (
        "its axis vertical or level"
        if obj.shape.kind is Shape.CYLINDER
        else "one of its axes vertical (roll and pitch multiples of 90 deg)"
    )
    return (
        f"{obj.name} resting on a face, {faces} within {fmt(REST_TILT_DEG)} deg",
        f"rpy_deg {vec(np.degrees(quat.to_rpy(quaternion)))}: {fmt(off)} deg off its nearest face, "
        "on an edge it cannot stay on",
    )


def start_problems(
    spec: WorldSpec, bad_goals: Collection[tuple[int, int]] = ()
) -> list[WorldFileProblem]:
    """Every body that starts sunk into the table or inside another body, and every goal
    inside another object where that object stands when the move ends.

    Parameters
    ----------
    spec : WorldSpec
    bad_goals : collection of (step, move) index pairs
        Goals already reported (off the table, in the air): after one, the object is nowhere
        it can be, so no obstacle is checked against it.

    Returns
    -------
    list of WorldFileProblem
        Fields are paths in the world file (``objects[1].pose.position``).
    """
    problems: list[WorldFileProblem] = []
    objects = spec.scene.objects
    table = spec.scene.table
    tx, ty, top = table.position
    for k, obj in enumerate(objects):
        tilted = face_problem(obj, obj.quaternion)
        if tilted is not None:
            problems.append(WorldFileProblem(f"objects[{k}].pose.rpy_deg", *tilted))
        x, y, z = obj.position
        over = abs(x - tx) <= table.size[0] / 2.0 and abs(y - ty) <= table.size[1] / 2.0
        half = resting_half_height(obj, obj.quaternion)
        if over and z - half < top - SINK_TOLERANCE_M:
            problems.append(
                WorldFileProblem(
                    f"objects[{k}].pose.position",
                    f"z >= {fmt(top + half)} m, so {obj.name} stands on the table top "
                    f"({fmt(top)} m + half its height {fmt(half)} m)",
                    f"z = {fmt(z)} m: {fmt(top - (z - half))} m of it inside the table",
                )
            )
    for k, obj in enumerate(objects):
        for other in objects[:k]:
            depth = _depth(
                obj, obj.position, obj.quaternion, other, other.position, other.quaternion
            )
            if depth > OVERLAP_TOLERANCE_M:
                problems.append(
                    WorldFileProblem(
                        f"objects[{k}].pose.position",
                        f"{obj.name} clear of {other.name} at the start",
                        f"{vec(obj.position)}: {fmt(depth * 1000)} mm inside {other.name} "
                        f"at {vec(other.position)}",
                    )
                )
    for f, fixture in enumerate(spec.scene.fixtures):
        walls = _fixture_walls(fixture)
        for obj in objects:
            depth = _wall_depth(obj, obj.position, obj.quaternion, walls)
            if depth > OVERLAP_TOLERANCE_M:
                problems.append(
                    WorldFileProblem(
                        f"fixtures[{f}].position",
                        f"{fixture.name}'s walls clear of {obj.name} at its start",
                        f"{vec(fixture.position[:2])}: a wall {fmt(depth * 1000)} mm inside "
                        f"{obj.name} at {vec(obj.position)}",
                    )
                )
        for i, step in enumerate(spec.task):
            obj = next(o for o in objects if o.name == step.object)
            for j, move in enumerate(step.moves):
                if move.fixture == fixture.name or (i, j) in bad_goals:
                    continue  # seated in it: inside its walls by their clearance
                depth = _wall_depth(obj, move.goal_position, move.goal_quaternion, walls)
                if depth > OVERLAP_TOLERANCE_M:
                    problems.append(
                        WorldFileProblem(
                            f"task[{i}].moves[{j}].goal.position",
                            f"a goal where {obj.name} is clear of {fixture.name}'s walls",
                            f"{vec(move.goal_position)}: {fmt(depth * 1000)} mm inside a wall "
                            f"of {fixture.name} at {vec(fixture.position[:2])}",
                        )
                    )
    obstacles = {o.name: (i, o) for i, o in enumerate(spec.scene.obstacles)}
    by_name = {obj.name: obj for obj in objects}
    # Where each object is as the task goes on: its start pose until its moves, then the
    # goal of its last move (a goal already reported off the table: no longer known).
    poses: dict[str, tuple[Vec3, Quat] | None] = {
        obj.name: (obj.position, obj.quaternion) for obj in objects
    }
    task_objects = {step.object for step in spec.task}
    done: set[str] = set()  # the objects moved so far
    for i, step in enumerate(spec.task):
        carried = by_name[step.object]
        for j, move in enumerate(step.moves):
            good = (i, j) not in bad_goals
            goal = (move.goal_position, move.goal_quaternion)
            here = poses[step.object]
            for body, pose in list(poses.items()):
                if body == step.object or pose is None:
                    continue
                if body not in task_objects and here is not None:
                    if _rides_on(by_name[body], pose, carried, here):
                        # It goes where the carry takes it, so where it ends is not known.
                        poses[body] = None
                        continue
                if not good:
                    continue
                depth = _depth(carried, *goal, by_name[body], *pose)
                if depth > OVERLAP_TOLERANCE_M:
                    at = "where its last move put it" if body in done else "where it stands"
                    problems.append(
                        WorldFileProblem(
                            f"task[{i}].moves[{j}].goal.position",
                            f"a goal where {step.object} is clear of {body} ({at} then)",
                            f"{vec(goal[0])}: {fmt(depth * 1000)} mm inside {body} at "
                            f"{vec(pose[0])}",
                        )
                    )
            for name in move.obstacles:
                o, obstacle = obstacles[name]
                where: list[tuple[str, tuple[Vec3, Quat], str]] = []
                for body, pose in poses.items():
                    if pose is None:
                        continue
                    moved = body == step.object
                    at = (
                        (
                            "at its start pose"
                            if j == 0
                            else f"at the goal of its move {j} (task[{i}].moves[{j - 1}])"
                        )
                        if moved
                        else "where it stands"
                    )
                    where.append((body, pose, f"{at} when task[{i}].moves[{j}] starts"))
                if good:
                    where.append((step.object, goal, f"at the goal of task[{i}].moves[{j}]"))
                for body, pose, at in where:
                    gap = _obstacle_gap(obstacle, by_name[body], *pose)
                    if gap < OBSTACLE_GAP_M:
                        problems.append(
                            WorldFileProblem(
                                f"obstacles[{o}].position",
                                f"{name} at least {fmt(OBSTACLE_GAP_M * 1000)} mm clear of "
                                f"{body} {at}",
                                f"{vec(obstacle.position)}: {_gap_words(gap)} {body} at "
                                f"{vec(pose[0])}",
                            )
                        )
            poses[step.object] = goal if good else None
            done.add(step.object)
    return problems


def _gap_words(gap: float) -> str:
    if abs(gap) < 1e-6:  # FCL's distances between touching shapes are off by rounding alone
        return "touching"
    if gap < 0.0:
        return f"{fmt(-gap * 1000)} mm inside"
    return f"{fmt(gap * 1000)} mm from"


def _depth(
    obj: ObjectSpec,
    position: Vec3,
    quaternion: Quat,
    other: ObjectSpec,
    other_position: Vec3,
    other_quaternion: Quat,
) -> float:
    """How deep ``obj`` and ``other``, at the poses given, interpenetrate, m (negative: their
    gap). A tray is its floor and walls: a ball lying inside it is clear of it."""
    return max(
        penetration_depth(a, pose_a, b, pose_b)
        for a, pose_a in _parts(obj.shape, position, quaternion)
        for b, pose_b in _parts(other.shape, other_position, other_quaternion)
    )


def _fixture_walls(fixture: FixtureSpec) -> list[tuple[ShapeSpec, tuple[Vec3, Quat]]]:
    """A fixture's four walls as boxes with their world poses."""
    centres, halves = fixture.walls()
    q = fixture.quaternion
    rotation = quat.to_matrix(np.asarray(q, dtype=float))
    origin = np.asarray(fixture.position, dtype=float)
    walls = []
    for centre, half in zip(centres, halves, strict=True):
        x, y, z = (float(v) for v in origin + rotation @ centre)
        walls.append((ShapeSpec.box(2.0 * half), ((x, y, z), q)))
    return walls


def _wall_depth(
    obj: ObjectSpec,
    position: Vec3,
    quaternion: Quat,
    walls: list[tuple[ShapeSpec, tuple[Vec3, Quat]]],
) -> float:
    """How deep ``obj`` at the pose given and a fixture's ``walls`` interpenetrate, m."""
    return max(
        penetration_depth(part, pose, wall, wall_pose)
        for part, pose in _parts(obj.shape, position, quaternion)
        for wall, wall_pose in walls
    )


def _rides_on(
    rider: ObjectSpec, pose: tuple[Vec3, Quat], carrier: ObjectSpec, at: tuple[Vec3, Quat]
) -> bool:
    """``rider`` at ``pose`` rests on ``carrier`` at ``at`` (a ball on a tray's floor, a box
    on another): within :data:`LOADED_GAP_M` of it, its centre over the carrier's footprint
    and above the carrier's centre. One standing beside the carrier does not ride on it."""
    offset = quat.rotate(
        quat.conjugate(np.asarray(at[1], dtype=float)),
        np.asarray(pose[0], dtype=float) - np.asarray(at[0], dtype=float),
    )
    half = np.asarray(carrier.shape.extents(), dtype=float) / 2.0
    over = bool(np.all(np.abs(offset[:2]) <= half[:2])) and offset[2] > 0.0
    return over and _clearance(rider, *pose, carrier, *at) < LOADED_GAP_M


def _clearance(
    obj: ObjectSpec,
    position: Vec3,
    quaternion: Quat,
    other: ObjectSpec,
    other_position: Vec3,
    other_quaternion: Quat,
) -> float:
    """The signed gap between ``obj`` and ``other`` at the poses given, m (as :func:`_depth`,
    part by part)."""
    return min(
        shape_gap(a, pose_a, b, pose_b)
        for a, pose_a in _parts(obj.shape, position, quaternion)
        for b, pose_b in _parts(other.shape, other_position, other_quaternion)
    )


def _parts(
    shape: ShapeSpec, position: Vec3, quaternion: Quat
) -> list[tuple[ShapeSpec, tuple[Vec3, Quat]]]:
    """A shape as solid parts with their world poses: a tray's boxes, else the shape itself."""
    if not shape.is_tray:
        return [(shape, (position, quaternion))]
    q = np.asarray(quaternion, dtype=float)
    parts: list[tuple[ShapeSpec, tuple[Vec3, Quat]]] = []
    for half, centre in shape.tray_boxes():
        x, y, z = (float(v) for v in np.asarray(position) + quat.rotate(q, np.asarray(centre)))
        parts.append((ShapeSpec.box(2.0 * np.asarray(half)), ((x, y, z), quaternion)))
    return parts


def _obstacle_gap(
    obstacle: ObstacleSpec,
    obj: ObjectSpec,
    position: tuple[float, float, float],
    quaternion: Quat,
) -> float:
    # A tray is its floor and walls: a sphere over a tray's well is as far as its nearest part.
    return min(
        shape_gap(obstacle.shape, (obstacle.position, _UPRIGHT), part, pose)
        for part, pose in _parts(obj.shape, position, quaternion)
    )


__all__ = [
    "OBSTACLE_GAP_M",
    "OVERLAP_TOLERANCE_M",
    "SINK_TOLERANCE_M",
    "fmt",
    "resting_half_height",
    "start_problems",
    "vec",
]

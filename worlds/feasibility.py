"""Can the robot do a world's task at all? Cheap checks before any simulation.

Each check reads only the world's dataclasses (:mod:`worlds.spec`), the reasoner's hard stage
and the robot's kinematic chain (:mod:`worlds.robots.reach`); none loads PyBullet. They find
what would otherwise fail only after seconds of simulation:

- an object no grasp the robot can make fits (wider than the palms' span, too heavy for the
  grip, a one-arm grasp without a gripper): the reasoner's refusals, one per grasp;
- a goal off the table: the object's centre must be over the table top's footprint (so its
  weight rests on the table) and at the height where it rests on the top, within
  :data:`REST_TOLERANCE_M` (lower is inside the table; higher drops it on release);
- a start or goal that turns an object off every face it could rest on
  (:func:`worlds.placement.face_problem`), and an object the task moves that does not start
  upright on its own z axis (its grasps are planned on the axes it stands on);
- a mesh object whose file is not centred on its origin (:mod:`worlds.mesh_sides`);
- a body that starts sunk into the table or inside another (:mod:`worlds.placement`);
- a goal out of reach: each palm of a grasp the reasoner offers, placed at the goal, must lie
  inside its arm's reach sphere (:func:`worlds.robots.reach.arm_reach`). The palms are taken
  at the contact faces' centres; the sphere bounds every posture, so a goal it refuses is out
  of reach for certain.

Problems name the world file's field (``task[0].moves[1].goal.position``, ``objects[0]``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import replace

import numpy as np

from affordances.actions import GRASP_ORDER
from affordances.config import ReasonerConfig
from affordances.context import ObjectContext, RobotCapabilities
from affordances.physics import GraspOption, HardAssessment, assess
from skills import quaternion as quat
from skills.turns import turn_steps
from skills.vocabulary import Arm, GraspType
from worlds.adapters import object_contexts, robot_capabilities
from worlds.mesh_sides import CENTRE_TOLERANCE_M, mesh_centre
from worlds.placement import REST_TILT_DEG, face_problem, resting_half_height, start_problems
from worlds.placement import fmt as _fmt
from worlds.placement import vec as _vec
from worlds.robots import robot_model_of
from worlds.robots.reach import ArmReach, arm_reach
from worlds.spec import MoveSpec, ObjectSpec, Shape, TableSpec, WorldSpec
from worlds.world_errors import WorldFileError, WorldFileProblem
from worlds.world_file import World, as_world_spec

#: How far a goal's height may be from the object resting on the table top, m: a centimetre
#: is half the 2 cm a placement is judged by.
REST_TOLERANCE_M = 0.01


def _off_table(position: Sequence[float], table: TableSpec) -> tuple[str, str] | None:
    """What a centre should be and what it is, if ``position`` is not over the table top's
    footprint; else None."""
    tx, ty, _ = table.position
    half_x, half_y = table.size[0] / 2.0, table.size[1] / 2.0
    x_range, y_range = (tx - half_x, tx + half_x), (ty - half_y, ty + half_y)
    beyond = []
    for axis, value, (low, high) in (("x", position[0], x_range), ("y", position[1], y_range)):
        if value < low:
            beyond.append(
                f"{_fmt(low - value)} m beyond the table's edge at {axis} = {_fmt(low)} m"
            )
        elif value > high:
            beyond.append(
                f"{_fmt(value - high)} m beyond the table's edge at {axis} = {_fmt(high)} m"
            )
    if beyond:
        return (
            f"a goal over the table top (x {_fmt(x_range[0])}..{_fmt(x_range[1])} m, "
            f"y {_fmt(y_range[0])}..{_fmt(y_range[1])} m)",
            f"{_vec(tuple(position))}: " + " and ".join(beyond),
        )
    return None


def _table_problem(obj: ObjectSpec, move: MoveSpec, table: TableSpec) -> tuple[str, str] | None:
    """What the goal should be and what it is, if it is not where the object rests on the
    table; else None."""
    off = _off_table(move.goal_position, table)
    if off is not None:
        return off
    top = table.position[2]
    gz = move.goal_position[2]
    half = resting_half_height(obj, move.goal_quaternion)
    rest = top + half
    if abs(gz - rest) > REST_TOLERANCE_M:
        return (
            f"z = {_fmt(rest)} m within {_fmt(REST_TOLERANCE_M)} m, where {obj.name} rests on "
            f"the table top ({_fmt(top)} m + half its height {_fmt(half)} m)",
            f"z = {_fmt(gz)} m",
        )
    return None


def _not_upright(obj: ObjectSpec) -> tuple[str, str] | None:
    """What the start of an object the task moves should be and what it is, if it does not
    stand on its own z axis (its grasps are planned on the axes it stands on; a flip is a
    goal's, from upright); else None."""
    rotation = quat.to_matrix(np.asarray(obj.quaternion, dtype=float))
    tilt = float(np.degrees(np.arccos(np.clip(rotation[2, 2], -1.0, 1.0))))
    if tilt <= REST_TILT_DEG:
        return None
    rpy = _vec(np.degrees(quat.to_rpy(np.asarray(obj.quaternion, dtype=float))))
    if obj.shape.kind is Shape.BOX:
        size = np.abs(rotation) @ np.asarray(obj.shape.size, dtype=float)  # along world x, y, z
        how = (
            f"the same box standing is size {_vec(size)} with rpy_deg [0, 0, 0] (a box "
            "standing on another face is its size given in that frame)"
        )
    elif obj.shape.kind is Shape.MESH:
        how = "turn the mesh file's vertices so that it stands on its z axis"
    else:
        how = "a cylinder is grasped standing, across its diameter"
    return (
        f"{obj.name} upright at its start, its z axis up within {_fmt(REST_TILT_DEG)} deg (its "
        "grasps are planned on the axes it stands on)",
        f"rpy_deg {rpy}: its z axis {_fmt(tilt)} deg from up; {how}",
    )


def _mesh_off_centre(obj: ObjectSpec) -> tuple[str, str] | None:
    """What a mesh object's file should be and what it is, if the mesh is not centred on its
    origin (its pose, rests and grasps are reckoned from its bounding box's centre); else
    None."""
    if obj.shape.kind is not Shape.MESH:
        return None
    centre = mesh_centre(obj.shape)
    if float(np.max(np.abs(centre))) <= CENTRE_TOLERANCE_M:
        return None
    return (
        f"a mesh centred on its origin (its bounding box's centre within "
        f"{_fmt(CENTRE_TOLERANCE_M * 1000)} mm of [0, 0, 0]: {obj.name}'s position is its "
        "origin's, and its rests and grasps are reckoned from its centre)",
        f"{obj.shape.mesh_path}: its bounding box centred at {_vec(centre)} m; move its "
        "vertices by minus that",
    )


def _robot_problem(spec: WorldSpec) -> WorldFileProblem | None:
    """Why the robot cannot stand where the world puts it: an arm's base inside the table
    top's footprint (the robot would stand in the table); else None."""
    table = spec.scene.table
    tx, ty, _ = table.position
    half_x, half_y = table.size[0] / 2.0, table.size[1] / 2.0
    model = robot_model_of(spec.scene.robot)
    for arm in (Arm.LEFT, Arm.RIGHT):
        x, y, _ = model.bodies[model.arms[arm].body].base2world_position
        if abs(x - tx) < half_x and abs(y - ty) < half_y:
            return WorldFileProblem(
                "robot.base.position",
                f"a robot beside the table, its arms' bases off the table top "
                f"(x {_fmt(tx - half_x)}..{_fmt(tx + half_x)} m, "
                f"y {_fmt(ty - half_y)}..{_fmt(ty + half_y)} m)",
                f"{_vec(spec.scene.robot.base_position)}: the {arm.value} arm's base at "
                f"[{_fmt(x)}, {_fmt(y)}] m stands inside it",
            )
    return None


def _out_of_reach(option: GraspOption, reach: Mapping[Arm, ArmReach]) -> str | None:
    """How a grasp's palms at the goal fall outside their arms' reach, or None."""
    for arm, palm in zip(option.arms, option.palms, strict=True):
        sphere = reach[arm]
        distance = sphere.distance_m(palm)
        if distance > sphere.radius_m:
            return (
                f"{option.grasp.value} puts the {arm.value} palm at {_vec(palm)}, "
                f"{_fmt(distance)} m from the centre of the {arm.value} arm's reach "
                f"({sphere.joint} at {_vec(sphere.shoulder)}); "
                f"the arm reaches at most {_fmt(sphere.radius_m)} m"
            )
    return None


def _no_grasp(hard: HardAssessment, grasps: Collection[GraspType] | None) -> str:
    """Why no grasp is left: the reasoner's refusals, and the feasible ones the tree won't make."""
    if grasps is None:
        return hard.no_grasp_reason()
    made = ", ".join(sorted(g.value for g in grasps))
    why = {r.grasp: r.why for r in hard.refused}
    why.update({o.grasp: f"the tree makes only {made}" for o in hard.options})
    return "; ".join(f"{g.value}: {why[g]}" for g in GRASP_ORDER if g in why)


def feasibility_problems(
    world: World | WorldSpec, grasps: Collection[GraspType] | None = None
) -> list[WorldFileProblem]:
    """Every reason the world's task cannot work, found without simulating.

    Parameters
    ----------
    world : World or WorldSpec
        A validated world.
    grasps : collection of GraspType, optional
        The grasps the tree that will run makes (its leaves implement); any if None.

    Returns
    -------
    list of WorldFileProblem
        Empty when the checks pass; fields are paths in the world file.
    """
    spec = as_world_spec(world)
    standing = _robot_problem(spec)
    if standing is not None:  # every other check assumes the robot stands beside the table
        return [standing]
    robot = robot_capabilities(spec)
    config = ReasonerConfig.under(spec.scene.gravity)
    contexts = {c.name: c for c in object_contexts(spec)}
    reach = arm_reach(robot_model_of(spec.scene.robot))
    index = {obj.name: k for k, obj in enumerate(spec.scene.objects)}
    problems: list[WorldFileProblem] = []
    graspable: dict[str, bool] = {}
    bad_goals: set[tuple[int, int]] = set()

    def usable(options: tuple[GraspOption, ...]) -> list[GraspOption]:
        return [o for o in options if grasps is None or o.grasp in grasps]

    # An object the task does not move (a ball loose on a tray) need not be graspable.
    moved = {step.object for step in spec.task}
    for k, obj in enumerate(spec.scene.objects):
        off_centre = _mesh_off_centre(obj)
        if off_centre is not None:
            problems.append(WorldFileProblem(f"objects[{k}].shape.file", *off_centre))
        lying = _not_upright(obj) if obj.name in moved else None
        if lying is not None:
            problems.append(WorldFileProblem(f"objects[{k}].pose.rpy_deg", *lying))
            graspable[obj.name] = False  # its grasps would be planned on the wrong axes
            continue
        hard = assess(contexts[obj.name], robot, config)
        graspable[obj.name] = bool(usable(hard.options))
        if not graspable[obj.name] and obj.name in moved:
            problems.append(
                WorldFileProblem(
                    f"objects[{k}]",
                    "a grasp the robot can make",
                    f"none for {obj.name}: {_no_grasp(hard, grasps)}",
                )
            )
    robot_yaw = math.radians(spec.scene.robot.base_rpy_deg[2])
    # Where each object's last move left it, over the task's steps: its yaw and its turn
    # about its grasp axis (it starts upright, _not_upright).
    left_at = {obj.name: (obj.yaw, 0.0) for obj in spec.scene.objects}
    for i, step in enumerate(spec.task):
        obj = spec.scene.objects[index[step.object]]
        yaw, pitch = left_at[obj.name]
        for j, move in enumerate(step.moves):
            field = f"task[{i}].moves[{j}].goal.position"
            before, yaw = yaw, move.goal_yaw
            stepped = _stepped_into_fixture(move, before, robot.max_turn_rad, robot_yaw)
            if stepped is not None:
                problems.append(WorldFileProblem(f"task[{i}].moves[{j}].goal.rpy_deg", *stepped))
            tilted = face_problem(obj, move.goal_quaternion)
            if tilted is not None:
                problems.append(WorldFileProblem(f"task[{i}].moves[{j}].goal.rpy_deg", *tilted))
                bad_goals.add((i, j))
                continue
            written = _goal_rpy(world, i, j)
            turned = _turn_problem(obj, move.goal_quaternion, pitch, written)
            if turned is not None:
                problems.append(WorldFileProblem(f"task[{i}].moves[{j}].goal.rpy_deg", *turned))
                bad_goals.add((i, j))
                continue
            pitch = grasp_pitch(move.goal_quaternion)
            table = _table_problem(obj, move, spec.scene.table)
            if table is not None:
                problems.append(WorldFileProblem(field, *table))
                bad_goals.add((i, j))
                continue
            if not graspable[obj.name]:
                continue
            miss = _reach_problem(contexts[obj.name], move, robot, config, reach, grasps)
            if miss is not None:
                problems.append(WorldFileProblem(field, *miss))
        left_at[obj.name] = (yaw, pitch)
    return start_problems(spec, bad_goals) + problems


#: The most a carry turns an object about its grasp axis (its y axis), deg: the box flip's
#: quarter turn, up or down (a half turn had been split into four carries and dropped).
MAX_PITCH_DEG = 90.0


def grasp_pitch(quaternion: Sequence[float]) -> float:
    """The turn about its own y axis (the grasp's) that, after a yaw, poses an object at
    ``quaternion`` from upright, rad (its y axis level: ``Rz(yaw) Ry(pitch)``)."""
    rotation = quat.to_matrix(np.asarray(quaternion, dtype=float))
    return math.atan2(-float(rotation[2, 0]), float(rotation[2, 2]))


def _goal_rpy(world: World | WorldSpec, step: int, move: int) -> Sequence[float] | None:
    """A goal's ``rpy_deg`` as the world file writes it (None for a spec built in code)."""
    if not isinstance(world, World):
        return None
    return world.task[step].moves[move].goal.rpy_deg


def _turn_problem(
    obj: ObjectSpec,
    goal: Sequence[float],
    pitch_before: float,
    written: Sequence[float] | None = None,
) -> tuple[str, str] | None:
    """What a goal's orientation should be and is, if the grip cannot turn ``obj`` to it
    from where its last move left it (``pitch_before``, rad): the grip, across the object's
    y faces, turns it about world z and about that y axis (:mod:`skills.flip`), a quarter turn
    at most in one carry; a roll tilts the y axis itself, which it cannot make. None if it
    can."""
    rotation = quat.to_matrix(np.asarray(goal, dtype=float))
    shown = written if written is not None else np.degrees(quat.to_rpy(np.asarray(goal, float)))
    rpy = _vec(np.round(np.asarray(shown, dtype=float), 6) + 0.0)
    expected = (
        f"a goal the grip turns {obj.name} to: about the vertical, and about its own y axis "
        f"(the grip's) by at most {MAX_PITCH_DEG:g} deg in a move, its y axis level within "
        f"{_fmt(REST_TILT_DEG)} deg (a roll of 0: rpy_deg [0, pitch, yaw])"
    )
    tilt = math.degrees(math.asin(min(1.0, abs(float(rotation[2, 1])))))
    if tilt > REST_TILT_DEG:
        same = (
            "; a cylinder lying along y is rpy_deg [0, 90, 90]"
            if obj.shape.kind is Shape.CYLINDER
            else ""
        )
        return (
            expected,
            f"rpy_deg {rpy}: its y axis {_fmt(tilt)} deg from level, a roll the grip across "
            f"its y faces cannot make{same}",
        )
    pitch = grasp_pitch(goal)
    turn = abs(math.degrees(math.remainder(pitch - pitch_before, 2.0 * math.pi)))
    if turn > MAX_PITCH_DEG + REST_TILT_DEG:
        upside = (
            " (a cylinder upside down is the same cylinder upright: rpy_deg [0, 0, yaw])"
            if obj.shape.kind is Shape.CYLINDER
            else ""
        )
        return (
            expected,
            f"rpy_deg {rpy}: a turn of {_fmt(turn)} deg about its y axis from where its last "
            f"move left it{upside}",
        )
    return None


def _stepped_into_fixture(
    move: MoveSpec, yaw: float, max_turn: float, robot_yaw: float
) -> tuple[str, str] | None:
    """What a move into a fixture should be and is, if its turn from ``yaw`` takes the grip
    more than one carry (:func:`skills.turns.turn_steps`): the steps before the last would set
    the object down turned part of the way, where the fixture's walls stand."""
    if move.fixture is None:
        return None
    steps = turn_steps(yaw, move.goal_yaw, max_turn, robot_yaw)
    if len(steps) < 2:
        return None
    turn = math.degrees(steps[-1] - yaw)
    return (
        f"a goal in fixture {move.fixture} the grip turns to in one carry (at most "
        f"{math.degrees(max_turn):.0f} deg from where the object stands before the move)",
        f"a turn of {turn:.0f} deg, {len(steps)} carries, each set down turned part of the way "
        f"where the walls stand: turn the fixture, or start the object, within "
        f"{math.degrees(max_turn):.0f} deg of it",
    )


def _reach_problem(
    context: ObjectContext,
    move: MoveSpec,
    robot: RobotCapabilities,
    config: ReasonerConfig,
    reach: Mapping[Arm, ArmReach],
    grasps: Collection[GraspType] | None,
) -> tuple[str, str] | None:
    """What the goal should be and what it is, if every grasp offered there (and made by the
    tree: ``grasps``, any if None) puts a palm out of its arm's reach; else None."""
    at_goal = replace(context, position=move.goal_position, yaw=move.goal_yaw, goals=())
    options = [
        o for o in assess(at_goal, robot, config).options if grasps is None or o.grasp in grasps
    ]
    misses = [_out_of_reach(o, reach) for o in options]
    if options and all(m is not None for m in misses):
        return "a goal within the arms' reach", str(misses[0])
    return None


def goal_checker(
    spec: WorldSpec, name: str
) -> Callable[[Sequence[float], float], tuple[str, str] | None]:
    """The check :func:`feasibility_problems` makes of each goal of object ``name``, for goals
    given by their centre ``xy`` (m, world frame) and yaw (degrees), upright and resting on the
    table top: what the goal should be and what it is, if it lies off the table top's
    footprint or every grasp there puts a palm out of its arm's reach; else None. The object,
    robot and reach are read once, for every goal asked."""
    obj = next(o for o in spec.scene.objects if o.name == name)
    context = next(c for c in object_contexts(spec) if c.name == name)
    robot = robot_capabilities(spec)
    reach = arm_reach(robot_model_of(spec.scene.robot))
    config = ReasonerConfig.under(spec.scene.gravity)

    def check(xy: Sequence[float], yaw_deg: float) -> tuple[str, str] | None:
        yaw = math.radians(yaw_deg)
        qx, qy, qz, qw = (float(v) for v in quat.from_rpy(np.array([0.0, 0.0, yaw])))
        quaternion = (qx, qy, qz, qw)
        z = spec.scene.table.position[2] + resting_half_height(obj, quaternion)
        move = MoveSpec(
            goal_position=(float(xy[0]), float(xy[1]), float(z)),
            goal_quaternion=quaternion,
            goal_yaw=yaw,
        )
        off = _off_table(move.goal_position, spec.scene.table)
        if off is not None:
            return off
        return _reach_problem(context, move, robot, config, reach, None)

    return check


def check_feasible(world: World | WorldSpec, file: str) -> None:
    """Raise :class:`WorldFileError` naming ``file`` if :func:`feasibility_problems` finds any."""
    problems = feasibility_problems(world)
    if problems:
        raise WorldFileError(file, problems)


__all__ = [
    "REST_TOLERANCE_M",
    "check_feasible",
    "feasibility_problems",
    "goal_checker",
    "resting_half_height",
]

"""Trial layouts: what each trial of a campaign draws, and whether a world's can be drawn.

Each trial draws, from ``numpy.random.default_rng([seed, trial])`` and within the world
file's ``trials`` section (:class:`worlds.world_file.TrialSettings`, as the workspace depends
on the robot):

- the parcel's start on the table, near the robot's centre line;
- one goal per move in its region (:meth:`~worlds.world_file.TrialSettings.goal_regions`: the
  paper's three, centre, right (-y) and left (+y), or the section's own ``moves``), each
  with a yaw drawn within the move's range;
- for every move but at most one (drawn at random, and kept free with probability 1/2) a new
  sphere, either *on the line*: above the straight path between the move's start and goal,
  under the demonstrated lift, or *ahead*: in front of the carry (along the robot's forward
  axis, +x for a robot facing +x) at the lifted parcel's height, of the kinds the move's
  region allows (a region without kinds gets no sphere). Every sphere clears the parcel at
  its move's start and goal (``clearance``), and the robot itself, posed grasping the parcel
  there, at rest and lifted by ``lift`` (``robot_clearance``, measured by PyBullet on the
  robot's own collision shapes), so only the carry can meet it: a sphere the robot would
  have to be in to pick the parcel up or put it down is not a test of avoidance.

:func:`check_trial_layout` tells, before a campaign starts, a world whose trials cannot be
drawn. The campaign that runs them is :mod:`experiment.trials`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from pydantic import ValidationError

from duet_robot.closing import Closing
from experiment.flip_draws import draw_object, goal_half_height, pitched_goal_postures
from experiment.insertion_trials import place_fixture

# Re-exported: the summary lives below the simulation, for reports that need no PyBullet.
from experiment.summary import composition_label as composition_label
from experiment.summary import reason_of as reason_of
from experiment.summary import summarise as summarise
from experiment.tray_draws import place_riders, tray_height, tray_layout_problem
from experiment.trial_regions import region_problems
from skills.turns import move_holds
from worlds.adapters import robot_capabilities
from worlds.bullet import pb
from worlds.palm_poses import lateral_grasp_palm_poses
from worlds.placement import start_problems, vec
from worlds.scene import Scene
from worlds.trays import riders
from worlds.world_errors import problems_from
from worlds.world_file import (
    BoxShape,
    CylinderShape,
    GoalRegion,
    ObstacleKind,
    Region,
    TrayShape,
    TrialSettings,
    World,
    as_world_spec,
    turn_free,
    world_from_data,
    world_spec,
)

#: Goal yaws drawn for a move before giving up on placing its sphere: the robot turning the
#: object must be clear of it too, and some turns leave no room for a sphere on the way.
YAW_ATTEMPTS = 8
#: Times a trial with turns is drawn again before giving up.
TRIAL_REDRAWS = 10
#: Spheres tried for one goal yaw.
SPHERE_ATTEMPTS = 200


@dataclass(frozen=True)
class Sphere:
    """An obstacle drawn for one move."""

    name: str
    centre: tuple[float, float, float]
    radius: float
    kind: ObstacleKind


def _box_gap(centre: np.ndarray, half: np.ndarray, point: np.ndarray, yaw: float = 0.0) -> float:
    """Distance from a point to the surface of a box turned by ``yaw`` about z (0 inside)."""
    c, s = math.cos(yaw), math.sin(yaw)
    dx, dy, dz = np.asarray(point, dtype=float) - centre
    local = np.array([c * dx + s * dy, -s * dx + c * dy, dz])
    d = np.maximum(np.abs(local) - half, 0.0)
    return float(np.linalg.norm(d))


@dataclass(frozen=True)
class Posture:
    """The robot holding the object somewhere on a move: where, and with which grip.

    Attributes
    ----------
    position : ndarray, shape (3,)
        The object's centre, m.
    object_yaw : float
        The object's yaw, rad.
    grip_yaw : float
        The palms' turn from their natural pose (:mod:`skills.turns`), rad.
    half_span : float
        Half the distance between the held faces, m.
    half_extents : ndarray, shape (3,), optional
        The box's half extents along its yawed frame's axes as held there (a box set down on
        its side, :mod:`experiment.flip_draws`), m; None: its own.
    """

    position: np.ndarray
    object_yaw: float
    grip_yaw: float
    half_span: float
    half_extents: np.ndarray | None = None


def move_postures(
    start: np.ndarray,
    start_yaw: float,
    goal: np.ndarray,
    goal_yaw: float,
    size: np.ndarray,
    max_turn: float,
    robot_yaw: float = 0.0,
) -> list[Posture]:
    """How the robot holds the object picking it up and putting it down on one move.

    A turn the grip cannot make in one grasp is made in steps at the goal
    (:func:`planner.port.stepped_moves`): each step's grasp at its start and its end
    (:func:`skills.turns.move_holds`), on the faces
    :func:`skills.turns.lateral_quarter_turns` chooses for it. (A world whose goal has no
    room makes them elsewhere, :mod:`worlds.turn_choice`; a drawn trial keeps its spheres
    clear of these holds, so its goal always has.)
    """
    return [
        Posture(
            h.position,
            h.object_yaw,
            h.grip_yaw,
            float(size[1] if h.quarter_turns % 2 == 0 else size[0]) / 2.0,
        )
        for h in move_holds(start, start_yaw, goal, goal_yaw, max_turn, robot_yaw)
    ]


class RobotClearance(Closing):
    """Distance from a sphere to the robot grasping the object at a given centre.

    The robot is posed by the same inverse-kinematics placement that starts an episode
    (:meth:`worlds.scene.Scene.place_palms`), palms on the object's +-y faces, in a scene of
    its own that is never stepped; PyBullet measures the distance on the robot's collision
    shapes, from one small probe ball (the distance to a sphere is the distance to its centre
    less its radius). Use as a context manager, or call :meth:`close`.
    """

    #: Radius of the probe ball, m.
    PROBE_RADIUS = 1e-3

    def __init__(self, world: World) -> None:
        self._scene = Scene.from_world(world)
        self._scene.set_active_obstacles(())
        object_size(world)  # a box, tray or mesh object to grasp, or a ValueError
        self._thickness = float(world.robot.palm_size[2])
        # The grips' yaws are the robot's (skills.turns): the palms turn with its heading.
        self._robot_yaw = math.radians(world.robot.base.rpy_deg[2])
        self._posed_at: tuple[float, ...] | None = None
        # Each posture's joint positions, per robot body and joint, as first solved (from the
        # posture tried before it, as every solve was when each candidate re-solved): a layout
        # draw tries hundreds of candidate spheres against the same few postures, and one
        # inverse-kinematics solve each, not one per candidate, makes the draw ~10x cheaper.
        self._solved: dict[tuple[float, ...], list[tuple[int, int, float]]] = {}
        client = self._scene.client
        shape = pb.createCollisionShape(
            pb.GEOM_SPHERE, radius=self.PROBE_RADIUS, physicsClientId=client
        )
        self._probe = pb.createMultiBody(0.0, shape, physicsClientId=client)
        self._loaded = self._joint_positions()

    def restart(self) -> None:
        """Forget every posture solved, and stand the robot as it was loaded: a draw that
        starts here measures what it would in a scene of its own."""
        self._solved.clear()
        self._posed_at = None
        self._reset(self._loaded)

    #: Farthest gap measured, m: beyond it :meth:`distance` is inf.
    REACH = 1.0

    def distance(
        self, posture: Posture, centre: np.ndarray, radius: float, within: float = REACH
    ) -> float:
        """Gap between a sphere and the nearest robot link holding the object in ``posture``,
        m (negative: overlap); inf if it is over ``within`` m (the links farther away are
        never measured: a draw asks only whether a sphere clears the robot by a margin)."""
        client = self._scene.client
        reach = min(within, self.REACH) + radius - self.PROBE_RADIUS
        key = (*(float(v) for v in posture.position), posture.grip_yaw, posture.half_span)
        if key != self._posed_at:
            self._pose(key, posture)
            self._posed_at = key
        pb.resetBasePositionAndOrientation(
            self._probe, list(centre), [0, 0, 0, 1], physicsClientId=client
        )
        gaps = [
            point[8]
            for body in self._scene.robot_ids
            for point in pb.getClosestPoints(self._probe, body, reach, physicsClientId=client)
        ]
        return min(gaps, default=math.inf) - (radius - self.PROBE_RADIUS)

    def _pose(self, key: tuple[float, ...], posture: Posture) -> None:
        """Pose the robot holding the object in ``posture`` (keyed ``key``): solved the first
        time, reset to its solution after."""
        solved = self._solved.get(key)
        if solved is None:
            self._scene.place_palms(
                lateral_grasp_palm_poses(
                    posture.position,
                    posture.half_span,
                    self._thickness,
                    grip_yaw=posture.grip_yaw + self._robot_yaw,
                )
            )
            solved = self._solved[key] = self._joint_positions()
        else:
            self._reset(solved)

    def _joint_positions(self) -> list[tuple[int, int, float]]:
        """(body, joint, position) of every joint the controller drives: all that placing the
        palms sets (:meth:`worlds.robots.RobotModel.driven_joints`)."""
        client = self._scene.client
        ids = self._scene.robot_ids
        return [
            (
                ids[d.body],
                d.joint,
                float(pb.getJointState(ids[d.body], d.joint, physicsClientId=client)[0]),
            )
            for d in self._scene.robot.driven_joints()
        ]

    def _reset(self, positions: list[tuple[int, int, float]]) -> None:
        """Reset every joint to its position in ``positions`` (:meth:`_joint_positions`), at
        rest: one call per body (a draw resets the robot thousands of times)."""
        client = self._scene.client
        bodies: dict[int, tuple[list[int], list[list[float]]]] = {}
        for body, joint, value in positions:
            joints, values = bodies.setdefault(body, ([], []))
            joints.append(joint)
            values.append([value])
        for body, (joints, values) in bodies.items():
            pb.resetJointStatesMultiDof(
                body,
                joints,
                targetValues=values,
                targetVelocities=[[0.0]] * len(joints),
                physicsClientId=client,
            )

    def close(self) -> None:
        """Disconnect the scene."""
        self._scene.close()


def _uniform(rng: np.random.Generator, bounds: tuple[float, float]) -> float:
    return float(rng.uniform(*bounds))


def _in_region(rng: np.random.Generator, region: Region, z: float) -> np.ndarray:
    return np.array([_uniform(rng, region.x), _uniform(rng, region.y), z])


#: The first trials the campaign's preflight tries to draw: a layout none of which it can
#: draw is refused (exit 2).
PREFLIGHT_TRIALS = 5


class DrawnWorldError(RuntimeError):
    """A trial's draw (a scaled size, a mass) that no world file may hold."""


def draw_trial(
    base: World, seed: int, trial: int, robot: RobotClearance | None = None
) -> tuple[World, list[str]]:
    """A variant of ``base`` for one trial and the kinds of obstacle per move.

    The base world gives the robot, table, object, simulation settings and the trial layout
    (``base.trials``); this draws the object's start, a goal per move and the obstacles.
    ``robot`` measures spheres against the robot (one is made for ``base`` if not given).
    """
    if robot is None:
        with RobotClearance(base) as own:
            return draw_trial(base, seed, trial, own)
    robot.restart()
    turning = any(_turns(region) for region in base.trials.goal_regions())
    # Objects that stand on the table through the trial (not the drawn one, nothing on it).
    standing = len(base.objects) - 1 - len(riding(base))
    again = TRIAL_REDRAWS if turning or standing else 1
    for redraw in range(again):
        try:
            drawn, kinds = _draw_trial(base, seed, trial, robot, redraw)
            if standing:
                # A start, goal or sphere drawn into an object standing there: drawn again.
                problems = start_problems(world_spec(drawn))
                if problems:
                    raise RuntimeError(problems[0].format("trial"))
            return drawn, kinds
        except RuntimeError:
            # A turn that leaves no room for the next move's sphere (the arms turned across
            # its way): the trial is drawn again from a stream of its own.
            if redraw == again - 1:
                raise
    raise AssertionError("unreachable")


#: The object shapes trials draw layouts around: their bounding boxes.
TRIAL_SHAPES = ("box", "tray", "mesh", "cylinder")


def object_size(world: World) -> tuple[float, float, float]:
    """Full extents of the world's first object, m: a box's or tray's size, a mesh's or
    an upright cylinder's bounding box (a mesh's file read); a ValueError for any other
    shape."""
    shape = world.objects[0].shape
    if shape.type not in TRIAL_SHAPES:
        raise ValueError(
            f"trials: expected a box, tray, mesh or cylinder object to grasp, got a {shape.type} "
            f"({world.objects[0].name!r})"
        )
    if isinstance(shape, BoxShape | TrayShape):
        return (float(shape.size[0]), float(shape.size[1]), float(shape.size[2]))
    return as_world_spec(world).scene.objects[0].shape.extents()  # a mesh's, its file read


def _turns(region: GoalRegion) -> bool:
    """Whether a move's goal yaw is drawn from a range rather than fixed."""
    assert region.yaw_deg is not None  # given by TrialSettings.goal_regions
    return region.yaw_deg[0] != region.yaw_deg[1]


def _yaw_range(region: GoalRegion) -> tuple[float, float]:
    assert region.yaw_deg is not None  # given by TrialSettings.goal_regions
    return region.yaw_deg


def _draw_trial(
    base: World, seed: int, trial: int, robot: RobotClearance, redraw: int
) -> tuple[World, list[str]]:
    """:func:`draw_trial` from stream ``redraw`` (0: the trial's own, as without turns)."""
    layout = base.trials
    rng = np.random.default_rng([seed, trial] if redraw == 0 else [seed, trial, 2, redraw])
    obj = base.objects[0]
    regions = layout.goal_regions()
    drawn = draw_object(layout, regions, object_size(base), seed, trial, redraw)
    cylinder = isinstance(obj.shape, CylinderShape)
    symmetric = turn_free(obj)
    if cylinder:
        drawn.size[1] = drawn.size[0]  # a scaled cylinder stays round
    if isinstance(obj.shape, TrayShape) and layout.size_scale is not None:
        # Its walls stay as tall as the palms need (experiment.tray_draws).
        palm = float(base.robot.palm_size[0])
        drawn.size[2] = tray_height(obj.shape.size[2], float(drawn.size[2]), palm)
    half = drawn.size / 2.0
    z = base.table.position[2] + half[2]
    start = _in_region(rng, layout.start, z)
    goals = [_in_region(rng, region, z) for region in regions]
    for goal, pitch in zip(goals, drawn.pitches, strict=True):
        goal[2] = base.table.position[2] + goal_half_height(drawn.size, pitch)
    # The yaws come from a generator of their own, so a layout without turns draws the same
    # starts, goals and spheres as before they were drawn.
    turn_rng = np.random.default_rng([seed, trial, 1, redraw])
    goal_yaws = [_uniform(turn_rng, _yaw_range(region)) for region in regions]
    start_yaw = math.radians(obj.pose.rpy_deg[2])
    max_turn = robot_capabilities(base).max_turn_rad
    robot_yaw = math.radians(base.robot.base.rpy_deg[2])
    size = 2.0 * half
    # Every move but at most one has a sphere (the paper's at least two of three).
    with_obstacle = [bool(region.obstacles) for region in regions]
    # The coin is drawn before the move it decides: the order of the draws the recorded
    # campaigns (bench/results) were drawn in.
    keep = bool(rng.random() < 0.5)
    free = int(rng.integers(len(regions)))
    with_obstacle[free] = with_obstacle[free] and keep
    spheres: list[Sphere | None] = []
    kinds: list[str] = []
    prev, prev_yaw = start, start_yaw
    for i, (goal, region) in enumerate(zip(goals, regions, strict=True)):
        sphere: Sphere | None = None
        low, high = _yaw_range(region)
        for attempt in range(YAW_ATTEMPTS):
            # The same yaw a whole turn apart is the same (a range may run past 180 degrees).
            if attempt == YAW_ATTEMPTS - 1 and (math.degrees(prev_yaw) - low) % 360.0 <= high - low:
                goal_yaws[i] = math.degrees(prev_yaw)  # at last, no turn at all
            elif attempt:  # no sphere fits the robot turning this way: another turn
                goal_yaws[i] = _uniform(turn_rng, (low, high))
            yaw = math.radians(goal_yaws[i])
            # An upright goal of an object a turn leaves as it was is reached unturned (the
            # run sends it so: worlds.world_file.turn_free), so its holds are the start's grip.
            if symmetric and drawn.pitches[i] == 0.0:
                yaw = prev_yaw
            postures = move_postures(prev, prev_yaw, goal, yaw, size, max_turn, robot_yaw)
            postures = pitched_goal_postures(postures, goal, half, drawn.pitches[i])
            if not with_obstacle[i]:
                break
            try:
                sphere = _draw_sphere(
                    rng,
                    f"ball_{i + 1}",
                    prev,
                    goal,
                    half,
                    layout,
                    region.obstacles,
                    robot,
                    postures,
                    robot_yaw,
                )
                break
            except RuntimeError:
                if attempt == YAW_ATTEMPTS - 1 or low == high:
                    raise
        spheres.append(sphere)
        kinds.append("none" if sphere is None else sphere.kind.value)
        prev, prev_yaw = goal, yaw
    data = base.model_dump(mode="json")
    data["objects"][0]["pose"]["position"] = start.tolist()
    if layout.size_scale is not None and cylinder:
        # Round still: its diameter scaled as its x extent was (the layout was drawn so).
        data["objects"][0]["shape"]["radius"] = float(drawn.size[0]) / 2.0
        data["objects"][0]["shape"]["height"] = float(drawn.size[2])
    elif layout.size_scale is not None:
        data["objects"][0]["shape"]["size"] = drawn.size.tolist()
    if drawn.mass is not None:
        data["objects"][0]["mass"] = drawn.mass
    # What rides on the object (a ball loose on a tray) starts on it: where it did, or drawn.
    place_riders(data, base, riding(base), start, drawn.size, (seed, trial, redraw))
    data["obstacles"] = [
        {
            "name": s.name,
            "shape": {"type": "sphere", "radius": s.radius},
            "position": list(s.centre),
        }
        for s in spheres
        if s is not None
    ]
    moves: list[dict[str, Any]] = [
        {
            "goal": {"position": g.tolist(), "rpy_deg": [0.0, pitch, yaw]},
            "obstacles": [] if s is None else [s.name],
        }
        for g, yaw, pitch, s in zip(goals, goal_yaws, drawn.pitches, spheres, strict=True)
    ]
    # A move the world's task carries with a skill of its own (a taught one) is carried with
    # it in every trial too: move i of a trial is the task's move i.
    told = [m.skill for step in base.task if step.object == obj.name for m in step.moves]
    for move, skill in zip(moves, told, strict=False):
        if skill is not None:
            move["skill"] = skill
    data["task"] = [{"object": obj.name, "moves": moves}]
    if layout.insertion is not None:
        # From a stream of its own: the draws above stay those of a world without it.
        data = place_fixture(data, np.random.default_rng([seed, trial, 3, redraw]))
    data["name"] = f"{base.name}_trial_{trial}"
    try:
        return world_from_data(data, base.source), kinds
    except ValidationError as exc:
        # A draw beyond what a world may hold (an object scaled past the largest box): the
        # draw's ranges are the file's to fix, named with the field the draw broke.
        problem = problems_from(exc, World)[0].format(f"trial {trial}'s drawn world")
        raise DrawnWorldError(
            f"trials: expected size_scale and mass_kg ranges whose draws a world file may "
            f"hold, got {problem}"
        ) from None


def _half(posture: Posture, half: np.ndarray) -> np.ndarray:
    """The box's half extents as held in ``posture``."""
    return half if posture.half_extents is None else posture.half_extents


def riding(world: World) -> list[int]:
    """Indices of the objects riding on ``objects[0]`` at the start
    (:func:`worlds.trays.riders`)."""
    spec = as_world_spec(world)
    carried = [step.object for step in world.task]
    on = {o.name for o in riders(spec.scene.objects, world.objects[0].name, carried)}
    return [k for k, o in enumerate(world.objects) if o.name in on]


def _draw_sphere(
    rng: np.random.Generator,
    name: str,
    start: np.ndarray,
    goal: np.ndarray,
    half: np.ndarray,
    layout: TrialSettings,
    allowed: Sequence[ObstacleKind],
    robot: RobotClearance,
    postures: list[Posture],
    robot_yaw: float = 0.0,
) -> Sphere:
    """A sphere of an ``allowed`` kind, on the line or ahead of the carry, clear of the box and
    of the robot holding it as it picks it up at the start and puts it down at the goal
    (``postures``: turned, and at every step of a turn made in steps), at rest and lifted.
    Ahead is along the robot's forward axis (heading ``robot_yaw`` rad: +x at 0)."""
    top = start[2] + half[2]
    lifted = np.array([0.0, 0.0, layout.lift])
    grasps = [
        replace(p, position=p.position + dz) for p in postures for dz in (0.0 * lifted, lifted)
    ]
    forward = np.array([math.cos(robot_yaw), math.sin(robot_yaw)])
    side = np.array([-math.sin(robot_yaw), math.cos(robot_yaw)])
    # The box's reach along the robot's forward axis, turned as it is at the start and goal.
    reach_x = max(
        abs(math.cos(p.object_yaw - robot_yaw)) * _half(p, half)[0]
        + abs(math.sin(p.object_yaw - robot_yaw)) * _half(p, half)[1]
        for p in postures
    )
    for _ in range(SPHERE_ATTEMPTS):  # rejection sampling
        radius = _uniform(rng, layout.sphere_radius)
        # Either kind with probability 1/2 (one draw, as before kinds could be restricted).
        if len(allowed) == 1:
            kind = allowed[0]
        else:
            kind = ObstacleKind.LINE if rng.random() < 0.5 else ObstacleKind.AHEAD
        if kind is ObstacleKind.LINE:
            t = float(rng.uniform(0.35, 0.65))
            xy = start[:2] + t * (goal[:2] - start[:2])
            centre = np.array([*xy, top + _uniform(rng, layout.line_gap) + radius])
        else:
            front = max(float(start[:2] @ forward), float(goal[:2] @ forward)) + reach_x
            along = front + radius + _uniform(rng, layout.ahead_gap)
            across = 0.5 * float((start[:2] + goal[:2]) @ side)
            xy = along * forward + across * side
            centre = np.array([xy[0], xy[1], top + _uniform(rng, layout.ahead_height)])
        box = min(_box_gap(p.position, _half(p, half), centre, p.object_yaw) for p in postures)
        if box - radius < layout.clearance:
            continue
        clearance = layout.robot_clearance
        if any(robot.distance(p, centre, radius, clearance) < clearance for p in grasps):
            continue
        return Sphere(name, (float(centre[0]), float(centre[1]), float(centre[2])), radius, kind)
    raise RuntimeError(
        f"the sphere drawn for a move ({name}): none of {SPHERE_ATTEMPTS} drawn kept clear of "
        "the object and the robot at the move's start and goal"
    )


class TrialLayoutError(ValueError):
    """A world whose ``trials`` section no trial can be drawn from; one message, not one per
    trial."""


def check_trial_layout(base: World, seed: int, label: str) -> None:
    """Raise :class:`TrialLayoutError` (naming ``label``, the world file) unless trials can be
    drawn from ``base``: a box object to grasp, and trial 0 of ``seed`` drawn as every trial
    is (its obstacles placed clear of the box and of the robot holding it), and its regions
    on the table and within the arms' reach (:func:`experiment.trial_regions.region_problems`).

    A layout that cannot place a sphere once (``clearance: 5``) cannot place it in any trial;
    drawing one costs a fraction of a second, and tells before a campaign starts.
    """
    obj = base.objects[0]
    others = sorted({step.object for step in base.task} - {obj.name})
    if others:
        raise TrialLayoutError(
            f"{label}: task: expected a task that moves objects[0] ({obj.name!r}) alone for "
            f"trials (each trial draws its start, goals and spheres; the other objects stand "
            f"where the file puts them), got moves of {', '.join(repr(o) for o in others)} too"
        )
    if obj.shape.type not in TRIAL_SHAPES:
        raise TrialLayoutError(
            f"{label}: objects[0].shape: expected a box, tray, mesh or cylinder object for "
            f"trials (their "
            f"obstacles and grasps are drawn around its bounding box), got a {obj.shape.type} "
            f"({obj.name!r})"
        )
    if obj.shape.type == "mesh" and base.trials.size_scale is not None:
        raise TrialLayoutError(
            f"{label}: trials.size_scale: expected none for a mesh object (its size is its "
            f"file's), got {list(base.trials.size_scale)}"
        )
    if obj.shape.type == "cylinder":
        for i, region in enumerate(base.trials.moves or ()):
            if any(p % 360.0 for p in region.pitch_deg or ()):
                raise TrialLayoutError(
                    f"{label}: trials.moves[{i}].pitch_deg: expected none for a cylinder (turned "
                    f"off its end it would roll once let go), got {list(region.pitch_deg)}"
                )
    problem = tray_layout_problem(base, riding(base))
    if problem is not None:
        raise TrialLayoutError(f"{label}: {problem}")
    off = region_problems(base)
    if off:
        raise TrialLayoutError("\n".join(f"{label}: {line}" for line in off))
    # A layout some of whose trials cannot be drawn is a campaign that records them as not
    # drawn; one whose first few all fail is a file to fix. (Trial 0 alone had refused a 14 cm
    # cylinder's campaign that draws 7 trials of 12.)
    first: RuntimeError | None = None
    with RobotClearance(base) as robot:
        for trial in range(PREFLIGHT_TRIALS):
            try:
                draw_trial(base, seed, trial, robot)
                return
            except DrawnWorldError as err:
                raise TrialLayoutError(f"{label}: {err}") from None
            except RuntimeError as err:
                first = first or err
    layout = base.trials
    raise TrialLayoutError(
        f"{label}: trials: expected a layout whose obstacles can be drawn, got none for "
        f"trials 0 to {PREFLIGHT_TRIALS - 1} (trial 0: {first}); draw smaller or farther "
        f"spheres (trials.sphere_radius "
        f"{vec(layout.sphere_radius)} m, trials.line_gap {vec(layout.line_gap)} m, "
        f"trials.ahead_gap {vec(layout.ahead_gap)} m: the defaults are the iiwas'), lower "
        f"trials.clearance ({layout.clearance:g} m) or trials.robot_clearance "
        f"({layout.robot_clearance:g} m), or move the regions apart"
    )

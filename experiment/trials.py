"""The paper's experiment: many trials of consecutive pick-and-place moves with new obstacles.

Each trial draws, from ``numpy.random.default_rng([seed, trial])`` and within the world
file's ``trials`` section (:class:`worlds.world_file.TrialSettings`, as the workspace depends
on the robot):

- the parcel's start on the table, near the robot's centre line;
- one goal per move in its region (:meth:`~worlds.world_file.TrialSettings.goal_regions`: the
  paper's three, centre, right (-y) and left (+y), or the section's own ``moves``), each
  with a yaw drawn within the move's range;
- for every move but at most one (drawn at random, and kept free with probability 1/2) a new
  sphere, either *on the line*: above the straight path between the move's start and goal,
  under the demonstrated lift, or *ahead*: in front (+x) of the carry at the lifted parcel's
  height, of the kinds the move's region allows (a region without kinds gets no sphere).
  Every sphere clears the parcel at its move's start
  and goal (``clearance``), and the robot itself, posed grasping the parcel there, at rest
  and lifted by ``lift`` (``robot_clearance``, measured by PyBullet on the robot's own
  collision shapes), so only the carry can meet it: a sphere the robot would have to be in
  to pick the parcel up or put it down is not a test of avoidance.

With ``hard``, each trial also runs against a physical truth drawn for it
(:mod:`experiment.hard`); its record says what was drawn (``hard``) and ``"mode": "hard"``.

Trials are judged as :func:`experiment.judge.judge` says (2 cm and 10 degrees per placement,
never dropped, no robot link or parcel touching an obstacle, arms never touching). Results
are appended to ``results.jsonl`` one line per trial as they finish, so an interrupted
campaign resumes where it stopped.
"""

from __future__ import annotations

import ctypes
import json
import math
import os
import signal
import socket
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from types import TracebackType
from typing import Any

import numpy as np
import pybullet as pb

from experiment.flip_draws import draw_object, goal_half_height, pitched_goal_postures
from experiment.hard import HardTrial, draw_hard, with_pushes
from experiment.insertion_trials import place_fixture
from experiment.preflight import tree_task_problems
from experiment.records import campaign_key, owned_by, tree_hash
from experiment.results import (
    ResultsFileError,
    campaign_lock,
    read_results,
    repair_tail,
)

# Re-exported: the summary lives below the simulation, for reports that need no PyBullet.
from experiment.summary import composition_label as composition_label
from experiment.summary import reason_of as reason_of
from experiment.summary import summarise as summarise
from experiment.tray_draws import place_riders, tray_height, tray_layout_problem
from planner.tree_reading import read_tree_document
from planner.user_leaves import register_leaves
from skills.turns import grip_yaw, lateral_quarter_turns, turn_steps
from worlds.adapters import robot_capabilities
from worlds.bodies import build_robot
from worlds.scene import Scene, lateral_grasp_palm_poses
from worlds.trays import riders
from worlds.world_file import (
    GoalRegion,
    ObstacleKind,
    Region,
    TrayShape,
    TrialSettings,
    World,
    as_world_spec,
    world_from_data,
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
    (:func:`planner.port.stepped_moves`): each step's grasp at its start and its end, on the
    faces :func:`skills.turns.lateral_quarter_turns` chooses for it.
    """
    out: list[Posture] = []
    yaw = start_yaw
    for i, step in enumerate(turn_steps(start_yaw, goal_yaw, max_turn, robot_yaw)):
        k = lateral_quarter_turns(yaw, step - yaw, robot_yaw)
        half = float(size[1] if k % 2 == 0 else size[0]) / 2.0
        first = grip_yaw(yaw, k, robot_yaw)
        out.append(Posture(start if i == 0 else goal, yaw, first, half))
        out.append(Posture(goal, step, first + (step - yaw), half))
        yaw = step
    return out


class RobotClearance:
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
        obj = world.objects[0]
        size = getattr(obj.shape, "size", None)
        if size is None:
            raise ValueError(
                f"trials: expected a box object to grasp, got a {obj.shape.type} ({obj.name!r})"
            )
        self._thickness = float(world.robot.palm_size[2])
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
                    grip_yaw=posture.grip_yaw,
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
        """Reset every joint to its position in ``positions`` (:meth:`_joint_positions`)."""
        client = self._scene.client
        for body, joint, value in positions:
            pb.resetJointState(body, joint, value, 0.0, physicsClientId=client)

    def close(self) -> None:
        """Disconnect the scene."""
        self._scene.close()

    def __enter__(self) -> RobotClearance:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        self.close()


def _uniform(rng: np.random.Generator, bounds: tuple[float, float]) -> float:
    return float(rng.uniform(*bounds))


def _in_region(rng: np.random.Generator, region: Region, z: float) -> np.ndarray:
    return np.array([_uniform(rng, region.x), _uniform(rng, region.y), z])


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
    for redraw in range(TRIAL_REDRAWS if turning else 1):
        try:
            return _draw_trial(base, seed, trial, robot, redraw)
        except RuntimeError:
            # A turn that leaves no room for the next move's sphere (the arms turned across
            # its way): the trial is drawn again from a stream of its own.
            if redraw == TRIAL_REDRAWS - 1 or not turning:
                raise
    raise AssertionError("unreachable")


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
    drawn = draw_object(
        layout, regions, getattr(obj.shape, "size", (0.2, 0.3, 0.15)), seed, trial, redraw
    )
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
            if attempt == YAW_ATTEMPTS - 1 and low <= math.degrees(prev_yaw) <= high:
                goal_yaws[i] = math.degrees(prev_yaw)  # at last, no turn at all
            elif attempt:  # no sphere fits the robot turning this way: another turn
                goal_yaws[i] = _uniform(turn_rng, (low, high))
            yaw = math.radians(goal_yaws[i])
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
    if layout.size_scale is not None:
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
    data["task"] = [
        {
            "object": obj.name,
            "moves": [
                {
                    "goal": {"position": g.tolist(), "rpy_deg": [0.0, pitch, yaw]},
                    "obstacles": [] if s is None else [s.name],
                }
                for g, yaw, pitch, s in zip(goals, goal_yaws, drawn.pitches, spheres, strict=True)
            ],
        }
    ]
    if layout.insertion is not None:
        # From a stream of its own: the draws above stay those of a world without it.
        data = place_fixture(data, np.random.default_rng([seed, trial, 3, redraw]))
    data["name"] = f"{base.name}_trial_{trial}"
    return world_from_data(data, base.source), kinds


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
) -> Sphere:
    """A sphere of an ``allowed`` kind, on the line or ahead of the carry, clear of the box and
    of the robot holding it as it picks it up at the start and puts it down at the goal
    (``postures``: turned, and at every step of a turn made in steps), at rest and lifted."""
    top = start[2] + half[2]
    lifted = np.array([0.0, 0.0, layout.lift])
    grasps = [
        replace(p, position=p.position + dz) for p in postures for dz in (0.0 * lifted, lifted)
    ]
    # The box's reach along x, turned as it is at the start and the goal.
    reach_x = max(
        abs(math.cos(p.object_yaw)) * _half(p, half)[0]
        + abs(math.sin(p.object_yaw)) * _half(p, half)[1]
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
            front = max(start[0], goal[0]) + reach_x
            centre = np.array(
                [
                    front + radius + _uniform(rng, layout.ahead_gap),
                    0.5 * (start[1] + goal[1]),
                    top + _uniform(rng, layout.ahead_height),
                ]
            )
        box = min(_box_gap(p.position, _half(p, half), centre, p.object_yaw) for p in postures)
        if box - radius < layout.clearance:
            continue
        clearance = layout.robot_clearance
        if any(robot.distance(p, centre, radius, clearance) < clearance for p in grasps):
            continue
        return Sphere(name, (float(centre[0]), float(centre[1]), float(centre[2])), radius, kind)
    raise RuntimeError(f"{name}: could not place a sphere clear of the start and goal")


class TrialLayoutError(ValueError):
    """A world whose ``trials`` section no trial can be drawn from; one message, not one per
    trial."""


def check_trial_layout(base: World, seed: int, label: str) -> None:
    """Raise :class:`TrialLayoutError` (naming ``label``, the world file) unless trials can be
    drawn from ``base``: a box object to grasp, and trial 0 of ``seed`` drawn as every trial
    is (its obstacles placed clear of the box and of the robot holding it).

    A layout that cannot place a sphere once (``clearance: 5``) cannot place it in any trial;
    drawing one costs a fraction of a second, and tells before a campaign starts.
    """
    obj = base.objects[0]
    if obj.shape.type not in ("box", "tray"):
        raise TrialLayoutError(
            f"{label}: objects[0].shape: expected a box or tray object for trials (their obstacles "
            f"and grasps are drawn around a box), got a {obj.shape.type} ({obj.name!r})"
        )
    problem = tray_layout_problem(base, riding(base))
    if problem is not None:
        raise TrialLayoutError(f"{label}: {problem}")
    try:
        draw_trial(base, seed, 0)
    except RuntimeError as err:
        layout = base.trials
        raise TrialLayoutError(
            f"{label}: trials: expected a layout whose obstacles can be drawn, got none for "
            f"trial 0 ({err}); lower trials.clearance ({layout.clearance:g} m) or "
            f"trials.robot_clearance ({layout.robot_clearance:g} m), or move the regions apart"
        ) from None


def run_trial(job: tuple[dict[str, Any], int, int]) -> dict[str, Any]:
    """Run one trial in this process; returns its JSON-ready record (never raises)."""
    from experiment.episode import run_episode

    base_data, seed, trial = job
    die = base_data.get("die_once")
    if die and die[0] == trial and not Path(die[1]).exists():
        # Test-only (DUET_TEST_DIE_ONCE): this worker dies on its first attempt of the trial.
        Path(die[1]).write_text(str(os.getpid()), encoding="utf-8")
        os._exit(1)
    source = Path(base_data["source"]) if base_data["source"] else None
    base = world_from_data(base_data["world"], source)
    tree = Path(base_data["tree"]) if base_data["tree"] else None
    hard: HardTrial | None = None
    try:
        # The user's leaves the tree may use, registered in this process too (a spawned
        # worker starts without them; a forked one finds them registered already).
        register_leaves(base_data.get("leaves", ()))
        world, kinds = draw_trial(base, seed, trial, _worker_clearance(base))
        if base_data.get("hard"):
            hard = draw_hard(world, seed, trial)
            world = with_pushes(world, hard.pushes)
        where = _layout_of(world)
        misfit = _tree_misfit(world, tree, base_data.get("main_tree"))
        record: dict[str, Any]
        if misfit:
            record = {"success": False, "sim_time_s": 0.0, "wall_time_s": 0.0}
            failure = misfit
        else:
            report = run_episode(
                world,
                tree,
                out=None,
                animation=False,
                main_tree=base_data.get("main_tree"),
                truth=None if hard is None else hard.truth,
            )
            record = report.summary()
            record.pop("outputs", None)
            failure = record["failure"] or ""
    except Exception as err:  # a trial that crashes is a failed trial with its reason
        record = {"success": False, "sim_time_s": 0.0, "wall_time_s": 0.0}
        kinds, where = [], {}
        failure = f"error: {type(err).__name__}: {err}"
    record.update(
        {
            "trial": trial,
            **base_data.get("key", {"seed": seed}),
            "obstacles": kinds,
            **where,
            "failure": failure,
            "backend": base_data.get("backend", "local"),
            "host": socket.gethostname(),
        }
    )
    if hard is not None:
        record.update({"mode": "hard", "hard": hard.summary()})
    return record


def _tree_misfit(world: World, tree: Path | None, main_tree: str | None) -> str:
    """Why a tree given with ``--tree`` cannot make this trial's task ("" when it can).

    Such a tree runs as written, with the moves its file names; a trial's turned goals may
    make more moves than the world file's (a turn the grip cannot make in one move is
    several), and a Move it lacks would never be made. The trial fails at once, saying so,
    instead of running the moves it has.
    """
    if tree is None:
        return ""
    problems = tree_task_problems(world, read_tree_document(tree, main_tree_id=main_tree))
    if not problems:
        return ""
    return (
        f"tree does not fit this trial's task: {problems[0]} (a tree given with --tree runs "
        "as written; a copy of the shipped tree in the world's tree field is made into each "
        "trial's task)"
    )


#: This process's RobotClearance and the base world it was built for (see _worker_clearance).
_CLEARANCE: dict[str, Any] = {}


def _worker_clearance(base: World) -> RobotClearance:
    """One :class:`RobotClearance` per process for its campaign's base world: a worker builds
    the robot's scene once, not once per trial (each draw restarts it, and so draws what a
    scene of its own would). A forked process builds its own."""
    key = (os.getpid(), base.model_dump_json())
    if _CLEARANCE.get("key") != key:
        _close_worker_clearance()
        _CLEARANCE.update(key=key, robot=RobotClearance(base))
    robot: RobotClearance = _CLEARANCE["robot"]
    return robot


def _close_worker_clearance() -> None:
    """Close this process's :func:`_worker_clearance` robot, if it built one."""
    if _CLEARANCE and _CLEARANCE["key"][0] == os.getpid():
        _CLEARANCE["robot"].close()
    _CLEARANCE.clear()


def _layout_of(world: World) -> dict[str, Any]:
    """Where a trial's object started and its moves' goals were (m), for reports."""
    start = world.objects[0].pose.position
    goals = [list(m.goal.position) for step in world.task for m in step.moves]
    return {"start": list(start), "goals": goals}


def campaign_of(
    base: World,
    seed: int,
    tree: Path | None,
    leaves: Sequence[str] = (),
    main_tree: str | None = None,
    hard: bool = False,
) -> dict[str, Any]:
    """The key of the campaign of ``base``, ``seed``, ``tree``, the tree's own ``leaves``, the
    ``main_tree`` run of it and whether it is ``hard`` (:func:`experiment.records.campaign_key`).

    A Hard campaign's settings hold its ranges (``trials.hard``, every value) and the robot's
    torque loop, which acts only on faulty actuators; the world's content hash leaves the
    ranges out, so an Easy campaign's key does not depend on them.
    """
    settings: dict[str, Any] = {"leaves": [_leaf_source(s) for s in leaves]} if leaves else {}
    if main_tree:
        settings["main_tree"] = main_tree
    if hard:
        settings["hard"] = base.trials.hard.model_dump(mode="json")
        loop = build_robot(as_world_spec(base).scene.robot).torque_loop
        settings["torque_loop"] = None if loop is None else loop.summary()
    template = base.tree_path() if tree is None else None
    if template is not None:  # the world's own tree: its content, not only its path
        settings["world_tree_sha256"] = tree_hash(template)
    data = base.model_dump(mode="json")
    data["trials"].pop("hard", None)
    return campaign_key(base.name, data, tree, seed, settings)


def _leaf_source(source: str) -> str:
    return str(Path(source).resolve()) if source.endswith(".py") else source


def campaign_results(path: Path, key: dict[str, Any]) -> dict[int, dict[str, Any]]:
    """The records in ``results.jsonl`` of one campaign (``key``: :func:`campaign_of`);
    records of other campaigns are ignored, as are lines that are not records
    (:func:`experiment.results.read_results` counts them).

    Raises
    ------
    ResultsFileError
        If the file is a folder or unreadable.
    """
    return {
        r["trial"]: r  # a trial run twice (an interrupted write) counts once, the last
        for r in read_results(path).records
        if owned_by(r, key)
    }


#: Where a campaign's trials can run.
BACKENDS = ("local", "ray")
#: Times Ray runs a trial again whose worker died (a killed process, a lost node).
RAY_RETRIES = 3


def _run_on_ray(
    jobs: list[tuple[dict[str, Any], int, int]],
    workers: int,
    address: str | None,
    keep: Callable[[dict[str, Any]], None],
) -> None:
    """Run ``jobs`` as Ray tasks, handing each record to ``keep`` here as it arrives.

    A task whose worker dies is run again by Ray (``RAY_RETRIES``); its record arrives once.
    Without ``address`` a local Ray of ``workers`` CPUs is started, whose workers import this
    project from its folder.
    """
    import ray

    from experiment.records import PROJECT

    started = not ray.is_initialized()
    if started:
        if address:
            ray.init(address=address, log_to_driver=False)
        else:
            ray.init(
                num_cpus=workers,
                include_dashboard=False,
                log_to_driver=False,
                runtime_env={"env_vars": {"PYTHONPATH": str(PROJECT)}},
            )
    task = ray.remote(num_cpus=1, max_retries=RAY_RETRIES)(run_trial)
    pending = [task.remote(job) for job in jobs]
    try:
        while pending:
            ready, pending = ray.wait(pending, num_returns=1)
            for ref in ready:
                try:
                    record = ray.get(ref)
                except ray.exceptions.RayError as err:
                    raise RuntimeError(
                        f"ray: a trial's worker failed {RAY_RETRIES + 1} times: {err}"
                    ) from None
                keep(record)
    except BaseException:  # Ctrl-C included: stop what is running, keep what finished
        for ref in pending:
            ray.cancel(ref, force=True)
        raise
    finally:
        if started:
            ray.shutdown()


#: Times the local pool runs a trial again whose worker died (killed, crashed), as Ray does.
POOL_RETRIES = RAY_RETRIES


def _run_on_pool(
    jobs: list[tuple[dict[str, Any], int, int]],
    workers: int,
    keep: Callable[[dict[str, Any]], None],
) -> None:
    """Run ``jobs`` on a pool of ``workers`` forked processes, handing each record to ``keep``
    here as it arrives.

    A worker that dies mid-trial (killed, out of memory, a crash in compiled code) breaks
    the pool: every trial running on it then, its own and the others', is run again on a new
    pool, and each record arrives once, since a trial is done only when its record arrived.
    At most one trial per worker is handed to the pool, so those running when it broke are
    all that is run again. A trial running when its pool broke ``POOL_RETRIES + 1`` times
    is a RuntimeError (as on Ray), not a campaign that never ends.
    """
    import multiprocessing as mp
    from collections import deque
    from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
    from concurrent.futures.process import BrokenProcessPool

    queue = deque(jobs)
    broken_runs: dict[int, int] = {}
    while queue:
        pool = ProcessPoolExecutor(
            workers, mp_context=mp.get_context("fork"), initializer=_worker_init
        )
        running: dict[Future[dict[str, Any]], tuple[dict[str, Any], int, int]] = {}
        lost: list[tuple[dict[str, Any], int, int]] = []
        broken = False
        try:
            while running or (queue and not broken):
                while queue and not broken and len(running) < workers:
                    try:
                        running[pool.submit(run_trial, queue[0])] = queue[0]
                        queue.popleft()
                    except BrokenProcessPool:  # it broke since the last result came
                        broken = True
                if not running:
                    break
                finished, _ = wait(running, return_when=FIRST_COMPLETED)
                for future in finished:
                    job = running.pop(future)
                    try:
                        record = future.result()
                    except BrokenProcessPool:
                        broken = True
                        lost.append(job)
                    else:
                        keep(record)
        except BaseException:  # Ctrl-C included: end the workers, keep what finished
            _end_pool(pool)
            raise
        pool.shutdown(wait=True)
        for _, _, trial in lost:
            broken_runs[trial] = broken_runs.get(trial, 0) + 1
            if broken_runs[trial] > POOL_RETRIES:
                raise RuntimeError(
                    f"local pool: trial {trial} was running when its worker died "
                    f"{broken_runs[trial]} times (killed or crashed)"
                )
        queue.extendleft(reversed(lost))


def _end_pool(pool: Any) -> None:
    """Stop a process pool now, its running trials too (they have no record: they run again
    when the campaign resumes)."""
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    # Python 3.14 has ProcessPoolExecutor.terminate_workers(); before it, its processes.
    for process in processes:
        process.terminate()


def _worker_init() -> None:
    """In a worker: leave Ctrl-C to the parent (which ends the pool), and die with it."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:  # Linux: the kernel sends SIGTERM when the parent dies, even by SIGKILL
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass
    if os.getppid() == 1:  # the parent died before the line above took effect
        os._exit(1)


def run_campaign(
    base: World,
    n: int,
    seed: int,
    out: Path,
    workers: int = 1,
    on_result: Callable[[dict[str, Any], int, int], None] | None = None,
    tree: Path | None = None,
    on_notice: Callable[[str], None] | None = None,
    leaves: Sequence[str] = (),
    backend: str = "local",
    address: str | None = None,
    main_tree: str | None = None,
    hard: bool = False,
) -> list[dict[str, Any]]:
    """Run trials ``0..n-1`` not yet in ``out/results.jsonl``; append each as it finishes.

    Parameters
    ----------
    base : World
    n : int
        Number of trials.
    seed : int
        Campaign seed: trial ``i`` draws from ``default_rng([seed, i])``.
    out : Path
        Folder of ``results.jsonl``.
    workers : int
        Worker processes (each runs its own PyBullet).
    on_result : callable (record, finished, total), optional
        Progress callback, in the parent process.
    tree : Path, optional
        Behaviour tree XML every trial runs (default: the paper's tree built in code).
        Records remember it: a campaign resumes only the trials of its own world, seed, tree
        and leaves (:func:`campaign_of`); other records in the file are kept and ignored.
    on_notice : callable (text), optional
        Told of what was repaired or skipped in an earlier ``results.jsonl``.
    leaves : sequence of str
        ``--leaves`` sources (files or modules) of the tree's own leaves; every worker
        registers them (:func:`planner.user_leaves.register_leaves`).
    backend : {"local", "ray"}
        Where trials run: a pool of ``workers`` processes here, or Ray tasks (a local Ray
        of ``workers`` CPUs, or the cluster at ``address``). Records are the same either way
        but for ``wall_time_s``, ``host`` and ``backend``; only this process writes them.
    address : str, optional
        A Ray cluster's address (``ray start --head`` prints it; "auto" finds a local one).
    main_tree : str, optional
        The ``<BehaviorTree ID>`` of ``tree`` to run instead of its ``main_tree_to_execute``;
        it is part of the campaign's key, so a campaign resumes only trials of the same one.
    hard : bool
        Hard mode (:mod:`experiment.hard`): every trial runs against a physical truth drawn
        for it. Part of the campaign's key, with the world's ``trials.hard`` ranges.

    Returns
    -------
    list of dict
        The records of trials ``0..n-1`` for this seed, in trial order.

    Raises
    ------
    ResultsFileError
        If ``out`` cannot hold the results, or its results file cannot be read or repaired.
    CampaignBusyError
        If another campaign is writing into ``out``.
    """
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise ResultsFileError(f"{out}: cannot make the folder: {err.strerror or err}") from None
    if backend not in BACKENDS:
        raise ValueError(f"run_campaign: expected backend in {BACKENDS}, got {backend!r}")
    with campaign_lock(out):
        return _run_locked(
            base,
            n,
            seed,
            out,
            workers,
            on_result,
            tree,
            on_notice or _quiet,
            leaves,
            backend,
            address,
            main_tree,
            hard,
        )


def _quiet(text: str) -> None:
    del text


def _run_locked(
    base: World,
    n: int,
    seed: int,
    out: Path,
    workers: int,
    on_result: Callable[[dict[str, Any], int, int], None] | None,
    tree: Path | None,
    on_notice: Callable[[str], None],
    leaves: Sequence[str],
    backend: str,
    address: str | None,
    main_tree: str | None = None,
    hard: bool = False,
) -> list[dict[str, Any]]:
    results = out / "results.jsonl"
    cut = repair_tail(results)
    if cut:
        on_notice(f"{results}: cut a torn last line ({cut} bytes) before appending")
    earlier = read_results(results)
    if earlier.skipped:
        on_notice(
            f"{results}: skipped {earlier.skipped} line(s) that are not trial records; "
            "their trials run again"
        )
    key = campaign_of(base, seed, tree, leaves, main_tree, hard)
    done = campaign_results(results, key)
    pending = [t for t in range(n) if t not in done]
    payload: dict[str, Any] = {
        "world": base.model_dump(mode="json"),
        "source": str(base.source or ""),
        "tree": str(tree.resolve()) if tree is not None else "",
        "key": key,
        "leaves": [_leaf_source(s) for s in leaves],
        "backend": backend,
        **({"main_tree": main_tree} if main_tree else {}),
        **({"hard": True} if hard else {}),
    }
    die = os.environ.get("DUET_TEST_DIE_ONCE", "")
    # Test-only (see run_trial): where trials run in worker processes, never in this one.
    if (backend == "ray" or workers > 1) and ":" in die:
        at, marker = die.split(":", 1)
        payload["die_once"] = (int(at), marker)
    jobs = [(payload, seed, t) for t in pending]
    finished = n - len(pending)
    try:
        fh = open(results, "a", encoding="utf-8")
    except OSError as err:
        raise ResultsFileError(f"{results}: cannot write it: {err.strerror or err}") from None
    with fh:

        def keep(rec: dict[str, Any]) -> None:
            nonlocal finished
            try:
                fh.write(json.dumps(rec) + "\n")
                fh.flush()
                os.fsync(fh.fileno())
            except OSError as err:  # a full disk: the trials before this one are kept whole
                try:
                    fh.close()  # its buffer cannot be written either; do not try again
                except OSError:
                    pass
                raise ResultsFileError(
                    f"{results}: cannot append trial {rec['trial']}: {err.strerror or err} "
                    "(the trials recorded before it are kept; run again to resume)"
                ) from None
            done[int(rec["trial"])] = rec
            finished += 1
            if on_result is not None:
                on_result(rec, finished, n)

        if backend == "ray":
            _run_on_ray(jobs, workers, address, keep)
        elif workers <= 1:
            try:
                for job in jobs:
                    keep(run_trial(job))
            finally:
                _close_worker_clearance()  # this process goes on: leave no scene behind
        else:
            _run_on_pool(jobs, workers, keep)
    return [done[t] for t in range(n) if t in done]

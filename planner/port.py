"""The world port: everything the planner's leaves may ask of, or tell, a world.

The port is split by role: :class:`Clock` (time), :class:`ObjectSensing` (objects, task,
gravity), :class:`PalmControl` (palms and the robot's declared capabilities) and
:class:`ObstacleScene` (obstacles and collision queries). :class:`WorldPort` is all four. The
simulated world (``worlds.sim_world.SimWorld``) and the in-memory fake
(:class:`planner.testing.FakeWorld`) both satisfy it, so a leaf is tested without PyBullet and
run unchanged against it. Leaves never step the world: the runner calls
:meth:`Clock.advance` between ticks, so ``update()`` never blocks.

Forces cross the port as forces (N): the planner asks for the squeeze depth that gives a force
(:meth:`PalmControl.squeeze_depth`) and never sees the controller's stiffness.

Poses are (position (3,), quaternion (4,) scalar-last) pairs in the world frame; twists are
(6,) arrays ``[vx, vy, vz, wx, wy, wz]``, world frame.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from affordances import ObjectContext, RobotCapabilities, SceneQuery
from skills import quaternion as quat
from skills import turns
from skills.level_carry import LooseBall
from skills.state import validated_pose
from skills.types import Array
from skills.vocabulary import Arm


@dataclass(frozen=True)
class Pose:
    """A pose in the world frame.

    Attributes
    ----------
    position : ndarray, shape (3,)
        m.
    orientation : ndarray, shape (4,)
        Unit quaternion ``(x, y, z, w)``.
    """

    position: Array
    orientation: Array

    @staticmethod
    def of(position: ArrayLike, orientation: ArrayLike = quat.IDENTITY) -> Pose:
        """Validated pose from array-likes."""
        return Pose(*validated_pose(position, orientation))


@dataclass(frozen=True)
class Move:
    """One step of a task: where the object should go and which obstacles are present.

    A world shows a move whose turn about z the robot's grip cannot make in one grasp as
    several moves (:func:`stepped_moves`): the steps before the last put the object down at
    the move's goal position turned part of the way; ``task_move`` and ``final`` say which of
    the task's moves a step belongs to and whether it is its last (the one to judge).

    Attributes
    ----------
    goal : Pose
        Goal pose of the object's centre.
    obstacles : tuple of str
        Names of the obstacles present during this move.
    skill : str or None
        Name or label of the library skill the move is carried with (the world file's
        ``skill``); None for the plan's transport skill.
    task_move : int or None
        Index of the task's move (as the world file lists the object's moves) this move is
        (a step of); None for a move not made by :func:`stepped_moves`.
    final : bool
        The last step of its task move: its goal is the task move's goal.
    fixture : str or None
        The fixture (:class:`FixtureInfo`) the move seats the object in: its goal is the
        seated pose; None for a placement on the table.
    """

    goal: Pose
    obstacles: tuple[str, ...] = ()
    skill: str | None = None
    task_move: int | None = None
    final: bool = True
    fixture: str | None = None


def stepped_moves(
    moves: Iterable[Move],
    start_yaw: float,
    max_turn: float,
    robot_yaw: float = 0.0,
    places: Sequence[ArrayLike | None] | None = None,
) -> tuple[Move, ...]:
    """A task's moves as a robot with a grip turn of ``max_turn`` rad makes them.

    Each move whose turn about z (from the previous goal's yaw, or ``start_yaw`` for the
    first) needs more than one grasp (:func:`skills.turns.turn_steps`) becomes several, each
    a move of its own with the move's obstacles: its steps before the last put the object
    down at its place (:func:`skills.turns.move_holds`; by default its goal position: a carry
    there turned part of the way, then turns in place), the last carries it to its goal.
    Every returned move names its task move (``Move.task_move``) and the last step of each
    is ``final``.

    Parameters
    ----------
    moves : iterable of Move
        The task's moves of one object, in order.
    start_yaw : float
        The object's yaw before the first move, rad.
    max_turn : float
        The robot's largest grip turn, rad (``RobotCapabilities.max_turn_rad``).
    robot_yaw : float
        The robot's heading, rad.
    places : sequence, optional
        Per task move, (3,) where its steps before the last stand, m, or None for its goal;
        default: all at their goals.

    Raises
    ------
    ValueError
        If ``places`` does not give one place per move.
    """
    moves = tuple(moves)
    chosen = tuple(places) if places is not None else (None,) * len(moves)
    if len(chosen) != len(moves):
        raise ValueError(
            f"stepped_moves: places: expected one per move ({len(moves)}), got {len(chosen)}"
        )
    out: list[Move] = []
    yaw = float(start_yaw)
    for index, (move, place) in enumerate(zip(moves, chosen, strict=True)):
        goal_yaw = turns.yaw_of(move.goal.orientation)
        steps = turns.turn_steps(yaw, goal_yaw, max_turn, robot_yaw)
        for i, step_yaw in enumerate(steps):
            last = i == len(steps) - 1
            where = move.goal.position if last or place is None else place
            # The last step keeps the goal's own quaternion (a tilt included); the others
            # turn it back about z by what is still to come.
            back = quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), step_yaw - steps[-1])
            orientation = (
                move.goal.orientation if last else quat.multiply(back, move.goal.orientation)
            )
            out.append(
                Move(
                    Pose(np.array(where, dtype=float), orientation),
                    move.obstacles,
                    skill=move.skill,
                    task_move=index,
                    final=last,
                    fixture=move.fixture,
                )
            )
        yaw = goal_yaw
    return tuple(out)


@dataclass(frozen=True)
class ObstacleInfo:
    """An obstacle the planner may reason about.

    Attributes
    ----------
    name : str
    position : ndarray, shape (3,)
        Centre, m.
    radius : float
        Bounding-sphere radius, m.
    """

    name: str
    position: Array
    radius: float


@dataclass(frozen=True)
class ObstacleGap:
    """How near an object is, as measured now, to the nearest present obstacle.

    Attributes
    ----------
    distance_m : float
        The gap between their surfaces, m (0 or less: touching).
    away : ndarray, shape (3,)
        Unit vector, world frame, along which moving the object widens the gap.
    obstacle : str
        The obstacle's name.
    """

    distance_m: float
    away: Array
    obstacle: str


@dataclass(frozen=True)
class FixtureInfo:
    """An open fixture on the table an object is inserted into: four walls around a slot.

    Attributes
    ----------
    name : str
    for_object : str
        The object it is made for.
    position : ndarray, shape (3,)
        Centre of the inside at its floor (the table top), m.
    yaw : float
        Turn about world z, rad.
    inner : ndarray, shape (2,)
        Inside extents along the fixture's x and y, m.
    wall_height : float
        Height of the walls above the floor, m.
    """

    name: str
    for_object: str
    position: Array
    yaw: float
    inner: Array
    wall_height: float


@dataclass(frozen=True)
class PathCheck:
    """Outcome of checking a predicted trajectory for collisions.

    Attributes
    ----------
    clear : bool
        No robot link, palm or the held object comes within the margin of an obstacle.
    min_distance_m : float
        Smallest distance of the path's sampled points (the held object's centre, the palms'
        origins) from an obstacle's surface, m: it ranks paths; the bodies' own clearance is
        what ``clear`` judges, against the margin.
    first_collision : int or None
        Index of the first waypoint in collision.
    detail : str
        What came closest to what, in words.
    doubtful : bool
        Refused only for the arms' links predicted near an obstacle, where the prediction is
        asked extra clearance the further the palms go (no palm, held object or link is
        predicted within the margin of anything else).
    end_clear : bool
        The path's last pose keeps the margin: its palms, held object and the arms' links
        posed there, without the extra clearance a long way asks of the links. False: every
        way to that pose ends within the margin of something, however it goes.
    end_objects : tuple of str
        The objects, where they rest, that an arm's link comes within the objects' margin of
        at the path's last pose (none for a check that does not keep off the objects).
    """

    clear: bool
    min_distance_m: float
    first_collision: int | None = None
    detail: str = ""
    doubtful: bool = False
    end_clear: bool = True
    end_objects: tuple[str, ...] = ()


@runtime_checkable
class Clock(Protocol):
    """Simulated time. Leaves read it; only the runner advances it."""

    def time(self) -> float:
        """Simulated time, s."""
        ...

    def advance(self, dt: float) -> None:
        """Run the world for ``dt`` seconds of simulated time (called by the runner only)."""
        ...


@runtime_checkable
class ObjectSensing(Protocol):
    """The objects as measured and declared, the task's moves, and the gravity they feel."""

    def object_pose(self, name: str) -> Pose:
        """Measured pose of an object's centre."""
        ...

    def object_twist(self, name: str) -> Array:
        """Measured twist of an object's centre, (6,)."""
        ...

    def object_extents(self, name: str) -> Array:
        """Bounding-box extents (x, y, z) of an object in its own frame, m."""
        ...

    def workspace_bounds(self, name: str) -> tuple[Array, Array]:
        """Box (lower (3,), upper (3,)) the object's centre must stay in: above the table top
        by half its height, inside the table's footprint, below the robot's reach, m."""
        ...

    def object_context(self, name: str) -> ObjectContext:
        """The object's declared properties and surroundings, for the affordance reasoner."""
        ...

    def task_moves(self, name: str) -> tuple[Move, ...]:
        """The moves the task asks of an object, in order, each turn split into the steps the
        robot's grip can make (:func:`stepped_moves`)."""
        ...

    def gravity(self) -> float:
        """Magnitude of the world's gravity, m/s^2 (what a grip must carry)."""
        ...

    def loose_balls(self, name: str) -> tuple[LooseBall, ...]:
        """The balls lying loose on an object (a rimmed tray), as the level carry needs them;
        empty for an object that carries none."""
        ...

    def fixtures(self) -> tuple[FixtureInfo, ...]:
        """The open fixtures on the table (always present; none in most worlds)."""
        ...

    def fixture_force(self, name: str) -> Array:
        """Force (3,) the fixtures exert on an object, N, world frame (normal and friction;
        zeros without contact): a wall pressing the object pushes it away from the wall."""
        ...

    def fixture_torque(self, name: str) -> Array:
        """Torque (3,) the fixtures' contacts exert on an object about its centre, N m, world
        frame (zeros without contact): where a wall bears on it (the box's edge on a wall's
        top, :func:`skills.insertion.bearing_point`)."""
        ...


@runtime_checkable
class PalmControl(Protocol):
    """The two palms: what they measure, what the robot declares, and how to command them."""

    def palm_pose(self, arm: Arm) -> Pose:
        """Measured pose of a palm frame."""
        ...

    def palm_twist(self, arm: Arm) -> Array:
        """Measured twist of a palm frame, (6,)."""
        ...

    def palm_target(self, arm: Arm) -> Pose:
        """The pose a palm's controller tracks now: the last :meth:`command_palm`'s (the rest
        pose before any). It differs from :meth:`palm_pose` by what holds the palm off it (a
        face it presses, a biased actuator); a skill that starts from it does not change the
        force the palm exerts."""
        ...

    def rest_palm_pose(self, arm: Arm) -> Pose:
        """Where a palm waits when it holds nothing."""
        ...

    def palm_thickness(self) -> float:
        """Thickness of a palm along its contact normal, m."""
        ...

    def robot_capabilities(self) -> RobotCapabilities:
        """What the robot declares it can carry and squeeze, and its palms' friction."""
        ...

    def squeeze_depth(self, force_n: float) -> float:
        """How far inside an object's face to command a palm for it to press with
        ``force_n`` N, m (the world's palm controller sets the ratio)."""
        ...

    def command_palm(self, arm: Arm, pose: Pose, twist: Array | None = None) -> None:
        """Set the target pose (and feed-forward twist) the palm's controller tracks."""
        ...

    def hold_palms(self) -> None:
        """Stop both arms: hold the last commanded poses with zero twist."""
        ...

    def contact_force(self, arm: Arm, name: str) -> float:
        """Normal force between a palm and an object, N (0 without contact)."""
        ...

    def palm_load(self, arm: Arm, name: str) -> float:
        """Upward force a palm exerts on an object, N (world +z; 0 without contact): the
        share of its weight the palm carries, as a wrist force sensor reads it. Near zero or
        below once a surface carries the object."""
        ...


def role_methods(role: type) -> frozenset[str]:
    """Names of the methods a role Protocol (or a union of roles) declares."""
    names: set[str] = set()
    for cls in role.__mro__:
        if cls is object or not getattr(cls, "_is_protocol", False):
            continue
        names.update(n for n, v in vars(cls).items() if callable(v) and not n.startswith("_"))
    return frozenset(names)


def offers(world: object, role: type) -> bool:
    """Whether ``world`` has every method of ``role``, asked by attribute lookup: a world
    seen through :class:`planner.testing.RoleView` (or any other proxy) answers as the
    world behind it does (``isinstance`` on a runtime-checkable Protocol does not look
    through ``__getattr__`` from Python 3.12 on)."""
    return all(callable(getattr(world, name, None)) for name in role_methods(role))


@runtime_checkable
class ArmJoints(Protocol):
    """An arm's joints, for a palm the palm law could not move (not part of
    :class:`WorldPort`: a world without joints, or one that keeps them to itself, leaves it
    out, and a leaf does without it)."""

    def arm_joints(self, arm: Arm) -> Array:
        """Measured joint positions of an arm, rad, (n,)."""
        ...

    def rest_joints(self, arm: Arm) -> Array:
        """The arm's rest posture, rad, (n,): its palm at :meth:`PalmControl.rest_palm_pose`
        with joints the arm shares with the other (a torso) at their own rest; where those
        stand elsewhere, the palm is elsewhere too."""
        ...

    def command_joints(self, arm: Arm, q: Array) -> None:
        """Hold the arm's joints at ``q`` (rad, (n,)) in joint space, its palm's command set
        aside until the next :meth:`PalmControl.command_palm` of the arm."""
        ...


@runtime_checkable
class ObstacleScene(Protocol):
    """The obstacles of the present move and the collision queries against them."""

    def set_active_obstacles(self, names: Iterable[str]) -> None:
        """Make exactly these obstacles present."""
        ...

    def obstacles(self) -> tuple[ObstacleInfo, ...]:
        """The obstacles present now."""
        ...

    def other_objects(self, name: str) -> tuple[ObstacleInfo, ...]:
        """The objects other than ``name`` where they lie now, each as its bounding sphere: an
        empty palms' path keeps clear of them as of the obstacles (:meth:`check_palm_path`),
        and a way in to ``name`` may go around them."""
        ...

    def obstacle_gap(self, name: str, within_m: float) -> ObstacleGap | None:
        """Object ``name``'s measured gap to the nearest present obstacle when it is under
        ``within_m`` m, else None (and None with no obstacle present)."""
        ...

    def check_trajectory(
        self,
        name: str,
        object_positions: Array,
        object_orientations: Array,
        palm_positions: Array,
        palm_orientations: Array,
        margin_m: float = 0.0,
        link_doubt: bool = True,
    ) -> PathCheck:
        """Check a predicted trajectory of the held object and both palms (and the arms that
        reach them) against the present obstacles.

        Shapes: object (N, 3), (N, 4); palms (N, 2, 3), (N, 2, 4), left then right.
        ``link_doubt``: where the world predicts the arms' links less surely than the palms,
        it may ask them more than ``margin_m`` (the simulator's grows with the palms' travel,
        :func:`worlds.path_checks.forearm_doubt`); False asks them ``margin_m`` alone.
        """
        ...

    def check_palm_path(
        self,
        palm_positions: Array,
        palm_orientations: Array,
        margin_m: float = 0.0,
        object_margin_m: float | None = None,
    ) -> PathCheck:
        """Check a predicted path of both palms holding nothing (an approach, a retreat), and
        the arm links carried with them, against the present obstacles (by ``margin_m``) and,
        where the world checks them, the objects where they rest (by ``object_margin_m``, the
        same as ``margin_m`` when None).

        Shapes: palms (N, 2, 3), (N, 2, 4), left then right.
        """
        ...

    def link_points(self) -> Array:
        """Points on the arms' links to keep away from obstacles, (M, 3), world frame."""
        ...

    def welded_spheres(self, arm: Arm) -> tuple[Array, Array]:
        """Bounding spheres of what is welded to ``arm``'s palm (a hand), palm apart: centres
        (K, 3) in the palm frame and radii (K,), m. It moves rigidly with a held object, so
        the object's obstacle steering steers it too; K may be 0."""
        ...

    def distance_query(self, points: Array) -> tuple[Array, Array]:
        """Distance (N,) from each point (N, 3) to the nearest obstacle, and its closest point."""
        ...

    def scene_query(self) -> SceneQuery:
        """The collision port the affordance reasoner's scene rules use."""
        ...


@runtime_checkable
class WorldPort(Clock, ObjectSensing, PalmControl, ObstacleScene, Protocol):
    """Everything a world offers the planner: all four roles. Units SI, world frame.

    A leaf's docstring names the roles it uses; a function that needs one role takes that
    role, so a test can hand it a stub of that role alone.
    """

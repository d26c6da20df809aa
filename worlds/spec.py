"""What a world is, as the core reads it: frozen dataclasses of floats, tuples and enums.

The world file's pydantic models (:mod:`worlds.world_schema`) stop at the file boundary:
:func:`worlds.world_file.world_spec` turns a validated world into a :class:`WorldSpec` once,
with every angle in radians or as a quaternion and every path resolved. The scene, the collision
mirror, the simulated world and the reasoner's adapters read only these.

Positions are in the world frame, m; quaternions scalar-last ``(x, y, z, w)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import StrEnum
from functools import lru_cache
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

# One vocabulary for every layer: the reasoner's shape, fragility and state enums.
from affordances.context import Fragility, ObjectState, Shape
from worlds.fixture_spec import FixtureSpec

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]


class RobotModelName(StrEnum):
    """Robot models the simulator knows. Adding a robot is one line here."""

    KUKA_IIWA = "kuka_iiwa"
    ICUB = "icub"


#: Models whose arms stand a fixed distance apart, m: a world's ``robot.arm_separation`` only
#: restates it (the iCub's shoulders).
FIXED_ARM_SEPARATION_M: dict[RobotModelName, float] = {RobotModelName.ICUB: 0.24}


class ObstacleKind(StrEnum):
    """Where a trial's obstacle sphere is drawn for a move (``app.py trials``)."""

    LINE = "line"  # above the straight path between the move's start and goal
    AHEAD = "ahead"  # in front (+x) of the carry, at the lifted object's height


@dataclass(frozen=True)
class ShapeSpec:
    """Geometry in the body frame, centred on the body origin.

    Attributes
    ----------
    kind : Shape
        Which of the fields below apply.
    size : tuple of float
        (3,) full box extents along x, y, z, m (BOX).
    radius : float
        Radius, m (CYLINDER, SPHERE).
    height : float
        Full height along z, m (CYLINDER).
    mesh_path : Path or None
        Mesh file, absolute once read from a world file (MESH); dynamic bodies collide with its
        convex hull.
    scale : float
        Uniform mesh scale (MESH).
    floor, rim : float
        A rimmed tray (BOX with ``rim > 0``): an open box of outer extents ``size``, its floor
        ``floor`` m thick at the bottom and its four walls ``rim`` m thick, up to the top. Every
        reader that needs only the outer box (extents, grasps, the reasoner, FCL) reads it as
        the box ``size``; the physics builds the floor and walls (:meth:`tray_boxes`).
    """

    kind: Shape
    size: Vec3 = (0.0, 0.0, 0.0)
    radius: float = 0.0
    height: float = 0.0
    mesh_path: Path | None = None
    scale: float = 1.0
    floor: float = 0.0
    rim: float = 0.0

    def __post_init__(self) -> None:
        ok = {
            Shape.BOX: min(self.size) > 0.0,
            Shape.CYLINDER: self.radius > 0.0 and self.height > 0.0,
            Shape.SPHERE: self.radius > 0.0,
            Shape.MESH: self.mesh_path is not None and self.scale > 0.0,
        }[Shape(self.kind)]
        if not ok:
            raise ValueError(
                f"ShapeSpec: expected positive dimensions for a {self.kind}, got {self}"
            )
        if self.rim > 0.0 and not (
            self.kind == Shape.BOX
            and 0.0 < self.floor < self.size[2]
            and 2.0 * self.rim < min(self.size[0], self.size[1])
        ):
            raise ValueError(
                "ShapeSpec: expected a tray's floor thinner than its height and its rims "
                f"narrower than half its width, got {self}"
            )

    @property
    def is_tray(self) -> bool:
        """Whether this is a rimmed tray (an open box), not a solid box."""
        return self.rim > 0.0

    def tray_boxes(self) -> list[tuple[Vec3, Vec3]]:
        """A tray's floor and four walls as boxes: (half extents, centre) each, body frame, m.

        The walls along x (the +-y walls) run the tray's full length and the +-x walls fit
        between them, so the boxes do not overlap.
        """
        x, y, z = (s / 2.0 for s in self.size)
        f, r = self.floor / 2.0, self.rim / 2.0
        wall = z - f  # half height of a wall, standing on the floor
        wz = -z + self.floor + wall
        return [
            ((x, y, f), (0.0, 0.0, -z + f)),
            ((x, r, wall), (0.0, y - r, wz)),
            ((x, r, wall), (0.0, -y + r, wz)),
            ((r, y - self.rim, wall), (x - r, 0.0, wz)),
            ((r, y - self.rim, wall), (-x + r, 0.0, wz)),
        ]

    @staticmethod
    def box(size: ArrayLike) -> ShapeSpec:
        """Box of full extents ``size`` (3,), m."""
        x, y, z = (float(v) for v in np.asarray(size, dtype=float).reshape(3))
        return ShapeSpec(Shape.BOX, size=(x, y, z))

    @staticmethod
    def tray(size: ArrayLike, floor: float, rim: float) -> ShapeSpec:
        """Rimmed tray of outer extents ``size`` (3,), floor and rim thicknesses, m."""
        x, y, z = (float(v) for v in np.asarray(size, dtype=float).reshape(3))
        return ShapeSpec(Shape.BOX, size=(x, y, z), floor=float(floor), rim=float(rim))

    @staticmethod
    def sphere(radius: float) -> ShapeSpec:
        """Sphere of ``radius``, m."""
        return ShapeSpec(Shape.SPHERE, radius=float(radius))

    @staticmethod
    def cylinder(radius: float, height: float) -> ShapeSpec:
        """Cylinder along z of ``radius`` and full ``height``, m."""
        return ShapeSpec(Shape.CYLINDER, radius=float(radius), height=float(height))

    @staticmethod
    def mesh(path: Path, scale: float = 1.0) -> ShapeSpec:
        """Triangle mesh in ``path`` scaled uniformly by ``scale``."""
        return ShapeSpec(Shape.MESH, mesh_path=Path(path), scale=float(scale))

    def bounding_radius(self) -> float:
        """Radius of a sphere around the body origin that holds the shape, m."""
        if self.kind == Shape.BOX:
            return 0.5 * float(np.linalg.norm(self.size))
        if self.kind == Shape.SPHERE:
            return self.radius
        if self.kind == Shape.CYLINDER:
            return float(np.hypot(self.radius, self.height / 2.0))
        return float(np.max(np.linalg.norm(self.mesh_vertices(), axis=1)))

    def extents(self) -> Vec3:
        """Full extents of the shape's bounding box along its own x, y, z, m (meshes: of their
        vertices; an object's must be centred on its origin, :mod:`worlds.mesh_sides`)."""
        if self.kind == Shape.BOX:
            return self.size
        if self.kind == Shape.SPHERE:
            d = 2.0 * self.radius
            return (d, d, d)
        if self.kind == Shape.CYLINDER:
            d = 2.0 * self.radius
            return (d, d, self.height)
        vertices = self.mesh_vertices()
        x, y, z = (float(v) for v in vertices.max(axis=0) - vertices.min(axis=0))
        return (x, y, z)

    def mesh_vertices(self) -> np.ndarray:
        """Scaled mesh vertices (V, 3), m (read-only: the file is read once per version)."""
        assert self.mesh_path is not None
        return _mesh_vertices(self.mesh_path, self.mesh_path.stat().st_mtime_ns) * self.scale


@lru_cache(maxsize=32)
def _mesh_vertices(path: Path, version: int) -> np.ndarray:
    """A mesh file's vertices (V, 3) as written, read once per ``version`` (its change time):
    a world's checks, its reasoner and its scene each ask for them."""
    import trimesh  # lazily: only worlds with meshes pay for it

    mesh = trimesh.load(path, force="mesh")
    assert isinstance(mesh, trimesh.Trimesh)
    vertices = np.asarray(mesh.vertices, dtype=float)
    vertices.flags.writeable = False
    return vertices


@dataclass(frozen=True)
class ObjectSpec:
    """A movable object on the table.

    Attributes
    ----------
    name : str
        Unique name.
    shape : ShapeSpec
        Geometry.
    mass : float
        Mass, kg.
    friction : float
        Lateral friction coefficient (Bullet multiplies the two bodies' coefficients).
    position : tuple of float
        (3,) initial centre in the world frame, m.
    quaternion : tuple of float
        (4,) initial orientation, scalar-last.
    category, material : str
        Free vocabulary the reasoner's rules match (``parcel``, ``cardboard``).
    fragility : Fragility
        How carefully to handle it.
    state : tuple of ObjectState
        Semantic state flags.
    yaw : float
        Initial rotation about world z as the file gives it, rad (the reasoner's footprint).
    """

    name: str
    shape: ShapeSpec
    mass: float
    friction: float
    position: Vec3
    quaternion: Quat = (0.0, 0.0, 0.0, 1.0)
    category: str = "object"
    material: str = "unknown"
    fragility: Fragility = Fragility.NORMAL
    state: tuple[ObjectState, ...] = ()
    yaw: float = 0.0

    def __post_init__(self) -> None:
        if self.mass <= 0.0 or self.friction < 0.0:
            raise ValueError(
                f"ObjectSpec {self.name!r}: expected mass > 0 and friction >= 0, "
                f"got {self.mass} and {self.friction}"
            )


@dataclass(frozen=True)
class ObstacleSpec:
    """A static obstacle (mass 0, no physics response).

    Attributes
    ----------
    name : str
        Unique name.
    shape : ShapeSpec
        Geometry.
    position : tuple of float
        (3,) centre in the world frame, m.
    """

    name: str
    shape: ShapeSpec
    position: Vec3


@dataclass(frozen=True)
class TableSpec:
    """The table: a static box whose top surface centre is ``position``.

    Attributes
    ----------
    position : tuple of float
        (3,) centre of the top surface, world frame, m.
    size : tuple of float
        (3,) length along x, width along y, height of the top above the floor, m.
    friction : float
        Lateral friction coefficient of the top.
    """

    position: Vec3 = (0.65, 0.0, 0.6)
    size: Vec3 = (0.6, 1.0, 0.6)
    friction: float = 0.5


@dataclass(frozen=True)
class RobotSpec:
    """The robot: which model, where, and its declared limits.

    Attributes
    ----------
    model : RobotModelName
        Robot model.
    base_position : tuple of float
        (3,) robot frame origin in the world, m.
    base_rpy_deg : tuple of float
        (3,) robot frame roll, pitch, yaw, degrees (the model builders' parameter).
    arm_separation : float
        Distance between the arm bases, m.
    mount_height : float
        Arm base height above the robot frame, m.
    palm_size : tuple of float
        (3,) palm box extents, m.
    payload_kg : float
        Payload per arm, kg.
    squeeze_force_n : float
        Largest steady squeeze per palm, N.
    """

    model: RobotModelName = RobotModelName.KUKA_IIWA
    base_position: Vec3 = (0.0, 0.0, 0.0)
    base_rpy_deg: Vec3 = (0.0, 0.0, 0.0)
    arm_separation: float = 0.7
    mount_height: float = 0.6
    palm_size: Vec3 = (0.12, 0.09, 0.02)
    payload_kg: float = 7.0
    squeeze_force_n: float = 40.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "model", RobotModelName(self.model))


def default_parcel() -> ObjectSpec:
    """The 1 kg, 0.20 x 0.30 x 0.15 m parcel at (0.6, 0, 0.675), friction 0.8."""
    return ObjectSpec(
        name="parcel",
        shape=ShapeSpec.box((0.20, 0.30, 0.15)),
        mass=1.0,
        friction=0.8,
        position=(0.6, 0.0, 0.675),
    )


#: Rounding allowed when a disturbance's window is turned into physics steps, in steps: a
#: window written as 0.5 s at 240 Hz starts at step 120 whatever 0.5 * 240 rounds to.
STEP_ROUNDING = 1e-6


@dataclass(frozen=True)
class DisturbanceSpec:
    """A scripted push: a force and a torque on an object over a window of simulated time.

    Both act at the object's centre of mass, in the world frame, on every physics step that
    starts inside the window (:meth:`steps`).

    Attributes
    ----------
    object : str
        Name of the object pushed.
    at_s : float
        Start of the window, simulated time, s, >= 0.
    duration_s : float
        Length of the window, s, > 0.
    force_n : tuple of float
        (3,) force, world frame, N.
    torque_nm : tuple of float
        (3,) torque, world frame, N m.
    while_held : bool
        Push only if both palms hold the object, off its support (touching no table,
        obstacle or fixture), when the window opens: a push during a carry, not while the
        palms set it down or let it go. Otherwise the whole window is skipped.
    """

    object: str
    at_s: float
    duration_s: float
    force_n: Vec3
    torque_nm: Vec3 = (0.0, 0.0, 0.0)
    while_held: bool = False

    def __post_init__(self) -> None:
        numbers = (self.at_s, self.duration_s, *self.force_n, *self.torque_nm)
        if (
            len(self.force_n) != 3
            or len(self.torque_nm) != 3
            or not all(math.isfinite(v) for v in numbers)
        ):
            raise ValueError(
                f"DisturbanceSpec {self.object!r}: expected finite numbers and 3-vectors, "
                f"got at_s={self.at_s}, duration_s={self.duration_s}, "
                f"force_n={self.force_n}, torque_nm={self.torque_nm}"
            )
        if self.at_s < 0.0 or self.duration_s <= 0.0:
            raise ValueError(
                f"DisturbanceSpec {self.object!r}: expected at_s >= 0 and duration_s > 0, "
                f"got {self.at_s} and {self.duration_s}"
            )

    def steps(self, physics_hz: int) -> range:
        """The physics steps the disturbance acts on.

        Step ``k`` starts at ``t = k / physics_hz``; it is pushed if
        ``at_s <= t < at_s + duration_s`` (times compared to :data:`STEP_ROUNDING` of a step),
        so a window of ``duration_s`` holds ``duration_s * physics_hz`` steps when that is a
        whole number, and a window shorter than a step may hold none.

        Parameters
        ----------
        physics_hz : int
            Physics rate, Hz.

        Returns
        -------
        range
            Indices of the physics steps, counted from 0 at the scene's start.
        """
        first = math.ceil(self.at_s * physics_hz - STEP_ROUNDING)
        stop = math.ceil((self.at_s + self.duration_s) * physics_hz - STEP_ROUNDING)
        return range(first, max(first, stop))


@dataclass(frozen=True)
class SceneSpec:
    """Everything needed to build a :class:`worlds.scene.Scene`.

    Attributes
    ----------
    robot : RobotSpec
        Robot model parameters.
    table : TableSpec
        The table.
    objects : tuple of ObjectSpec
        Movable objects.
    obstacles : tuple of ObstacleSpec
        Static obstacles (all inactive at the start).
    physics_hz : int
        Physics rate, Hz.
    control_hz : int
        Rate at which callers are expected to update palm commands, Hz.
    gravity : float
        Gravity along world z, m/s^2.
    seed : int
        Seed of the scene's random generator.
    disturbances : tuple of DisturbanceSpec
        Scripted pushes on the objects, in the world file's order (none by default).
    fixtures : tuple of FixtureSpec
        Open fixtures standing on the table (always present; none by default).
    """

    robot: RobotSpec = field(default_factory=RobotSpec)
    table: TableSpec = field(default_factory=TableSpec)
    objects: tuple[ObjectSpec, ...] = field(default_factory=lambda: (default_parcel(),))
    obstacles: tuple[ObstacleSpec, ...] = ()
    physics_hz: int = 240
    control_hz: int = 60
    gravity: float = -9.81
    seed: int = 0
    disturbances: tuple[DisturbanceSpec, ...] = ()
    fixtures: tuple[FixtureSpec, ...] = ()

    def __post_init__(self) -> None:
        if self.physics_hz <= 0 or self.control_hz <= 0 or self.physics_hz % self.control_hz:
            raise ValueError(
                "SceneSpec: expected physics_hz a positive multiple of control_hz, "
                f"got {self.physics_hz} and {self.control_hz}"
            )
        names = [o.name for o in self.objects] + [o.name for o in self.obstacles]
        names += [f.name for f in self.fixtures]
        duplicates = sorted({n for n in names if names.count(n) > 1})
        if duplicates:
            raise ValueError(f"SceneSpec: expected unique names, got duplicates {duplicates}")
        objects = [o.name for o in self.objects]
        unknown = [d.object for d in self.disturbances if d.object not in objects]
        if unknown:
            raise ValueError(
                f"SceneSpec: expected disturbances on objects in {objects}, got {unknown}"
            )

    def object_named(self, name: str) -> ObjectSpec:
        """The object called ``name``."""
        for obj in self.objects:
            if obj.name == name:
                return obj
        names = [o.name for o in self.objects]
        raise KeyError(f"SceneSpec: expected an object name in {names}, got {name!r}")


@dataclass(frozen=True)
class MoveSpec:
    """One place goal of an object, with the obstacles present while it moves there.

    Attributes
    ----------
    goal_position : tuple of float
        (3,) goal of the object's centre, world frame, m.
    goal_quaternion : tuple of float
        (4,) goal orientation, scalar-last.
    goal_yaw : float
        Goal rotation about world z as the file gives it, rad.
    obstacles : tuple of str
        Names of the obstacles present during the move.
    skill : str or None
        Name or label of the library's absolute skill the move is carried with; None for the
        plan's transport skill.
    fixture : str or None
        The fixture the move seats the object in (its goal is the seated pose); None for a
        placement on the table.
    """

    goal_position: Vec3
    goal_quaternion: Quat
    goal_yaw: float
    obstacles: tuple[str, ...] = ()
    skill: str | None = None
    fixture: str | None = None


@dataclass(frozen=True)
class TaskStepSpec:
    """Consecutive moves of one object; each starts where the last ended.

    Attributes
    ----------
    object : str
        Name of the object.
    moves : tuple of MoveSpec
        The goals, in order.
    """

    object: str
    moves: tuple[MoveSpec, ...]


@dataclass(frozen=True)
class WorldSpec:
    """A whole world as the core reads it.

    Attributes
    ----------
    name : str
        World name.
    scene : SceneSpec
        Robot, table, objects, obstacles and physics settings.
    task : tuple of TaskStepSpec
        What to move where.
    max_sim_time_s : float
        Simulated time limit of a run, s.
    skill_library : Path or None
        Folder of the skill library, absolute; None for the default library.
    source : Path or None
        The world file, absolute; None for a world built in code.
    """

    name: str
    scene: SceneSpec
    task: tuple[TaskStepSpec, ...]
    max_sim_time_s: float = 120.0
    skill_library: Path | None = None
    source: Path | None = None

    def moves_of(self, name: str) -> tuple[MoveSpec, ...]:
        """Every move of object ``name``, in task order."""
        return tuple(m for step in self.task if step.object == name for m in step.moves)


__all__ = [
    "STEP_ROUNDING",
    "DisturbanceSpec",
    "FixtureSpec",
    "Fragility",
    "MoveSpec",
    "ObjectSpec",
    "ObjectState",
    "ObstacleSpec",
    "RobotModelName",
    "RobotSpec",
    "SceneSpec",
    "Shape",
    "ShapeSpec",
    "TableSpec",
    "TaskStepSpec",
    "WorldSpec",
    "default_parcel",
]

"""World files: the YAML (or JSON) description of a dual-arm pick-and-place scene.

A world file names the robot, the table, the objects on it, the obstacles, the task (which
object goes where, with which obstacles present) and the simulation settings. This module
validates such a file with pydantic v2 and turns every problem into a :class:`WorldFileError`
that names the file, the field path, what was expected and what was received.

Conventions: SI units; angles in the file are degrees (``rpy_deg``); world frame z up; the
robot faces +x and its left arm is at +y. Relative paths (mesh files, skill library) are
resolved against the folder of the world file.

Examples
--------
>>> world = load_world("worlds/parcel_pick_place.yaml")  # doctest: +SKIP
>>> world.objects[0].pose.quaternion_xyzw()  # doctest: +SKIP
(0.0, 0.0, 0.0, 1.0)
"""

from __future__ import annotations

import json
import math
import os
import sys
import types
import typing
from collections.abc import Mapping, Sequence, Sized
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any, Literal

import yaml
from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    PrivateAttr,
    StrictBool,
    ValidationError,
    ValidationInfo,
    field_validator,
    model_validator,
)
from pydantic.fields import FieldInfo

from affordances.context import Fragility, ObjectState  # one vocabulary for both layers

__all__ = [
    "DEFAULT_SKILL_LIBRARY",
    "WORLD_FILE_VERSION",
    "BoxShape",
    "CylinderShape",
    "Fragility",
    "MeshShape",
    "Move",
    "ObjectState",
    "Obstacle",
    "Pose",
    "Range",
    "Region",
    "Robot",
    "RobotModelName",
    "Shape",
    "ShapeType",
    "SimSettings",
    "SkillSettings",
    "SphereShape",
    "Table",
    "TaskStep",
    "TrialSettings",
    "World",
    "WorldFileError",
    "WorldFileProblem",
    "WorldObject",
    "dump_world",
    "load_world",
    "world_cli_schema",
    "world_cli_validate",
    "world_json_schema",
]

WORLD_FILE_VERSION = 1
"""The only world file format version this module reads."""

DEFAULT_SKILL_LIBRARY = "default"
"""Value of ``skills.library`` that selects the skill library shipped with the project."""

_MAX_LISTED_PROBLEMS = 20
_MAX_SHOWN_CHARS = 80
_CONTEXT_BASE_DIR = "base_dir"


# --------------------------------------------------------------------------------------------
# Errors
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class WorldFileProblem:
    """One problem found in a world file.

    Attributes
    ----------
    field : str or None
        Path of the offending field, e.g. ``objects[0].mass``; None for whole-file problems.
    expected : str
        What the field (or file) should have been.
    received : str
        What was found instead, already formatted for display.
    line : int or None
        1-based line of a YAML/JSON syntax error, else None.
    column : int or None
        1-based column of a YAML/JSON syntax error, else None.
    """

    field: str | None
    expected: str
    received: str
    line: int | None = None
    column: int | None = None

    def format(self, file: str) -> str:
        """Render this problem as one line prefixed by ``file``."""
        if self.line is not None:
            where = f"{file}:{self.line}:{self.column}" if self.column else f"{file}:{self.line}"
            return f"{where}: {self.expected}: {self.received}"
        prefix = f"{file}: {self.field}" if self.field else file
        return f"{prefix}: expected {self.expected}, got {self.received}"


class WorldFileError(ValueError):
    """A world file could not be read or is not a valid world.

    ``str()`` gives one line per problem, each naming the file, the field path, what was
    expected and what was received, e.g.
    ``worlds/x.yaml: objects[0].mass: expected a number greater than 0, got -1.0``; YAML
    syntax errors read ``worlds/x.yaml:12:5: invalid YAML: <problem>``.

    Parameters
    ----------
    file : str
        The world file, as the caller named it.
    problems : sequence of WorldFileProblem
        At least one problem; the attributes below describe the first one.

    Attributes
    ----------
    file : str
        The world file, as the caller named it.
    field : str or None
        Path of the first offending field (``objects[0].mass``), None for whole-file problems.
    line : int or None
        1-based line of a syntax error, else None.
    expected : str
        What the first offending field (or the file) should have been.
    received : str
        What was found instead.
    problems : tuple of WorldFileProblem
        Every problem found (validation reports several at once).
    """

    def __init__(self, file: str, problems: Sequence[WorldFileProblem]) -> None:
        if not problems:
            raise ValueError("WorldFileError: expected at least one problem, got none")
        self.file = file
        self.problems = tuple(problems)
        first = self.problems[0]
        self.field = first.field
        self.line = first.line
        self.expected = first.expected
        self.received = first.received
        lines = [p.format(file) for p in self.problems[:_MAX_LISTED_PROBLEMS]]
        if len(self.problems) > _MAX_LISTED_PROBLEMS:
            lines.append(f"{file}: ... and {len(self.problems) - _MAX_LISTED_PROBLEMS} more")
        super().__init__("\n".join(lines))


@dataclass(frozen=True)
class _Issue:
    """A problem found by a validator; ``path`` is relative to where it was raised."""

    path: tuple[str | int, ...]
    expected: str
    received: str


class _FieldProblems(ValueError):
    """Raised inside validators so that the error keeps a field path and expected/received.

    pydantic wraps it in a ``value_error`` whose ``ctx["error"]`` is this exception; the
    conversion to :class:`WorldFileError` reads the issues back from there.
    """

    def __init__(self, issues: Sequence[_Issue]) -> None:
        self.issues = tuple(issues)
        super().__init__(
            "; ".join(
                f"{_format_path(i.path) or '<here>'}: expected {i.expected}, got {i.received}"
                for i in self.issues
            )
        )


def _problem(expected: str, received: Any, *path: str | int) -> _FieldProblems:
    return _FieldProblems([_Issue(tuple(path), expected, _show(received))])


def _show(value: Any) -> str:
    """Format a received value for an error message: a shortened repr, enums as values."""
    if isinstance(value, _Shown):
        return value.text
    text = repr(_plain(value))
    if len(text) > _MAX_SHOWN_CHARS:
        text = text[: _MAX_SHOWN_CHARS - 3] + "..."
    if not isinstance(value, str | int | float | bool | type(None) | list | tuple | dict):
        text = f"{text} ({type(value).__name__})"
    return text


def _plain(value: Any) -> Any:
    """Enums as their values and tuples as lists, so messages look like the file."""
    if isinstance(value, StrEnum):
        return value.value
    if isinstance(value, list | tuple):
        return [_plain(item) for item in value]
    return value


@dataclass(frozen=True)
class _Shown:
    """A received value that is already formatted (e.g. a description, not a repr)."""

    text: str


def _format_path(path: Sequence[str | int]) -> str:
    text = ""
    for item in path:
        if isinstance(item, int):
            text += f"[{item}]"
        else:
            text += f".{item}" if text else item
    return text


# --------------------------------------------------------------------------------------------
# Field types
# --------------------------------------------------------------------------------------------


def _vector3(value: Any) -> Any:
    """Check for exactly 3 finite numbers before pydantic's own tuple validation."""
    if isinstance(value, str | bytes) or not isinstance(value, Sequence):
        raise _problem("a list of exactly 3 numbers [x, y, z]", value)
    if len(value) != 3:
        raise _problem(
            "a list of exactly 3 numbers [x, y, z]", _Shown(f"{len(value)} items {_show(value)}")
        )
    for i, item in enumerate(value):
        _check_finite(item, i)
    return tuple(float(item) for item in value)


def _check_finite(item: Any, index: int) -> None:
    """Raise unless ``item`` (at ``index`` of a list) is a finite int or float, not a bool."""
    if isinstance(item, bool) or not isinstance(item, int | float):
        raise _problem("a number", item, index)
    try:
        finite = math.isfinite(item)
    except OverflowError:  # an int too large for a float
        finite = False
    if not finite:
        raise _problem("a finite number", item, index)


_Finite = Annotated[float, Field(strict=True, allow_inf_nan=False)]
_Positive = Annotated[float, Field(strict=True, allow_inf_nan=False, gt=0)]
_NonNegative = Annotated[float, Field(strict=True, allow_inf_nan=False, ge=0)]
_PositiveInt = Annotated[int, Field(strict=True, gt=0)]
_NonNegativeInt = Annotated[int, Field(strict=True, ge=0)]
_Name = Annotated[str, Field(strict=True, min_length=1)]
_Text = Annotated[str, Field(strict=True)]

Vector3 = Annotated[tuple[_Finite, _Finite, _Finite], BeforeValidator(_vector3)]
"""Three finite numbers ``[x, y, z]``."""

PositiveVector3 = Annotated[tuple[_Positive, _Positive, _Positive], BeforeValidator(_vector3)]
"""Three finite numbers ``[x, y, z]``, each greater than 0."""


def _range(value: Any) -> Any:
    """Check for exactly 2 finite numbers ``[low, high]`` with ``low <= high``."""
    if isinstance(value, str | bytes) or not isinstance(value, Sequence) or len(value) != 2:
        raise _problem("a list of exactly 2 numbers [low, high]", value)
    for i, item in enumerate(value):
        _check_finite(item, i)
    if value[0] > value[1]:
        raise _problem("low <= high", value)
    return (float(value[0]), float(value[1]))


Range = Annotated[tuple[_Finite, _Finite], BeforeValidator(_range)]
"""Two finite numbers ``[low, high]``, low <= high: values are drawn uniformly between them."""


class _FileModel(BaseModel):
    """Base of every world file model: unknown keys are errors and values are immutable."""

    model_config = ConfigDict(extra="forbid", frozen=True)


# --------------------------------------------------------------------------------------------
# Enums
# --------------------------------------------------------------------------------------------


class RobotModelName(StrEnum):
    """Robot models the simulator knows. Adding a robot is one line here."""

    KUKA_IIWA = "kuka_iiwa"
    ICUB = "icub"


class ShapeType(StrEnum):
    """Discriminator of the ``shape`` union."""

    BOX = "box"
    CYLINDER = "cylinder"
    SPHERE = "sphere"
    MESH = "mesh"


_EXCLUSIVE_STATES = ((ObjectState.OPEN, ObjectState.CLOSED), (ObjectState.FULL, ObjectState.EMPTY))


# --------------------------------------------------------------------------------------------
# Geometry
# --------------------------------------------------------------------------------------------


class Pose(_FileModel):
    """A position and a roll-pitch-yaw orientation in degrees.

    ``rpy_deg`` are extrinsic rotations about the fixed x, then y, then z axes (the
    URDF/PyBullet convention).
    """

    position: Vector3 = Field(description="position [x, y, z], m")
    rpy_deg: Vector3 = Field(
        default=(0.0, 0.0, 0.0),
        description="roll, pitch, yaw about the fixed x, y, z axes, degrees",
    )

    def quaternion_xyzw(self) -> tuple[float, float, float, float]:
        """Orientation as a unit quaternion, scalar last.

        Returns
        -------
        tuple of 4 float
            ``(x, y, z, w)``, same frame as ``position``.
        """
        from skills import quaternion as quat  # lazily: validating a file needs no numpy

        x, y, z, w = quat.from_rpy([math.radians(a) for a in self.rpy_deg]).tolist()
        return (x, y, z, w)


class BoxShape(_FileModel):
    """A box centred on its pose."""

    type: Literal[ShapeType.BOX] = ShapeType.BOX
    size: PositiveVector3 = Field(description="full extents [x, y, z] in the body frame, m")


class CylinderShape(_FileModel):
    """A cylinder centred on its pose, axis along the body z axis."""

    type: Literal[ShapeType.CYLINDER] = ShapeType.CYLINDER
    radius: _Positive = Field(description="radius, m, > 0")
    height: _Positive = Field(description="full height along z, m, > 0")


class SphereShape(_FileModel):
    """A sphere centred on its pose."""

    type: Literal[ShapeType.SPHERE] = ShapeType.SPHERE
    radius: _Positive = Field(description="radius, m, > 0")


class MeshShape(_FileModel):
    """A triangle mesh loaded with trimesh, in the body frame, scaled uniformly.

    ``file`` is kept as written; resolve it with :meth:`World.resolve_path`.
    """

    type: Literal[ShapeType.MESH] = ShapeType.MESH
    file: _Name = Field(
        description="mesh file (obj, stl, ply, ...), relative to the world file's folder"
    )
    scale: _Positive = Field(default=1.0, description="uniform scale factor, > 0")

    @field_validator("file")
    @classmethod
    def _mesh_loads(cls, file: str, info: ValidationInfo) -> str:
        path = _resolve(file, info)
        expected = "a mesh file that exists and trimesh can load"
        if not path.is_file():
            reason = "a folder" if path.is_dir() else "no such file"
            raise _problem(expected, _Shown(f"{file!r} ({reason}: {path})"))
        _check_mesh(path, file, expected)
        return file


def _check_mesh(path: Path, file: str, expected: str) -> None:
    import trimesh  # lazily: only worlds with meshes pay for it

    try:
        mesh = trimesh.load(path, force="mesh")
    except Exception as exc:  # trimesh raises many kinds; any of them means "unloadable"
        raise _problem(expected, _Shown(f"{file!r} ({type(exc).__name__}: {exc})")) from None
    if len(getattr(mesh, "faces", ())) == 0:
        raise _problem(expected, _Shown(f"{file!r} (no triangles in {path})"))


Shape = Annotated[
    BoxShape | CylinderShape | SphereShape | MeshShape,
    Field(discriminator="type"),
]
"""Geometry of an object or obstacle, selected by its ``type`` key."""


def _resolve(path: str, info: ValidationInfo) -> Path:
    """Resolve ``path`` against the world file's folder from the validation context."""
    candidate = Path(path)
    if candidate.is_absolute():
        return candidate
    context = info.context if isinstance(info.context, Mapping) else {}
    base = context.get(_CONTEXT_BASE_DIR)
    return (Path(base) if base is not None else Path.cwd()) / candidate


# --------------------------------------------------------------------------------------------
# Scene
# --------------------------------------------------------------------------------------------


class Robot(_FileModel):
    """The dual-arm robot: model, placement and hardware limits."""

    model: RobotModelName = Field(description="robot model")
    base: Pose = Field(
        description="robot frame in the world: midpoint between the two arm bases, x forward"
    )
    arm_separation: _Positive = Field(
        description="distance between the arm bases along the robot's y axis, m, > 0"
    )
    mount_height: _NonNegative = Field(
        description="height of the arm bases above the floor, m, >= 0"
    )
    payload_kg: _Positive = Field(description="payload per arm, kg, > 0")
    squeeze_force_n: _Positive = Field(description="largest steady squeeze per palm, N, > 0")
    palm_size: PositiveVector3 = Field(description="flat palm box extents [x, y, z], m")


class Table(_FileModel):
    """The table the objects stand on."""

    position: Vector3 = Field(description="centre of the table top surface, world frame, m")
    size: PositiveVector3 = Field(
        description="[length along x, width along y, height of the top above the floor], m"
    )
    friction: _NonNegative = Field(description="friction coefficient of the top, >= 0")

    @model_validator(mode="after")
    def _top_height_agrees(self) -> Table:
        # The top's height is written twice (position z and size z); disagreeing copies
        # would make the scene builder and the planner see different tables.
        if not math.isclose(self.position[2], self.size[2], abs_tol=1e-6):
            raise _problem(
                f"z equal to size[2] (the top's height above the floor, {self.size[2]} m)",
                self.position[2],
                "position",
                2,
            )
        return self


class WorldObject(_FileModel):
    """An object the robot can manipulate."""

    name: _Name = Field(description="unique name (across objects and obstacles)")
    category: _Name = Field(description="free text: parcel, box, glass, bottle, tray, ...")
    shape: Shape
    mass: _Positive = Field(description="mass, kg, > 0")
    friction: _NonNegative = Field(description="friction coefficient, >= 0")
    material: _Text = Field(default="unknown", description="free text: cardboard, glass, ...")
    fragility: Fragility = Field(default=Fragility.NORMAL, description="how carefully to handle")
    state: tuple[ObjectState, ...] = Field(default=(), description="semantic state flags")
    pose: Pose = Field(description="initial pose of the object's centre, world frame")

    @field_validator("state")
    @classmethod
    def _states_consistent(cls, state: tuple[ObjectState, ...]) -> tuple[ObjectState, ...]:
        issues = []
        for i, flag in enumerate(state):
            if flag in state[:i]:
                issues.append(_Issue((i,), "each state at most once", _show(flag)))
        for a, b in _EXCLUSIVE_STATES:
            if a in state and b in state:
                issues.append(
                    _Issue((), f"at most one of {a.value!r} and {b.value!r}", _show(state))
                )
        if issues:
            raise _FieldProblems(issues)
        return state


class Obstacle(_FileModel):
    """A static obstacle, present only during the moves that name it."""

    name: _Name = Field(description="unique name (across objects and obstacles)")
    shape: Shape
    position: Vector3 = Field(description="centre of the obstacle, world frame, m")


class Move(_FileModel):
    """One place goal for an object, with the obstacles present while moving there."""

    goal: Pose = Field(description="goal pose of the object's centre, world frame")
    obstacles: tuple[_Name, ...] = Field(
        default=(), description="names of the obstacles present during this move"
    )


class TaskStep(_FileModel):
    """A sequence of moves applied to one object; each move starts where the last ended."""

    object: _Name = Field(description="name of the object to move")
    moves: tuple[Move, ...] = Field(min_length=1, description="consecutive goals, at least 1")


class SimSettings(_FileModel):
    """Simulation rates, seed and limits."""

    physics_hz: _PositiveInt = Field(default=240, description="physics rate, Hz, > 0")
    control_hz: _PositiveInt = Field(
        default=60, description="control rate, Hz, > 0, divides physics_hz"
    )
    seed: _NonNegativeInt = Field(default=0, description="seed of every random choice, >= 0")
    gravity: _Finite = Field(default=-9.81, description="gravity along world z, m/s^2")
    max_sim_time_s: _Positive = Field(default=120.0, description="simulated time limit, s, > 0")
    compiled: StrictBool = Field(
        default=False,
        description="run the skills' composition step compiled (numba, the fast extra): "
        "within 1e-9 of the numpy path, several times faster",
    )

    @model_validator(mode="after")
    def _rates_divide(self) -> SimSettings:
        if self.physics_hz % self.control_hz != 0:
            raise _problem(
                f"a multiple of control_hz ({self.control_hz})", self.physics_hz, "physics_hz"
            )
        return self


class SkillSettings(_FileModel):
    """Where the skill library comes from."""

    library: _Name = Field(
        default=DEFAULT_SKILL_LIBRARY,
        description='"default", or a folder relative to the world file\'s folder',
    )

    @field_validator("library")
    @classmethod
    def _library_exists(cls, library: str, info: ValidationInfo) -> str:
        if library == DEFAULT_SKILL_LIBRARY:
            return library
        path = _resolve(library, info)
        if not path.is_dir():
            reason = "a file, not a folder" if path.exists() else "no such folder"
            raise _problem(
                f'"{DEFAULT_SKILL_LIBRARY}" or an existing folder',
                _Shown(f"{library!r} ({reason}: {path})"),
            )
        return library


class Region(_FileModel):
    """A rectangle of the table where an object's centre is drawn."""

    x: Range = Field(description="[low, high] of the centre's x, world frame, m")
    y: Range = Field(description="[low, high] of the centre's y, world frame, m")


class TrialSettings(_FileModel):
    """How ``app.py trials`` draws the paper's experiment in this world.

    The workspace depends on the robot, so the world says where the object starts, where its
    centre, right (-y) and left (+y) goals lie, and how the obstacle spheres are drawn. The
    defaults suit the default two-iiwa world.
    """

    start: Region = Field(
        default=Region(x=(0.50, 0.60), y=(-0.04, 0.04)), description="the object's start"
    )
    centre: Region = Field(
        default=Region(x=(0.58, 0.68), y=(-0.03, 0.03)), description="the first goal"
    )
    right: Region = Field(
        default=Region(x=(0.55, 0.65), y=(-0.18, -0.12)), description="the second goal (-y)"
    )
    left: Region = Field(
        default=Region(x=(0.55, 0.65), y=(0.12, 0.18)), description="the third goal (+y)"
    )
    sphere_radius: Range = Field(default=(0.03, 0.05), description="obstacle radius, m, > 0")
    line_gap: Range = Field(
        default=(0.03, 0.06),
        description="a sphere on the line: its bottom above the object's top, m",
    )
    ahead_gap: Range = Field(
        default=(0.0, 0.04),
        description="a sphere ahead: its surface in front (+x) of the object's front face, m",
    )
    ahead_height: Range = Field(
        default=(-0.02, 0.06),
        description="a sphere ahead: its centre above the object's top, m",
    )
    clearance: _NonNegative = Field(
        default=0.02,
        description="least gap between a sphere and the object at its move's start and goal, m",
    )
    robot_clearance: _NonNegative = Field(
        default=0.05,
        description="least gap between a sphere and the robot grasping the object at its "
        "move's start and goal, m",
    )
    lift: _NonNegative = Field(
        default=0.03,
        description="the robot_clearance holds also with the object lifted this much at the "
        "start and the goal (a carry begins with a lift and ends with a lowering), m",
    )

    @field_validator("sphere_radius")
    @classmethod
    def _radius_positive(cls, radius: tuple[float, float]) -> tuple[float, float]:
        if radius[0] <= 0.0:
            raise _problem("radii > 0", radius)
        return radius


class World(_FileModel):
    """A whole world file.

    The absolute path of the file it was loaded from is :attr:`source` (None when built in
    code); it is not a field, so it is neither in the schema nor written by :func:`dump_world`.
    """

    version: Annotated[int, Field(strict=True)] = Field(
        description="world file format version, must be 1",
        json_schema_extra={"const": WORLD_FILE_VERSION},
    )
    name: _Name = Field(description="world name")
    description: _Text = Field(default="", description="free text")
    robot: Robot
    table: Table
    objects: tuple[WorldObject, ...] = Field(min_length=1, description="at least 1 object")
    obstacles: tuple[Obstacle, ...] = Field(default=(), description="may be empty")
    task: tuple[TaskStep, ...] = Field(min_length=1, description="at least 1 step")
    sim: SimSettings = Field(default_factory=SimSettings)
    skills: SkillSettings = Field(default_factory=SkillSettings)
    trials: TrialSettings = Field(default_factory=TrialSettings)

    _source: Path | None = PrivateAttr(default=None)

    @property
    def source(self) -> Path | None:
        """Absolute path of the world file, or None if the world was built in code."""
        return self._source

    @property
    def base_dir(self) -> Path:
        """Folder that relative paths in the file are resolved against (cwd if no source)."""
        return self._source.parent if self._source is not None else Path.cwd()

    def resolve_path(self, path: str) -> Path:
        """Resolve a path written in the file (mesh, library) against :attr:`base_dir`."""
        candidate = Path(path)
        return candidate if candidate.is_absolute() else self.base_dir / candidate

    def object_named(self, name: str) -> WorldObject:
        """The object called ``name``; raises KeyError if there is none."""
        for obj in self.objects:
            if obj.name == name:
                return obj
        raise KeyError(f"world {self.name!r}: expected an object named {name!r}, found none")

    def obstacle_named(self, name: str) -> Obstacle:
        """The obstacle called ``name``; raises KeyError if there is none."""
        for obstacle in self.obstacles:
            if obstacle.name == name:
                return obstacle
        raise KeyError(f"world {self.name!r}: expected an obstacle named {name!r}, found none")

    @field_validator("version")
    @classmethod
    def _known_version(cls, version: int) -> int:
        if version != WORLD_FILE_VERSION:
            raise _problem(
                f"{WORLD_FILE_VERSION} (the only world file version this program reads)", version
            )
        return version

    @model_validator(mode="after")
    def _names_resolve(self, info: ValidationInfo) -> World:
        issues: list[_Issue] = []
        first_use: dict[str, str] = {}
        named: list[tuple[str, int, str]] = [
            ("objects", i, o.name) for i, o in enumerate(self.objects)
        ] + [("obstacles", i, o.name) for i, o in enumerate(self.obstacles)]
        for group, i, name in named:
            here = _format_path((group, i))
            if name in first_use:
                issues.append(
                    _Issue(
                        (group, i, "name"),
                        f"a name not already used (used by {first_use[name]})",
                        _show(name),
                    )
                )
            else:
                first_use[name] = here
        object_names = [o.name for o in self.objects]
        obstacle_names = [o.name for o in self.obstacles]
        for s, step in enumerate(self.task):
            if step.object not in object_names:
                issues.append(
                    _Issue(
                        ("task", s, "object"),
                        f"the name of an object ({_one_of(object_names)})",
                        _show(step.object),
                    )
                )
            for m, move in enumerate(step.moves):
                for k, obstacle in enumerate(move.obstacles):
                    if obstacle not in obstacle_names:
                        issues.append(
                            _Issue(
                                ("task", s, "moves", m, "obstacles", k),
                                f"the name of an obstacle ({_one_of(obstacle_names)})",
                                _show(obstacle),
                            )
                        )
                    elif obstacle in move.obstacles[:k]:
                        issues.append(
                            _Issue(
                                ("task", s, "moves", m, "obstacles", k),
                                "each obstacle named at most once per move",
                                _show(obstacle),
                            )
                        )
        if issues:
            raise _FieldProblems(issues)
        context = info.context if isinstance(info.context, Mapping) else {}
        source = context.get("source")
        if source is not None:
            self._source = Path(source)
        return self


def _one_of(names: Sequence[str]) -> str:
    if not names:
        return "there are none"
    return "one of " + ", ".join(repr(n) for n in names)


# --------------------------------------------------------------------------------------------
# pydantic errors -> WorldFileError
# --------------------------------------------------------------------------------------------


def _strip_annotated(annotation: Any) -> Any:
    while typing.get_origin(annotation) is Annotated:
        annotation = typing.get_args(annotation)[0]
    return annotation


def _is_model(annotation: Any) -> bool:
    return isinstance(annotation, type) and issubclass(annotation, BaseModel)


def _tagged_members(annotation: Any) -> dict[str, type[BaseModel]]:
    """Members of a discriminated union of models, keyed by their ``type`` tag."""
    if typing.get_origin(annotation) not in (typing.Union, types.UnionType):
        return {}
    members: dict[str, type[BaseModel]] = {}
    for arg in typing.get_args(annotation):
        arg = _strip_annotated(arg)
        if _is_model(arg) and "type" in arg.model_fields:
            tag = arg.model_fields["type"].default
            members[str(getattr(tag, "value", tag))] = arg
    return members


def _element_type(annotation: Any, index: int) -> Any:
    args = typing.get_args(annotation)
    if typing.get_origin(annotation) is tuple and args:
        if len(args) == 2 and args[1] is Ellipsis:
            return args[0]
        return args[index] if 0 <= index < len(args) else None
    if typing.get_origin(annotation) is list and args:
        return args[0]
    return None


@dataclass(frozen=True)
class _Located:
    path: tuple[str | int, ...]
    parent: type[BaseModel] | None
    field: FieldInfo | None


def _locate(loc: Sequence[str | int]) -> _Located:
    """Turn a pydantic ``loc`` into a user-facing path, dropping union tags.

    Also returns the model holding the last key and that key's field, if any, so messages
    can list the allowed keys or describe a missing field.
    """
    annotation: Any = World
    path: list[str | int] = []
    parent: type[BaseModel] | None = None
    field: FieldInfo | None = None
    for item in loc:
        annotation = _strip_annotated(annotation)
        if isinstance(item, int):
            path.append(item)
            annotation = _element_type(annotation, item)
            parent, field = None, None
            continue
        members = _tagged_members(annotation)
        if item in members:
            annotation = members[item]
            continue
        path.append(item)
        if _is_model(annotation):
            parent = annotation
            field = annotation.model_fields.get(item)
            annotation = field.annotation if field is not None else None
        else:
            parent, field, annotation = None, None, None
    return _Located(tuple(path), parent, field)


_EXPECTED_BY_TYPE = {
    "float_type": "a number",
    "float_parsing": "a number",
    "int_type": "a whole number",
    "int_parsing": "a whole number",
    "int_from_float": "a whole number",
    "string_type": "text",
    "bool_type": "true or false",
    "tuple_type": "a list",
    "list_type": "a list",
    "dict_type": "a mapping of keys to values",
    "model_type": "a mapping of keys to values",
    "model_attributes_type": "a mapping of keys to values",
    "finite_number": "a finite number",
}


def _problems_from(error: ValidationError) -> list[WorldFileProblem]:
    """Translate every pydantic error into a :class:`WorldFileProblem`."""
    problems: list[WorldFileProblem] = []
    errors = error.errors()
    for err in errors:
        if err["type"] == "too_short" and any(
            len(other["loc"]) > len(err["loc"]) and other["loc"][: len(err["loc"])] == err["loc"]
            for other in errors
        ):
            continue  # pydantic also reports a tuple as too short when one of its items fails
        located = _locate(err["loc"])
        kind = err["type"]
        ctx = err.get("ctx") or {}
        value = err.get("input")
        cause = ctx.get("error")
        if isinstance(cause, _FieldProblems):
            for issue in cause.issues:
                where = _format_path(located.path + issue.path) or None
                problems.append(WorldFileProblem(where, issue.expected, issue.received))
            continue
        path = located.path
        if kind == "missing":
            what = located.field.description if located.field is not None else None
            expected = f"a value ({what})" if what else "a value"
            received = "nothing (the key is missing)"
        elif kind == "extra_forbidden":
            allowed = ", ".join(located.parent.model_fields) if located.parent else "none"
            expected = f"only the keys {allowed}"
            received = f"unknown key {path[-1]!r}" if path else _show(value)
        elif kind in ("union_tag_invalid", "union_tag_not_found"):
            path = (*path, "type")
            tags = ", ".join(repr(t.value) for t in ShapeType)
            expected = f"a shape type, one of {tags}"
            received = _show(ctx["tag"]) if "tag" in ctx else "nothing (the key is missing)"
        elif kind in ("greater_than", "greater_than_equal", "less_than", "less_than_equal"):
            relation = {
                "greater_than": ("gt", "greater than"),
                "greater_than_equal": ("ge", "greater than or equal to"),
                "less_than": ("lt", "less than"),
                "less_than_equal": ("le", "less than or equal to"),
            }[kind]
            expected = f"a number {relation[1]} {_number(ctx.get(relation[0]))}"
            received = _show(value)
        elif kind in ("too_short", "too_long", "string_too_short", "string_too_long"):
            expected, received = _length_problem(kind, ctx, value)
        elif kind == "invalid_key":
            path = path[:-1]
            expected = "text keys"
            received = f"key {_show(err['loc'][-1])}"
        elif kind in ("enum", "literal_error"):
            expected = f"one of {ctx.get('expected')}"
            received = _show(value)
        elif kind in _EXPECTED_BY_TYPE:
            expected = _EXPECTED_BY_TYPE[kind]
            received = _show(value)
        else:
            message = str(err.get("msg", kind))
            expected = message.removeprefix("Input should be ").removeprefix("Value error, ")
            received = _show(value)
        problems.append(WorldFileProblem(_format_path(path) or None, expected, received))
    return problems


def _number(value: Any) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


def _length_problem(kind: str, ctx: Mapping[str, Any], value: Any) -> tuple[str, str]:
    is_text = kind.startswith("string")
    if kind.endswith("short"):
        least = ctx.get("min_length")
        expected = f"non-empty text (at least {least} character)" if is_text else None
        expected = expected or f"a list with at least {least} item{'s' if least != 1 else ''}"
    else:
        most = ctx.get("max_length")
        expected = f"at most {most} {'characters' if is_text else 'items'}"
    if is_text:
        return expected, _show(value)
    count = ctx.get("actual_length")
    count = len(value) if count is None and isinstance(value, Sized) else count
    return expected, f"{count} item{'s' if count != 1 else ''}"


# --------------------------------------------------------------------------------------------
# Reading files
# --------------------------------------------------------------------------------------------


class _StrictLoader(yaml.SafeLoader):
    """Safe YAML loader that rejects duplicate keys (PyYAML silently keeps the last one)."""


def _construct_mapping(loader: yaml.SafeLoader, node: yaml.MappingNode) -> dict[Any, Any]:
    # Only keys written in this mapping count: keys merged in with "<<" may be overridden.
    seen: set[Any] = set()
    for key_node, _ in node.value:
        if key_node.tag == "tag:yaml.org,2002:merge":
            continue
        key = loader.construct_object(key_node, deep=True)
        try:
            duplicate = key in seen
            seen.add(key)
        except TypeError:
            raise yaml.constructor.ConstructorError(
                "while constructing a mapping",
                node.start_mark,
                "found an unhashable key",
                key_node.start_mark,
            ) from None
        if duplicate:
            raise yaml.constructor.ConstructorError(
                "while constructing a mapping",
                node.start_mark,
                f"found duplicate key {key!r}",
                key_node.start_mark,
            )
    return loader.construct_mapping(node, deep=True)


_StrictLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)


def _read_text(path: Path, label: str) -> str:
    expected = "a readable UTF-8 world file"
    try:
        is_dir = path.is_dir()
        data = b"" if is_dir else path.read_bytes()
    except FileNotFoundError:
        raise WorldFileError(label, [WorldFileProblem(None, expected, "no such file")]) from None
    except PermissionError:
        problem = WorldFileProblem(None, expected, "permission denied")
        raise WorldFileError(label, [problem]) from None
    except (OSError, ValueError) as exc:
        problem = WorldFileProblem(None, expected, f"{type(exc).__name__}: {exc}")
        raise WorldFileError(label, [problem]) from None
    if is_dir:
        raise WorldFileError(label, [WorldFileProblem(None, expected, "a folder")])
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        received = f"byte 0x{data[exc.start]:02x} at offset {exc.start}, which is not UTF-8"
        raise WorldFileError(label, [WorldFileProblem(None, expected, received)]) from None


def _parse(text: str, path: Path, label: str) -> Any:
    """Parse YAML (or JSON for ``.json`` files), reporting syntax errors with line:column."""
    if path.suffix.lower() == ".json":
        try:
            return json.loads(text)
        except json.JSONDecodeError as exc:
            problem = WorldFileProblem(None, "invalid JSON", exc.msg, exc.lineno, exc.colno)
            raise WorldFileError(label, [problem]) from None
        except RecursionError:
            problem = WorldFileProblem(None, "a world file", "JSON nested too deeply")
            raise WorldFileError(label, [problem]) from None
    try:
        return yaml.load(text, Loader=_StrictLoader)  # a SafeLoader subclass
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        reason = exc.problem or exc.context or "syntax error"
        if exc.problem and exc.context and exc.context_mark is not None:
            start = exc.context_mark
            reason += f" ({exc.context} at line {start.line + 1}, column {start.column + 1})"
        line = mark.line + 1 if mark is not None else 1
        column = mark.column + 1 if mark is not None else None
        problem = WorldFileProblem(None, "invalid YAML", reason, line, column)
        raise WorldFileError(label, [problem]) from None
    except yaml.YAMLError as exc:
        raise WorldFileError(label, [WorldFileProblem(None, "valid YAML", str(exc))]) from None
    except RecursionError:
        problem = WorldFileProblem(None, "a world file", "YAML nested too deeply")
        raise WorldFileError(label, [problem]) from None


def load_world(path: str | os.PathLike[str]) -> World:
    """Read and validate a world file (YAML, or JSON if the name ends in ``.json``).

    Parameters
    ----------
    path : str or path-like
        The world file. Relative paths inside it resolve against its folder.

    Returns
    -------
    World
        The validated world; ``world.source`` is the absolute path of the file.

    Raises
    ------
    WorldFileError
        If the file is missing, unreadable, not UTF-8, not valid YAML/JSON, or not a valid
        world. The message names the file, the field path, what was expected and what was
        received.
    """
    label = os.fspath(path)
    file = Path(label)
    data = _parse(_read_text(file, label), file, label)
    if not isinstance(data, Mapping):
        received = "an empty file" if data is None else _show(data)
        top = f"a mapping with the keys {', '.join(World.model_fields)}"
        raise WorldFileError(label, [WorldFileProblem(None, top, received)])
    source = file.absolute()
    context = {_CONTEXT_BASE_DIR: source.parent, "source": source}
    try:
        return World.model_validate(data, context=context)
    except ValidationError as exc:
        raise WorldFileError(label, _problems_from(exc)) from None
    except RecursionError:
        problem = WorldFileProblem(None, "a world file", "data nested too deeply")
        raise WorldFileError(label, [problem]) from None


def dump_world(world: World) -> str:
    """Write a world as YAML text that :func:`load_world` reads back to an equal world.

    Parameters
    ----------
    world : World
        The world to write.

    Returns
    -------
    str
        YAML text, keys in schema order, enums as their values, vectors as lists.
    """
    return yaml.safe_dump(world.model_dump(mode="json"), sort_keys=False, allow_unicode=True)


def world_json_schema() -> dict[str, Any]:
    """JSON Schema (draft 2020-12) of world files, for editors and documentation.

    Returns
    -------
    dict
        The schema; cross-field checks (names resolve, rates divide, mesh files load) are
        described in field descriptions but only enforced by :func:`load_world`.
    """
    schema = World.model_json_schema()
    return {"$schema": "https://json-schema.org/draft/2020-12/schema", **schema}


# --------------------------------------------------------------------------------------------
# Command line (wired into app.py by the lead)
# --------------------------------------------------------------------------------------------


def world_cli_validate(path: str) -> int:
    """``app.py validate FILE``: check a world file and print the verdict.

    Parameters
    ----------
    path : str
        The world file.

    Returns
    -------
    int
        0 if the world is valid (summary on stdout), 2 if it is not (one line per problem on
        stderr), 1 on an internal error (message on stderr, never a traceback).
    """
    try:
        world = load_world(path)
    except WorldFileError as exc:
        print(exc, file=sys.stderr)
        return 2
    except Exception as exc:  # the command line promises no tracebacks
        print(
            f"{path}: internal error while validating: {type(exc).__name__}: {exc}", file=sys.stderr
        )
        return 1
    moves = sum(len(step.moves) for step in world.task)
    print(
        f"{path}: ok: world {world.name!r}, {_count(len(world.objects), 'object')}, "
        f"{_count(len(world.obstacles), 'obstacle')}, {_count(len(world.task), 'task step')}, "
        f"{_count(moves, 'move')}"
    )
    return 0


def world_cli_schema() -> int:
    """``app.py schema``: print the JSON Schema of world files to stdout; returns 0."""
    print(json.dumps(world_json_schema(), indent=2))
    return 0


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}{'' if n == 1 else 's'}"

"""The world file's schema: pydantic v2 models of a dual-arm pick-and-place world.

Every model forbids unknown keys and is immutable. Validators raise
:class:`worlds.world_errors.FieldProblems`, so that a bad value reports its field path, what
was expected and what was received. The core never reads these models: it reads the
dataclasses of :mod:`worlds.spec`, made once by :func:`worlds.world_file.world_spec`.

Conventions: SI units; angles in the file are degrees (``rpy_deg``); world frame z up; the
robot faces its frame's +x with its left arm at +y (its base pose places that frame in the
world: a robot may face the table from any side). Relative paths (mesh files, skill library) are
resolved against the folder of the world file.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    PrivateAttr,
    SerializerFunctionWrapHandler,
    StrictBool,
    ValidationInfo,
    field_validator,
    model_serializer,
    model_validator,
)

from worlds.fixture_schema import Fixture, InsertionTrials, fixture_issues
from worlds.spec import Fragility, ObjectState, ObstacleKind, RobotModelName, Shape
from worlds.world_errors import FieldProblems, Issue, Shown, field_problem, format_path, show_value

WORLD_FILE_VERSION = 1
"""The only world file format version this module reads."""

DEFAULT_SKILL_LIBRARY = "default"
"""Value of ``skills.library`` that selects the skill library shipped with the project."""

CONTEXT_BASE_DIR = "base_dir"
"""Key of the validation context that holds the folder relative paths resolve against."""


# --------------------------------------------------------------------------------------------
# Field types
# --------------------------------------------------------------------------------------------


def _vector3(value: Any) -> Any:
    """Check for exactly 3 finite numbers before pydantic's own tuple validation."""
    if isinstance(value, str | bytes) or not isinstance(value, Sequence):
        raise field_problem("a list of exactly 3 numbers [x, y, z]", value)
    if len(value) != 3:
        raise field_problem(
            "a list of exactly 3 numbers [x, y, z]",
            Shown(f"{len(value)} items {show_value(value)}"),
        )
    for i, item in enumerate(value):
        _check_finite(item, i)
    return tuple(float(item) for item in value)


def _check_finite(item: Any, index: int) -> None:
    """Raise unless ``item`` (at ``index`` of a list) is a finite int or float, not a bool."""
    if isinstance(item, bool) or not isinstance(item, int | float):
        raise field_problem("a number", item, index)
    try:
        finite = math.isfinite(item)
    except OverflowError:  # an int too large for a float
        finite = False
    if not finite:
        raise field_problem("a finite number", item, index)


#: Largest magnitude of any number in a world file: far beyond anything the physics can mean
#: (a 1e308 m position validated, then turned into NaN in the first physics step).
LIMIT = 1e6
#: Largest magnitude of a position or an extent, m: a tabletop world is metres across.
LIMIT_M = 100.0
_Finite = Annotated[float, Field(strict=True, allow_inf_nan=False, ge=-LIMIT, le=LIMIT)]
_Positive = Annotated[float, Field(strict=True, allow_inf_nan=False, gt=0, le=LIMIT)]
_NonNegative = Annotated[float, Field(strict=True, allow_inf_nan=False, ge=0, le=LIMIT)]
_PositiveInt = Annotated[int, Field(strict=True, gt=0, le=10**9)]
_NonNegativeInt = Annotated[int, Field(strict=True, ge=0, le=2**63 - 1)]
_Metres = Annotated[float, Field(strict=True, allow_inf_nan=False, ge=-LIMIT_M, le=LIMIT_M)]
_PositiveMetres = Annotated[float, Field(strict=True, allow_inf_nan=False, gt=0, le=LIMIT_M)]
_Name = Annotated[str, Field(strict=True, min_length=1)]
_Text = Annotated[str, Field(strict=True)]
#: A skill's name or label in a library: letters, digits, '_' or '-', not starting with a digit.
_SKILL_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_-]*")

Vector3 = Annotated[tuple[_Metres, _Metres, _Metres], BeforeValidator(_vector3)]
"""Three finite numbers ``[x, y, z]``, within 100 (a position, m)."""

FiniteVector3 = Annotated[tuple[_Finite, _Finite, _Finite], BeforeValidator(_vector3)]
"""Three finite numbers ``[x, y, z]``, within 1e6 (a force, N, or a torque, N m)."""

_Degrees = Annotated[float, Field(strict=True, allow_inf_nan=False, ge=-720.0, le=720.0)]
Angles3 = Annotated[tuple[_Degrees, _Degrees, _Degrees], BeforeValidator(_vector3)]
"""Three finite angles ``[roll, pitch, yaw]``, degrees, within two turns either way."""

PositiveVector3 = Annotated[
    tuple[_PositiveMetres, _PositiveMetres, _PositiveMetres], BeforeValidator(_vector3)
]
"""Three finite numbers ``[x, y, z]``, each greater than 0 and at most 100 (extents, m)."""


def _range(value: Any) -> Any:
    """Check for exactly 2 finite numbers ``[low, high]`` with ``low <= high``."""
    if isinstance(value, str | bytes) or not isinstance(value, Sequence) or len(value) != 2:
        raise field_problem("a list of exactly 2 numbers [low, high]", value)
    for i, item in enumerate(value):
        _check_finite(item, i)
    if value[0] > value[1]:
        raise field_problem("low <= high", value)
    return (float(value[0]), float(value[1]))


Range = Annotated[tuple[_Finite, _Finite], BeforeValidator(_range)]
"""Two finite numbers ``[low, high]``, low <= high: values are drawn uniformly between them."""


def _optional_range(value: Any) -> Any:
    """A :data:`Range`, or None (left to a default)."""
    return None if value is None else _range(value)


OptionalRange = Annotated[tuple[_Finite, _Finite] | None, BeforeValidator(_optional_range)]
"""A :data:`Range`, or None for a default given elsewhere."""


class _FileModel(BaseModel):
    """Base of every world file model: unknown keys are errors and values are immutable."""

    model_config = ConfigDict(extra="forbid", frozen=True)


_EXCLUSIVE_STATES = ((ObjectState.OPEN, ObjectState.CLOSED), (ObjectState.FULL, ObjectState.EMPTY))


# --------------------------------------------------------------------------------------------
# Geometry
# --------------------------------------------------------------------------------------------


class PoseEntry(_FileModel):
    """A position and a roll-pitch-yaw orientation in degrees.

    ``rpy_deg`` are extrinsic rotations about the fixed x, then y, then z axes (the
    URDF/PyBullet convention).
    """

    position: Vector3 = Field(description="position [x, y, z], m")
    rpy_deg: Angles3 = Field(
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

    type: Literal[Shape.BOX] = Shape.BOX
    size: PositiveVector3 = Field(description="full extents [x, y, z] in the body frame, m")


class TrayShape(_FileModel):
    """A rimmed tray centred on its pose: an open box, a floor and four walls up to the top.

    The palms squeeze the outer faces of its +-y walls, as they squeeze a box's y faces.
    """

    type: Literal["tray"] = "tray"
    size: PositiveVector3 = Field(description="outer extents [x, y, height] in the body frame, m")
    floor: _Positive = Field(description="floor thickness, m, > 0 and below the height")
    rim: _Positive = Field(description="wall thickness, m, > 0 and below half of x and y")

    @model_validator(mode="after")
    def _fits(self) -> TrayShape:
        if self.floor >= self.size[2]:
            raise field_problem(
                f"a floor thinner than the tray's height ({self.size[2]:g} m)", self.floor, "floor"
            )
        half = min(self.size[0], self.size[1]) / 2.0
        if self.rim >= half:
            raise field_problem(
                f"a rim thinner than half the tray's width ({half:g} m)", self.rim, "rim"
            )
        return self


class CylinderShape(_FileModel):
    """A cylinder centred on its pose, axis along the body z axis."""

    type: Literal[Shape.CYLINDER] = Shape.CYLINDER
    radius: _Positive = Field(description="radius, m, > 0")
    height: _Positive = Field(description="full height along z, m, > 0")


class SphereShape(_FileModel):
    """A sphere centred on its pose."""

    type: Literal[Shape.SPHERE] = Shape.SPHERE
    radius: _Positive = Field(description="radius, m, > 0")


class MeshShape(_FileModel):
    """A triangle mesh loaded with trimesh, in the body frame, scaled uniformly.

    ``file`` is kept as written; resolve it with :meth:`World.resolve_path`.
    """

    type: Literal[Shape.MESH] = Shape.MESH
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
            raise field_problem(expected, Shown(f"{file!r} ({reason}: {path})"))
        _check_mesh(path, file, expected)
        return file


def _check_mesh(path: Path, file: str, expected: str) -> None:
    import trimesh  # lazily: only worlds with meshes pay for it

    try:
        mesh = trimesh.load(path, force="mesh")
    except Exception as exc:  # trimesh raises many kinds; any of them means "unloadable"
        raise field_problem(expected, Shown(f"{file!r} ({type(exc).__name__}: {exc})")) from None
    if len(getattr(mesh, "faces", ())) == 0:
        raise field_problem(expected, Shown(f"{file!r} (no triangles in {path})"))


ShapeModel = Annotated[
    BoxShape | TrayShape | CylinderShape | SphereShape | MeshShape,
    Field(discriminator="type"),
]
"""Geometry of an object or obstacle, selected by its ``type`` key (a :class:`Shape`)."""


def _resolve(path: str, info: ValidationInfo) -> Path:
    """Resolve ``path`` against the world file's folder from the validation context."""
    candidate = Path(path)
    if candidate.is_absolute():
        return candidate
    context = info.context if isinstance(info.context, Mapping) else {}
    base = context.get(CONTEXT_BASE_DIR)
    return (Path(base) if base is not None else Path.cwd()) / candidate


# --------------------------------------------------------------------------------------------
# Scene
# --------------------------------------------------------------------------------------------


class Robot(_FileModel):
    """The dual-arm robot: model, placement and hardware limits."""

    model: RobotModelName = Field(description="robot model")
    base: PoseEntry = Field(
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
            raise field_problem(
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
    shape: ShapeModel
    mass: _Positive = Field(description="mass, kg, > 0")
    friction: _NonNegative = Field(description="friction coefficient, >= 0")
    material: _Text = Field(default="unknown", description="free text: cardboard, glass, ...")
    fragility: Fragility = Field(default=Fragility.NORMAL, description="how carefully to handle")
    state: tuple[ObjectState, ...] = Field(default=(), description="semantic state flags")
    pose: PoseEntry = Field(description="initial pose of the object's centre, world frame")

    @field_validator("state")
    @classmethod
    def _states_consistent(cls, state: tuple[ObjectState, ...]) -> tuple[ObjectState, ...]:
        issues = []
        for i, flag in enumerate(state):
            if flag in state[:i]:
                issues.append(Issue((i,), "each state at most once", show_value(flag)))
        for a, b in _EXCLUSIVE_STATES:
            if a in state and b in state:
                issues.append(
                    Issue((), f"at most one of {a.value!r} and {b.value!r}", show_value(state))
                )
        if issues:
            raise FieldProblems(issues)
        return state


class Obstacle(_FileModel):
    """A static obstacle, present only during the moves that name it."""

    name: _Name = Field(description="unique name (across objects and obstacles)")
    shape: ShapeModel
    position: Vector3 = Field(description="centre of the obstacle, world frame, m")


class MoveEntry(_FileModel):
    """One place goal for an object, with the obstacles present while moving there."""

    goal: PoseEntry = Field(description="goal pose of the object's centre, world frame")
    obstacles: tuple[_Name, ...] = Field(
        default=(), description="names of the obstacles present during this move"
    )
    skill: _Name | None = Field(
        default=None,
        description="name or label of the library's absolute skill this move is carried with "
        "(a taught skill's label); default: the plan's transport skill",
    )
    fixture: _Name | None = Field(
        default=None,
        description="the fixture (fixtures[].name) this move seats the object in; the goal "
        "must then be the seated pose",
    )

    @field_validator("skill")
    @classmethod
    def _skill_is_a_name(cls, skill: str | None) -> str | None:
        if skill is not None and _SKILL_NAME.fullmatch(skill) is None:
            raise field_problem("a skill name or label (letters, digits, '_' or '-')", skill)
        return skill

    @model_serializer(mode="wrap")
    def _without_no_fixture(self, handler: SerializerFunctionWrapHandler) -> Any:
        # A move into no fixture dumps as before fixtures existed (its world's content hash
        # names its trial campaigns, experiment.records).
        data = handler(self)
        if self.fixture is None and isinstance(data, dict):
            data.pop("fixture", None)
        return data


class TaskStep(_FileModel):
    """A sequence of moves applied to one object; each move starts where the last ended."""

    object: _Name = Field(description="name of the object to move")
    moves: tuple[MoveEntry, ...] = Field(min_length=1, description="consecutive goals, at least 1")


class DisturbanceEntry(_FileModel):
    """A scripted push on an object: a force (and a torque) over a window of simulated time.

    Both act at the object's centre of mass, in the world frame, on every physics step whose
    start time ``t`` has ``at_s <= t < at_s + duration_s``.
    """

    at_s: _NonNegative = Field(description="start of the window, simulated time, s, >= 0")
    object: _Name = Field(description="name of the object pushed")
    force_n: FiniteVector3 = Field(description="force [x, y, z], world frame, N")
    duration_s: _Positive = Field(description="length of the window, s, > 0")
    torque_nm: FiniteVector3 = Field(
        default=(0.0, 0.0, 0.0), description="torque [x, y, z], world frame, N m"
    )
    while_held: StrictBool = Field(
        default=False,
        description="push only if both palms hold the object when the window opens (a push "
        "during a carry); otherwise the window is skipped",
    )


class SimSettings(_FileModel):
    """Simulation rates, seed and limits."""

    physics_hz: Annotated[int, Field(strict=True, ge=60, le=10_000)] = Field(
        default=240, description="physics rate, Hz, 60 to 10000"
    )
    control_hz: Annotated[int, Field(strict=True, ge=10, le=1000)] = Field(
        default=60, description="control rate, Hz, 10 to 1000, divides physics_hz"
    )
    seed: _NonNegativeInt = Field(
        default=0,
        description="seed of a run's random choices, >= 0; a run of the shipped leaves makes "
        "none (physics, skills and tree are deterministic); trials draw from their own seed",
    )
    gravity: _Finite = Field(default=-9.81, description="gravity along world z, m/s^2")
    max_sim_time_s: Annotated[float, Field(strict=True, allow_inf_nan=False, gt=0, le=86_400)] = (
        Field(default=120.0, description="simulated time limit, s, > 0, at most a day")
    )
    max_wall_time_s: Annotated[float, Field(strict=True, allow_inf_nan=False, gt=0, le=86_400)] = (
        Field(
            default=3600.0,
            description="wall-clock limit of a run, s: a run still going then ends as a failure",
        )
    )
    compiled: StrictBool = Field(
        default=True,
        description="ignored, kept so that older files load: every composition runs compiled",
    )

    @model_validator(mode="after")
    def _rates_divide(self) -> SimSettings:
        if self.physics_hz % self.control_hz != 0:
            raise field_problem(
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
            raise field_problem(
                f'"{DEFAULT_SKILL_LIBRARY}" or an existing folder',
                Shown(f"{library!r} ({reason}: {path})"),
            )
        return library


class Region(_FileModel):
    """A rectangle of the table where an object's centre is drawn."""

    x: Range = Field(description="[low, high] of the centre's x, world frame, m")
    y: Range = Field(description="[low, high] of the centre's y, world frame, m")


def _yaw_in_a_turn(yaw: tuple[float, float] | None) -> tuple[float, float] | None:
    # One turn at most, anywhere in [-360, 360]: [90, 270] is the yaws a robot facing -x
    # holds as one facing +x holds [-90, 90].
    if yaw is not None and (yaw[0] < -360.0 or yaw[1] > 360.0 or yaw[1] - yaw[0] > 360.0):
        raise field_problem(
            "angles within [-360, 360] degrees spanning at most one turn (360 degrees)", yaw
        )
    return yaw


#: Every kind of obstacle sphere, in the order a trial draws between them.
OBSTACLE_KINDS = (ObstacleKind.LINE, ObstacleKind.AHEAD)


class GoalRegion(Region):
    """One move of a trial: where its goal's centre is drawn, the goal's yaw and the kinds of
    obstacle sphere the move may get."""

    yaw_deg: OptionalRange = Field(
        default=None,
        description="[low, high] of the goal's yaw about z, degrees, within [-360, 360] and "
        "one turn (e.g. [90, 270] for a robot facing -x); default: trials.goal_yaw_deg",
    )
    obstacles: tuple[ObstacleKind, ...] = Field(
        default=OBSTACLE_KINDS,
        description="kinds of sphere this move's obstacle is drawn as (line: over the "
        "straight path, under the lift; ahead: in front of the carry, along the robot's forward "
        "axis, +x for a robot facing +x); [] for none",
    )

    pitch_deg: tuple[_Finite, ...] = Field(
        default=(),
        description="pitches the goal is drawn from, one with equal chance, degrees, each -90, "
        "0 or 90: a turn about the box's y axis (the palms' axis) that sets it down on its "
        "side; default: upright",
    )

    _yaw = field_validator("yaw_deg")(_yaw_in_a_turn)

    @field_validator("pitch_deg")
    @classmethod
    def _quarter_turns(cls, pitches: tuple[float, ...]) -> tuple[float, ...]:
        if any(p not in (-90.0, 0.0, 90.0) for p in pitches):
            raise field_problem("pitches of -90, 0 or 90 degrees", pitches)
        return pitches

    @field_validator("obstacles")
    @classmethod
    def _each_kind_once(cls, kinds: tuple[ObstacleKind, ...]) -> tuple[ObstacleKind, ...]:
        if len(set(kinds)) != len(kinds):
            raise field_problem("each kind at most once", kinds)
        return kinds


def _range_at_least(low: float, strict: bool, what: str) -> Any:
    """A validator of a :data:`Range` whose low end is above ``low`` (``strict``) or at it."""

    def check(bounds: tuple[float, float]) -> tuple[float, float]:
        if bounds[0] < low or (strict and bounds[0] == low):
            raise field_problem(what, bounds)
        return bounds

    return check


#: Default range of a fixture's true offset from its file place, m (Hard mode): a little over
#: its usual 5 mm clearance, so the carry may come down on a wall's top.
FIXTURE_OFFSET_M = (0.0, 0.008)


class HardSettings(_FileModel):
    """How ``app.py trials --hard`` draws each trial's physical truth: the physics differs from
    what the robot is told by values drawn from these ranges (uniform unless said otherwise),
    from the campaign seed and the trial's index alone."""

    mass_scale: Range = Field(
        default=(0.5, 1.5), description="the object's true mass over its file mass, > 0"
    )
    friction_scale: Range = Field(
        default=(0.7, 1.3), description="the object's true friction over its file one, >= 0"
    )
    palm_friction_scale: Range = Field(
        default=(0.8, 1.2), description="the palms' true friction over their model's, >= 0"
    )
    table_dz_m: Range = Field(
        default=(-0.03, 0.03),
        description="the table top's true height less the file's, m; the object starts on it",
    )
    fixture_offset_m: Range = Field(
        default=FIXTURE_OFFSET_M,
        description="how far each fixture truly stands from its file place, m, 0 to 0.1, in "
        "a direction uniform on the table (the robot finds its walls by touch)",
    )
    pose_sigma_m: Annotated[float, Field(strict=True, allow_inf_nan=False, ge=0, le=1)] = Field(
        default=0.005,
        description="standard deviation of the sensed start position's error along x and y "
        "(normal), m, 0 to 1",
    )
    yaw_sigma_deg: Annotated[float, Field(strict=True, allow_inf_nan=False, ge=0, le=180)] = Field(
        default=2.0,
        description="standard deviation of the sensed start yaw's error (normal), degrees, "
        "0 to 180",
    )
    push_rate_hz: Annotated[float, Field(strict=True, allow_inf_nan=False, ge=0, le=10)] = Field(
        default=0.2,
        description="mean pushes per second of simulated time on each object (Poisson), 0 to 10",
    )
    push_force_n: Range = Field(
        default=(5.0, 20.0),
        description="a push's force, N, >= 0, in a direction uniform on the sphere",
    )
    push_duration_s: Range = Field(default=(0.05, 0.2), description="a push's length, s, > 0")
    torque_scale: Range = Field(
        default=(0.85, 1.15), description="each joint's applied torque over its computed, > 0"
    )
    torque_bias: Annotated[float, Field(strict=True, allow_inf_nan=False, ge=0, le=1)] = Field(
        default=0.03,
        description="each joint's torque bias is drawn within +- this fraction of its torque "
        "limit, 0 to 1",
    )
    torque_lag_s: Range = Field(
        default=(0.01, 0.03),
        description="time constant of the first-order lag on the applied torques, s, >= 0",
    )
    latency_ticks: Annotated[int, Field(strict=True, ge=0, le=100)] = Field(
        default=1,
        description="physics steps between reading the joint state and applying the torque "
        "computed from it, 0 to 100",
    )

    _positive = field_validator("mass_scale", "torque_scale", "push_duration_s")(
        _range_at_least(0.0, True, "values > 0")
    )
    _non_negative = field_validator(
        "friction_scale", "palm_friction_scale", "push_force_n", "torque_lag_s"
    )(_range_at_least(0.0, False, "values >= 0"))

    @model_serializer(mode="wrap")
    def _as_before_fixtures(self, handler: SerializerFunctionWrapHandler) -> Any:
        # A hard section that leaves the fixtures' offset at its default dumps as it did before
        # the field existed: a world's content hash names its campaigns (experiment.records).
        data = handler(self)
        if isinstance(data, dict) and self.fixture_offset_m == FIXTURE_OFFSET_M:
            data.pop("fixture_offset_m", None)
        return data

    @field_validator("fixture_offset_m")
    @classmethod
    def _within_a_decimetre(cls, offset: tuple[float, float]) -> tuple[float, float]:
        if offset[0] < 0.0 or offset[1] > 0.1:
            raise field_problem("distances within [0, 0.1] m", offset)
        return offset

    @field_validator("table_dz_m")
    @classmethod
    def _within_a_metre(cls, dz: tuple[float, float]) -> tuple[float, float]:
        if dz[0] < -1.0 or dz[1] > 1.0:
            raise field_problem("heights within [-1, 1] m", dz)
        return dz


def _fraction_of_room(bounds: tuple[float, float] | None) -> tuple[float, float] | None:
    if bounds is not None and (bounds[0] < -1.0 or bounds[1] > 1.0):
        raise field_problem("fractions within [-1, 1]", bounds)
    return bounds


class RiderTrials(_FileModel):
    """How ``app.py trials`` draws the balls loose on a tray (``objects[0]``,
    :func:`worlds.trays.riders`): where each starts on the floor, its radius and its mass.

    A start is a fraction, per axis of the tray's frame, of how far the ball's centre can go
    from the tray's centre with ``wall_gap`` m left to the walls (-1 and 1: that close to
    the -x or +x wall), so every start lies inside whatever tray the trial draws.
    """

    x: OptionalRange = Field(
        default=None,
        description="[low, high] of the ball's start along the tray's x, a fraction of its "
        "room, within [-1, 1]; default: the file's place (the same fraction of the room)",
    )
    y: OptionalRange = Field(
        default=None,
        description="[low, high] of the ball's start along the tray's y, a fraction of its "
        "room, within [-1, 1]; default: the file's place (the same fraction of the room)",
    )
    radius_scale: OptionalRange = Field(
        default=None,
        description="[low, high] of a factor the ball's radius is scaled by, > 0; "
        "default: the file's radius",
    )
    mass_kg: OptionalRange = Field(
        default=None, description="[low, high] of the ball's mass, kg, > 0; default: the file's"
    )
    wall_gap: _NonNegative = Field(
        default=0.005, description="least gap between the ball and a wall at its start, m"
    )

    _fraction = field_validator("x", "y")(_fraction_of_room)

    @field_validator("radius_scale", "mass_kg")
    @classmethod
    def _positive_or_none(cls, bounds: tuple[float, float] | None) -> tuple[float, float] | None:
        if bounds is not None and bounds[0] <= 0.0:
            raise field_problem("values > 0", bounds)
        return bounds


class TrialSettings(_FileModel):
    """How ``app.py trials`` draws the paper's experiment in this world.

    The workspace depends on the robot, so the world says where the object starts, where its
    goals lie and how the obstacle spheres are drawn. The goals are either the paper's three,
    ``centre``, ``right`` (-y) and ``left`` (+y), or any number of ``moves``, each a
    :class:`GoalRegion` (not both). The defaults suit the default two-iiwa world.
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
        description="a sphere ahead: its surface in front of the object's front face (along the "
        "robot's forward axis), m",
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
    goal_yaw_deg: Range = Field(
        default=(0.0, 0.0),
        description="[low, high] of each goal's yaw about z, degrees, within [-360, 360] and "
        "one turn (e.g. [90, 270] for a robot facing -x; a move's own yaw_deg replaces it)",
    )
    moves: tuple[GoalRegion, ...] = Field(
        default=(),
        min_length=1,
        description="each move's goal region, in order, at least 1; without it the three "
        "moves centre, right and left",
    )
    hard: HardSettings = Field(
        default_factory=HardSettings,
        description="with --hard, how each trial's physics is drawn to differ from the file",
    )
    size_scale: OptionalRange = Field(
        default=None,
        description="[low, high] of a factor each trial scales the object's box extents by "
        "(one factor per axis), > 0; a tray's height never below the least the palms need "
        "(experiment.tray_draws) or the file's; default: the file's size",
    )
    mass_kg: OptionalRange = Field(
        default=None, description="[low, high] of the object's mass, kg, > 0; default: the file's"
    )

    @field_validator("size_scale", "mass_kg")
    @classmethod
    def _positive_or_none(cls, bounds: tuple[float, float] | None) -> tuple[float, float] | None:
        if bounds is not None and bounds[0] <= 0.0:
            raise field_problem("values > 0", bounds)
        return bounds

    insertion: InsertionTrials | None = Field(
        default=None,
        description="where a trial draws a fixture (and the box it fits); default: as is",
    )
    riders: RiderTrials | None = Field(
        default=None,
        description="how a trial draws the balls loose on a tray (objects[0]); default: "
        "each where the file puts it on the tray, its own radius and mass",
    )

    @field_validator("sphere_radius")
    @classmethod
    def _radius_positive(cls, radius: tuple[float, float]) -> tuple[float, float]:
        if radius[0] <= 0.0:
            raise field_problem("radii > 0", radius)
        return radius

    _yaw = field_validator("goal_yaw_deg")(_yaw_in_a_turn)

    @model_validator(mode="after")
    def _one_form_of_goals(self) -> TrialSettings:
        named = [k for k in _PAPER_REGIONS if k in self.model_fields_set]
        if self.moves and named:
            raise field_problem(
                "either moves or the regions centre, right and left, not both",
                Shown(f"{named[0]} beside moves ({len(self.moves)})"),
                named[0],
            )
        return self

    def goal_regions(self) -> tuple[GoalRegion, ...]:
        """Each move's goal region, in order, its ``yaw_deg`` given (``goal_yaw_deg`` unless
        the move has its own): ``moves``, or the paper's centre, right and left."""
        regions = self.moves or tuple(
            GoalRegion(x=r.x, y=r.y) for r in (self.centre, self.right, self.left)
        )
        return tuple(
            r if r.yaw_deg is not None else r.model_copy(update={"yaw_deg": self.goal_yaw_deg})
            for r in regions
        )

    @model_serializer(mode="wrap")
    def _as_before(self, handler: SerializerFunctionWrapHandler) -> Any:
        # Settings without a hard section or moves dump as before those existed: a world's
        # content hash names its trial campaigns (experiment.records), and those must stay
        # its own. With moves, the unused paper regions are left out (they are defaults).
        data = handler(self)
        if isinstance(data, dict):
            if self.hard == HardSettings():
                data.pop("hard", None)
            if self.insertion is None:
                data.pop("insertion", None)
            if self.riders is None:
                data.pop("riders", None)
            for key in ("moves",) if not self.moves else _PAPER_REGIONS:
                data.pop(key, None)
            for key in ("size_scale", "mass_kg"):
                if data.get(key) is None:
                    data.pop(key, None)
            for move in data.get("moves", ()):
                if isinstance(move, dict) and not move.get("pitch_deg"):
                    move.pop("pitch_deg", None)
        return data


#: The paper's three goal regions, in the order of its moves.
_PAPER_REGIONS = ("centre", "right", "left")


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
    disturbances: tuple[DisturbanceEntry, ...] = Field(
        default=(), description="scripted pushes on objects during a run; may be empty"
    )
    tree: _Name | None = Field(
        default=None,
        description="the behaviour tree this world's task runs without --tree: an XML file "
        "relative to the world file's folder, with the shipped tree's Task, PickAndPlace and "
        "Move subtrees (one PickAndPlace per task step, one Move per move is made of it); "
        "default planner/trees/pick_and_place.xml",
    )

    fixtures: tuple[Fixture, ...] = Field(
        default=(), description="open fixtures on the table an object is inserted into"
    )

    @field_validator("tree")
    @classmethod
    def _tree_exists(cls, tree: str | None, info: ValidationInfo) -> str | None:
        if tree is None:
            return tree
        path = _resolve(tree, info)
        if not path.is_file() or path.suffix.lower() != ".xml":
            reason = "not an .xml file" if path.is_file() else "no such file"
            raise field_problem(
                "an existing behaviour tree .xml file", Shown(f"{tree!r} ({reason}: {path})")
            )
        return tree

    def tree_path(self) -> Path | None:
        """The file of :attr:`tree`, resolved, or None for the shipped tree."""
        return None if self.tree is None else self.resolve_path(self.tree)

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
            raise field_problem(
                f"{WORLD_FILE_VERSION} (the only world file version this program reads)", version
            )
        return version

    @model_validator(mode="after")
    def _names_resolve(self, info: ValidationInfo) -> World:
        issues: list[Issue] = []
        first_use: dict[str, str] = {}
        named: list[tuple[str, int, str]] = [
            ("objects", i, o.name) for i, o in enumerate(self.objects)
        ] + [("obstacles", i, o.name) for i, o in enumerate(self.obstacles)]
        for group, i, name in named:
            here = format_path((group, i))
            if name in first_use:
                issues.append(
                    Issue(
                        (group, i, "name"),
                        f"a name not already used (used by {first_use[name]})",
                        show_value(name),
                    )
                )
            else:
                first_use[name] = here
        object_names = [o.name for o in self.objects]
        obstacle_names = [o.name for o in self.obstacles]
        for s, step in enumerate(self.task):
            if step.object not in object_names:
                issues.append(
                    Issue(
                        ("task", s, "object"),
                        f"the name of an object ({_one_of(object_names)})",
                        show_value(step.object),
                    )
                )
            for m, move in enumerate(step.moves):
                for k, obstacle in enumerate(move.obstacles):
                    if obstacle not in obstacle_names:
                        issues.append(
                            Issue(
                                ("task", s, "moves", m, "obstacles", k),
                                f"the name of an obstacle ({_one_of(obstacle_names)})",
                                show_value(obstacle),
                            )
                        )
                    elif obstacle in move.obstacles[:k]:
                        issues.append(
                            Issue(
                                ("task", s, "moves", m, "obstacles", k),
                                "each obstacle named at most once per move",
                                show_value(obstacle),
                            )
                        )
        for d, disturbance in enumerate(self.disturbances):
            if disturbance.object not in object_names:
                issues.append(
                    Issue(
                        ("disturbances", d, "object"),
                        f"the name of an object ({_one_of(object_names)})",
                        show_value(disturbance.object),
                    )
                )
        issues += fixture_issues(self)
        low = self.trials.hard.table_dz_m[0]
        if self.table.size[2] + low <= 0.0:
            issues.append(
                Issue(
                    ("trials", "hard", "table_dz_m"),
                    f"a low end above -{self.table.size[2]:g} m (the table's height)",
                    show_value(self.trials.hard.table_dz_m),
                )
            )
        if issues:
            raise FieldProblems(issues)
        context = info.context if isinstance(info.context, Mapping) else {}
        source = context.get("source")
        if source is not None:
            self._source = Path(source)
        return self

    @model_serializer(mode="wrap")
    def _without_empty_disturbances(self, handler: SerializerFunctionWrapHandler) -> Any:
        # A world without disturbances dumps as it did before the section existed: its content
        # hash names its trial campaigns (experiment.records), and those must stay its own.
        data = handler(self)
        if not self.disturbances and isinstance(data, dict):
            data.pop("disturbances", None)
        if self.tree is None and isinstance(data, dict):
            data.pop("tree", None)
        if not self.fixtures and isinstance(data, dict):
            data.pop("fixtures", None)
        return data


def _one_of(names: Sequence[str]) -> str:
    if not names:
        return "there are none"
    return "one of " + ", ".join(repr(n) for n in names)

"""The world file's schema: pydantic v2 models of a dual-arm pick-and-place world.

Every model forbids unknown keys and is immutable. Validators raise
:class:`worlds.world_errors.FieldProblems`, so that a bad value reports its field path, what
was expected and what was received. The core never reads these models: it reads the
dataclasses of :mod:`worlds.spec`, made once by :func:`worlds.world_file.world_spec`.

Conventions: SI units; angles in the file are degrees (``rpy_deg``); world frame z up; the
robot faces its frame's +x with its left arm at +y (its base pose places that frame in the
world: a robot may face the table from any side). Relative paths (mesh files, skill library) are
resolved against the folder of the world file.

The checked field types and the models' base are :mod:`worlds.schema_types`; the ``trials``
section, where ``app.py trials`` draws, is :mod:`worlds.trial_schema`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import (
    Field,
    PrivateAttr,
    SerializerFunctionWrapHandler,
    StrictBool,
    ValidationInfo,
    field_validator,
    model_serializer,
    model_validator,
)

from worlds.fixture_schema import Fixture, fixture_issues
from worlds.schema_types import (
    SKILL_NAME,
    Angles3,
    FileModel,
    FiniteVector3,
    Name,
    NonNegative,
    NonNegativeInt,
    Positive,
    PositiveVector3,
    Text,
    Vector3,
)
from worlds.spec import FIXED_ARM_SEPARATION_M, Fragility, ObjectState, RobotModelName, Shape
from worlds.trial_schema import TrialSettings, trials_in_robot_frame
from worlds.world_errors import FieldProblems, Issue, Shown, field_problem, format_path, show_value

WORLD_FILE_VERSION = 1
"""The only world file format version this module reads."""

DEFAULT_SKILL_LIBRARY = "default"
"""Value of ``skills.library`` that selects the skill library shipped with the project."""

CONTEXT_BASE_DIR = "base_dir"
"""Key of the validation context that holds the folder relative paths resolve against."""


_EXCLUSIVE_STATES = ((ObjectState.OPEN, ObjectState.CLOSED), (ObjectState.FULL, ObjectState.EMPTY))


# --------------------------------------------------------------------------------------------
# Geometry
# --------------------------------------------------------------------------------------------


class PoseEntry(FileModel):
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


class BoxShape(FileModel):
    """A box centred on its pose."""

    type: Literal[Shape.BOX] = Shape.BOX
    size: PositiveVector3 = Field(description="full extents [x, y, z] in the body frame, m")


class TrayShape(FileModel):
    """A rimmed tray centred on its pose: an open box, a floor and four walls up to the top.

    The palms squeeze the outer faces of its +-y walls, as they squeeze a box's y faces.
    """

    type: Literal["tray"] = "tray"
    size: PositiveVector3 = Field(description="outer extents [x, y, height] in the body frame, m")
    floor: Positive = Field(description="floor thickness, m, > 0 and below the height")
    rim: Positive = Field(description="wall thickness, m, > 0 and below half of x and y")

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


class CylinderShape(FileModel):
    """A cylinder centred on its pose, axis along the body z axis."""

    type: Literal[Shape.CYLINDER] = Shape.CYLINDER
    radius: Positive = Field(description="radius, m, > 0")
    height: Positive = Field(description="full height along z, m, > 0")


class SphereShape(FileModel):
    """A sphere centred on its pose."""

    type: Literal[Shape.SPHERE] = Shape.SPHERE
    radius: Positive = Field(description="radius, m, > 0")


class MeshShape(FileModel):
    """A triangle mesh loaded with trimesh, in the body frame, scaled uniformly.

    ``file`` is kept as written; resolve it with :meth:`World.resolve_path`.
    """

    type: Literal[Shape.MESH] = Shape.MESH
    file: Name = Field(
        description="mesh file (obj, stl, ply, ...), relative to the world file's folder"
    )
    scale: Positive = Field(default=1.0, description="uniform scale factor, > 0")

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
    vertices = np.asarray(getattr(mesh, "vertices", ()), dtype=np.float64)
    if not np.all(np.isfinite(vertices)):
        raise field_problem(
            "a mesh of finite vertices", Shown(f"{file!r} (a vertex not a number in {path})")
        )
    extents = np.ptp(vertices, axis=0)
    flat = [axis for axis, extent in zip("xyz", extents, strict=True) if extent <= 0.0]
    if flat:  # a body without volume has no mass distribution, no faces to grasp
        raise field_problem(
            "a mesh with volume (an extent along x, y and z)",
            Shown(f"{file!r} (flat along {' and '.join(flat)}: extents {extents.tolist()})"),
        )


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


class Robot(FileModel):
    """The dual-arm robot: model, placement and hardware limits."""

    model: RobotModelName = Field(description="robot model")
    base: PoseEntry = Field(
        description="robot frame in the world: midpoint between the two arm bases, x forward"
    )
    arm_separation: Positive = Field(
        description="distance between the arm bases along the robot's y axis, m, > 0"
    )
    mount_height: NonNegative = Field(
        description="height of the arm bases above the floor, m, >= 0"
    )
    payload_kg: Positive = Field(description="payload per arm, kg, > 0")
    squeeze_force_n: Positive = Field(description="largest steady squeeze per palm, N, > 0")
    palm_size: PositiveVector3 = Field(description="flat palm box extents [x, y, z], m")

    @model_validator(mode="after")
    def _separation_the_model_has(self) -> Robot:
        # A model whose arms are fixed apart ignores the field: another value would be a
        # setting that silently does nothing (a user's iCub world of 0.5 m validated).
        fixed = FIXED_ARM_SEPARATION_M.get(self.model)
        if fixed is not None and not math.isclose(self.arm_separation, fixed, abs_tol=0.005):
            raise field_problem(
                f"{fixed} for model {self.model.value} (its arms stand that far apart; the "
                "field restates it)",
                self.arm_separation,
                "arm_separation",
            )
        return self


class Table(FileModel):
    """The table the objects stand on."""

    position: Vector3 = Field(description="centre of the table top surface, world frame, m")
    size: PositiveVector3 = Field(
        description="[length along x, width along y, height of the top above the floor], m"
    )
    friction: NonNegative = Field(description="friction coefficient of the top, >= 0")

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


class WorldObject(FileModel):
    """An object the robot can manipulate."""

    name: Name = Field(description="unique name (across objects and obstacles)")
    category: Name = Field(description="free text: parcel, box, glass, bottle, tray, ...")
    shape: ShapeModel
    mass: Positive = Field(description="mass, kg, > 0")
    friction: NonNegative = Field(description="friction coefficient, >= 0")
    material: Text = Field(default="unknown", description="free text: cardboard, glass, ...")
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


class Obstacle(FileModel):
    """A static obstacle, present only during the moves that name it."""

    name: Name = Field(description="unique name (across objects and obstacles)")
    shape: ShapeModel
    position: Vector3 = Field(description="centre of the obstacle, world frame, m")


class MoveEntry(FileModel):
    """One place goal for an object, with the obstacles present while moving there."""

    goal: PoseEntry = Field(description="goal pose of the object's centre, world frame")
    obstacles: tuple[Name, ...] = Field(
        default=(), description="names of the obstacles present during this move"
    )
    skill: Name | None = Field(
        default=None,
        description="name or label of the library's absolute skill this move is carried with "
        "(a taught skill's label); default: the plan's transport skill",
    )
    fixture: Name | None = Field(
        default=None,
        description="the fixture (fixtures[].name) this move seats the object in; the goal "
        "must then be the seated pose",
    )

    @field_validator("skill")
    @classmethod
    def _skill_is_a_name(cls, skill: str | None) -> str | None:
        if skill is not None and SKILL_NAME.fullmatch(skill) is None:
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


class TaskStep(FileModel):
    """A sequence of moves applied to one object; each move starts where the last ended."""

    object: Name = Field(description="name of the object to move")
    moves: tuple[MoveEntry, ...] = Field(min_length=1, description="consecutive goals, at least 1")


class DisturbanceEntry(FileModel):
    """A scripted push on an object: a force (and a torque) over a window of simulated time.

    Both act at the object's centre of mass, in the world frame, on every physics step whose
    start time ``t`` has ``at_s <= t < at_s + duration_s``.
    """

    at_s: NonNegative = Field(description="start of the window, simulated time, s, >= 0")
    object: Name = Field(description="name of the object pushed")
    force_n: FiniteVector3 = Field(description="force [x, y, z], world frame, N")
    duration_s: Positive = Field(description="length of the window, s, > 0")
    torque_nm: FiniteVector3 = Field(
        default=(0.0, 0.0, 0.0), description="torque [x, y, z], world frame, N m"
    )
    while_held: StrictBool = Field(
        default=False,
        description="push only if both palms hold the object when the window opens (a push "
        "during a carry); otherwise the window is skipped",
    )


class SimSettings(FileModel):
    """Simulation rates, seed and limits."""

    # The lowest rates the palms' impedance law and the leaves' force loops hold at: at 60 Hz
    # physics the grasp never reached its squeeze; at 20 Hz control the arms flailed and flung
    # the parcel off the table, at 24 Hz the release never let go (30 Hz and 120 Hz run).
    physics_hz: Annotated[int, Field(strict=True, ge=120, le=10_000)] = Field(
        default=240,
        description="physics rate, Hz, 120 to 10000 (below 120 the grasp is not held)",
    )
    control_hz: Annotated[int, Field(strict=True, ge=30, le=1000)] = Field(
        default=60,
        description="control rate, Hz, 30 to 1000, divides physics_hz (below 30 the palms' "
        "force loops are unstable)",
    )
    seed: NonNegativeInt = Field(
        default=0,
        description="seed of a run's random choices, >= 0; a run of the shipped leaves makes "
        "none (physics, skills and tree are deterministic); trials draw from their own seed",
    )
    gravity: Annotated[float, Field(strict=True, allow_inf_nan=False, le=0, ge=-1000)] = Field(
        default=-9.81,
        description="gravity along world z, m/s^2, -1000 to 0: down, or none (a positive "
        "value would fling the objects off the table)",
    )
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


class SkillSettings(FileModel):
    """Where the skill library comes from."""

    library: Name = Field(
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


#: The world file's sections that may be left out, and so left empty (null in YAML).
OPTIONAL_SECTIONS = ("obstacles", "sim", "skills", "trials", "disturbances", "fixtures")


class World(FileModel):
    """A whole world file.

    The absolute path of the file it was loaded from is :attr:`source` (None when built in
    code); it is not a field, so it is neither in the schema nor written by :func:`dump_world`.
    """

    version: Annotated[int, Field(strict=True)] = Field(
        description="world file format version, must be 1",
        json_schema_extra={"const": WORLD_FILE_VERSION},
    )
    name: Name = Field(description="world name")
    description: Text = Field(default="", description="free text")
    robot: Robot
    table: Table
    objects: tuple[WorldObject, ...] = Field(min_length=1, description="at least 1 object")
    obstacles: tuple[Obstacle, ...] = Field(default=(), description="may be empty")
    task: tuple[TaskStep, ...] = Field(min_length=1, description="at least 1 step")
    sim: SimSettings = Field(default_factory=SimSettings)
    skills: SkillSettings = Field(default_factory=SkillSettings)
    trials: TrialSettings = Field(
        default_factory=TrialSettings,
        description="where app.py trials draws each trial; default: the default world's "
        "regions placed where the robot stands and turned with it",
    )
    disturbances: tuple[DisturbanceEntry, ...] = Field(
        default=(), description="scripted pushes on objects during a run; may be empty"
    )
    tree: Name | None = Field(
        default=None,
        description="the behaviour tree this world's task runs without --tree: an XML file "
        "relative to the world file's folder, with the shipped tree's Task, PickAndPlace and "
        "Move subtrees (one PickAndPlace per task step, one Move per move is made of it); "
        "default planner/trees/pick_and_place.xml",
    )

    fixtures: tuple[Fixture, ...] = Field(
        default=(), description="open fixtures on the table an object is inserted into"
    )

    @model_validator(mode="before")
    @classmethod
    def _trials_with_the_robot(cls, data: Any) -> Any:
        # An optional section left empty (`trials:` with its lines commented out, which YAML
        # reads as null) is that section left out: its defaults.
        if isinstance(data, Mapping) and any(data.get(k, ()) is None for k in OPTIONAL_SECTIONS):
            data = {k: v for k, v in data.items() if not (k in OPTIONAL_SECTIONS and v is None)}
        # Without a trials section, the defaults (made for a robot at the origin facing +x)
        # stand where this robot stands, turned with it (trials_in_robot_frame): a world laid
        # out elsewhere draws its trials in front of its robot. A base that does not read as
        # numbers is left to the field checks.
        if not isinstance(data, Mapping) or "trials" in data:
            return data
        try:
            base = data["robot"]["base"]
            position = [float(v) for v in base["position"]]
            yaw = float(base.get("rpy_deg", (0.0, 0.0, 0.0))[2])
        except (KeyError, TypeError, ValueError, IndexError):
            return data
        if len(position) != 3 or not all(math.isfinite(v) for v in (*position, yaw)):
            return data
        placed = trials_in_robot_frame(position, yaw)
        return {**data, "trials": placed} if placed else data  # empty: the defaults' own robot

    @field_validator("tree")
    @classmethod
    def _tree_exists(cls, tree: str | None, info: ValidationInfo) -> str | None:
        if tree is None:
            return tree
        path = _resolve(tree, info)
        if not path.is_file() or path.suffix.lower() != ".xml":
            reason = (
                "not an .xml file"
                if path.is_file()
                else "a folder"
                if path.is_dir()
                else "no such file"
            )
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

"""World files: reading the YAML (or JSON) description of a dual-arm pick-and-place scene.

A world file names the robot, the table, the objects on it, the obstacles, the task (which
object goes where, with which obstacles present) and the simulation settings. This module reads
such a file, validates it against the schema (:mod:`worlds.world_schema`) and turns every
problem into a :class:`worlds.world_errors.WorldFileError` that names the file, the field path,
what was expected and what was received. :func:`world_spec` then converts the validated world,
once, into the frozen dataclasses the core reads (:mod:`worlds.spec`).

The schema's models and the error types are re-exported here: ``from worlds.world_file import
World, load_world`` is the way in for other packages.

Examples
--------
>>> world = load_world("worlds/parcel_pick_place.yaml")  # doctest: +SKIP
>>> world_spec(world).scene.objects[0].quaternion  # doctest: +SKIP
(0.0, 0.0, 0.0, 1.0)
"""

from __future__ import annotations

import json
import math
import os
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import yaml
from pydantic import ValidationError

from affordances.safe_yaml import YamlFileError, parse_yaml, read_bounded
from skills import quaternion as quat
from worlds.fixture_schema import Fixture
from worlds.schema_types import Range
from worlds.spec import (
    DisturbanceSpec,
    FixtureSpec,
    Fragility,
    MoveSpec,
    ObjectSpec,
    ObjectState,
    ObstacleKind,
    ObstacleSpec,
    Quat,
    RobotModelName,
    RobotSpec,
    SceneSpec,
    Shape,
    ShapeSpec,
    TableSpec,
    TaskStepSpec,
    WorldSpec,
)
from worlds.trial_schema import GoalRegion, HardSettings, Region, TrialSettings
from worlds.world_errors import WorldFileError, WorldFileProblem, problems_from, show_value
from worlds.world_schema import (
    CONTEXT_BASE_DIR,
    DEFAULT_SKILL_LIBRARY,
    WORLD_FILE_VERSION,
    BoxShape,
    CylinderShape,
    DisturbanceEntry,
    MeshShape,
    MoveEntry,
    Obstacle,
    PoseEntry,
    Robot,
    ShapeModel,
    SimSettings,
    SkillSettings,
    SphereShape,
    Table,
    TaskStep,
    TrayShape,
    World,
    WorldObject,
)

__all__ = [
    "DEFAULT_SKILL_LIBRARY",
    "WORLD_FILE_VERSION",
    "BoxShape",
    "CylinderShape",
    "DisturbanceEntry",
    "Fragility",
    "GoalRegion",
    "HardSettings",
    "MeshShape",
    "MoveEntry",
    "ObjectState",
    "Obstacle",
    "ObstacleKind",
    "PoseEntry",
    "Range",
    "Region",
    "Robot",
    "RobotModelName",
    "Shape",
    "ShapeModel",
    "SimSettings",
    "SkillSettings",
    "SphereShape",
    "Table",
    "TaskStep",
    "TrayShape",
    "TrialSettings",
    "World",
    "WorldFileError",
    "WorldFileProblem",
    "WorldObject",
    "as_world_spec",
    "dump_world",
    "load_world",
    "turn_free",
    "world_cli_schema",
    "world_cli_validate",
    "world_from_data",
    "world_json_schema",
    "world_spec",
    "world_summary",
]


# --------------------------------------------------------------------------------------------
# Reading files
# --------------------------------------------------------------------------------------------


def _read_text(path: Path, label: str) -> str:
    expected = "a readable UTF-8 world file"
    try:
        data = read_bounded(path)
    except YamlFileError as exc:
        raise WorldFileError(label, [WorldFileProblem(None, expected, exc.problem)]) from None
    except FileNotFoundError:
        raise WorldFileError(label, [WorldFileProblem(None, expected, "no such file")]) from None
    except PermissionError:
        problem = WorldFileProblem(None, expected, "permission denied")
        raise WorldFileError(label, [problem]) from None
    except (OSError, ValueError) as exc:
        problem = WorldFileProblem(None, expected, f"{type(exc).__name__}: {exc}")
        raise WorldFileError(label, [problem]) from None
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        received = f"byte 0x{data[exc.start]:02x} at offset {exc.start}, which is not UTF-8"
        raise WorldFileError(label, [WorldFileProblem(None, expected, received)]) from None


class _DuplicateKey(ValueError):
    """A JSON object giving one key twice (json keeps the last, silently)."""


def _unique_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise _DuplicateKey(f"the key {key[:60]!r}")
        out[key] = value
    return out


def _parse(text: str, path: Path, label: str) -> Any:
    """Parse YAML (or JSON for ``.json`` files), reporting syntax errors with line:column."""
    if path.suffix.lower() == ".json":
        try:
            return json.loads(text, object_pairs_hook=_unique_keys)
        except _DuplicateKey as exc:
            problem = WorldFileProblem(None, "each key once per object", f"{exc} twice")
            raise WorldFileError(label, [problem]) from None
        except json.JSONDecodeError as exc:
            problem = WorldFileProblem(None, "invalid JSON", exc.msg, exc.lineno, exc.colno)
            raise WorldFileError(label, [problem]) from None
        except RecursionError:
            problem = WorldFileProblem(None, "a world file", "JSON nested too deeply")
            raise WorldFileError(label, [problem]) from None
        except ValueError as exc:  # an integer of more digits than Python converts
            why = f"a number it cannot read: {exc}".split(";")[0]
            raise WorldFileError(label, [WorldFileProblem(None, "a world file", why)]) from None
    try:
        return parse_yaml(text)
    except YamlFileError as exc:
        if exc.line is not None:
            problem = WorldFileProblem(None, "invalid YAML", exc.problem, exc.line, exc.column)
        else:
            problem = WorldFileProblem(None, "a world file", exc.problem)
        raise WorldFileError(label, [problem]) from None


def world_from_data(data: Mapping[str, Any], source: Path | None) -> World:
    """Validate world data as if it were read from the file ``source`` (relative paths inside
    resolve against its folder; None: against the working directory).

    Raises
    ------
    pydantic.ValidationError
        If the data is not a valid world.
    """
    context: dict[str, Any] = {}
    if source is not None:
        context = {CONTEXT_BASE_DIR: source.parent, "source": source}
    return World.model_validate(data, context=context)


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
        received = "an empty file" if data is None else show_value(data)
        top = f"a mapping with the keys {', '.join(World.model_fields)}"
        raise WorldFileError(label, [WorldFileProblem(None, top, received)])
    try:
        return world_from_data(data, file.absolute())
    except ValidationError as exc:
        raise WorldFileError(label, problems_from(exc, World)) from None
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
# The file boundary: a validated World -> the core's dataclasses
# --------------------------------------------------------------------------------------------


def _shape_spec(shape: ShapeModel, world: World) -> ShapeSpec:
    if isinstance(shape, BoxShape):
        return ShapeSpec.box(shape.size)
    if isinstance(shape, TrayShape):
        return ShapeSpec.tray(shape.size, shape.floor, shape.rim)
    if isinstance(shape, SphereShape):
        return ShapeSpec.sphere(shape.radius)
    if isinstance(shape, CylinderShape):
        return ShapeSpec.cylinder(shape.radius, shape.height)
    return ShapeSpec.mesh(world.resolve_path(shape.file), shape.scale)


def _object_spec(obj: WorldObject, world: World) -> ObjectSpec:
    x, y, z = obj.pose.position
    return ObjectSpec(
        name=obj.name,
        shape=_shape_spec(obj.shape, world),
        mass=float(obj.mass),
        friction=float(obj.friction),
        position=(x, y, z),
        quaternion=obj.pose.quaternion_xyzw(),
        category=obj.category,
        material=obj.material,
        fragility=obj.fragility,
        state=tuple(obj.state),
        yaw=math.radians(obj.pose.rpy_deg[2]),
    )


def turn_free(obj: WorldObject) -> bool:
    """Whether a turn about world z leaves ``obj`` as it was where it starts: a sphere, or a
    cylinder standing upright. Its moves' upright goals take its start's heading
    (:func:`_symmetric`), so a grip never turns it."""
    if isinstance(obj.shape, SphereShape):
        return True
    return isinstance(obj.shape, CylinderShape) and _upright(obj.pose.quaternion_xyzw())


def _symmetric(obj: WorldObject, move: MoveEntry) -> tuple[Quat, float] | None:
    """The orientation and yaw a move's goal takes when the object's symmetry makes the one
    written the one it starts in: any goal of a sphere; an upright goal of a cylinder standing
    upright (a turn about its own axis leaves it as it was). The robot then does not turn it to
    a heading nothing can see (a cylinder's 180 degrees had taken two re-grasps), and the
    judge does not count one (:func:`planner.composition.goal_error`). None: as written."""
    start = (obj.pose.quaternion_xyzw(), math.radians(obj.pose.rpy_deg[2]))
    if isinstance(obj.shape, SphereShape):
        return start
    if isinstance(obj.shape, CylinderShape) and _upright(start[0]):
        return start if _upright(move.goal.quaternion_xyzw()) else None
    return None


def _upright(q: Quat) -> bool:
    """Whether orientation ``q`` keeps a body's z axis within a degree of world z."""
    return float(quat.tilt(q)) < math.radians(1.0)


def _move_spec(move: MoveEntry, same_as_start: tuple[Quat, float] | None = None) -> MoveSpec:
    x, y, z = move.goal.position
    turned = (move.goal.quaternion_xyzw(), math.radians(move.goal.rpy_deg[2]))
    quaternion, yaw = turned if same_as_start is None else same_as_start
    return MoveSpec(
        goal_position=(x, y, z),
        goal_quaternion=quaternion,
        goal_yaw=yaw,
        obstacles=tuple(move.obstacles),
        skill=move.skill,
        fixture=move.fixture,
    )


def _fixture_spec(fixture: Fixture, world: World) -> FixtureSpec:
    size = world.object_named(fixture.for_object).shape
    assert isinstance(size, BoxShape)  # validated: a fixture is made for a box
    x, y = fixture.position
    return FixtureSpec(
        name=fixture.name,
        position=(x, y, float(world.table.position[2])),
        yaw=math.radians(fixture.yaw_deg),
        inner=(
            size.size[0] + 2.0 * fixture.clearance,
            size.size[1] + 2.0 * fixture.clearance,
        ),
        wall_thickness=float(fixture.wall_thickness),
        wall_height=float(fixture.wall_height),
        friction=float(fixture.friction),
        for_object=fixture.for_object,
    )


def world_spec(world: World) -> WorldSpec:
    """Convert a validated world into the core's frozen dataclasses, once.

    Angles become quaternions (and the reasoner's yaw in radians); mesh and skill-library
    paths are resolved against the world file's folder (the working folder for a world built
    in code), so the result does not depend on where it is used from.

    Parameters
    ----------
    world : World
        A world from :func:`load_world` (or built in code).

    Returns
    -------
    WorldSpec
    """
    robot = world.robot
    sim = world.sim
    library = world.skills.library
    scene = SceneSpec(
        robot=RobotSpec(
            model=robot.model,
            base_position=robot.base.position,
            base_rpy_deg=robot.base.rpy_deg,
            arm_separation=float(robot.arm_separation),
            mount_height=float(robot.mount_height),
            palm_size=robot.palm_size,
            payload_kg=float(robot.payload_kg),
            squeeze_force_n=float(robot.squeeze_force_n),
        ),
        table=TableSpec(
            position=world.table.position,
            size=world.table.size,
            friction=float(world.table.friction),
        ),
        objects=tuple(_object_spec(o, world) for o in world.objects),
        obstacles=tuple(
            ObstacleSpec(o.name, _shape_spec(o.shape, world), o.position) for o in world.obstacles
        ),
        physics_hz=int(sim.physics_hz),
        control_hz=int(sim.control_hz),
        gravity=float(sim.gravity),
        seed=int(sim.seed),
        disturbances=tuple(
            DisturbanceSpec(
                d.object, d.at_s, d.duration_s, d.force_n, d.torque_nm, while_held=d.while_held
            )
            for d in world.disturbances
        ),
        fixtures=tuple(_fixture_spec(f, world) for f in world.fixtures),
    )
    return WorldSpec(
        name=world.name,
        scene=scene,
        task=tuple(
            TaskStepSpec(
                step.object,
                tuple(
                    _move_spec(m, _symmetric(world.object_named(step.object), m))
                    for m in step.moves
                ),
            )
            for step in world.task
        ),
        max_sim_time_s=float(sim.max_sim_time_s),
        skill_library=None if library == DEFAULT_SKILL_LIBRARY else world.resolve_path(library),
        source=world.source,
    )


def as_world_spec(world: World | WorldSpec) -> WorldSpec:
    """``world`` as a :class:`WorldSpec`: converted by :func:`world_spec` if it is a ``World``.

    For entry points that take either (``SimWorld(world)``, ``Scene.from_world(world)``).
    """
    return world if isinstance(world, WorldSpec) else world_spec(world)


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
    print(f"{path}: ok: {world_summary(world)}")
    return 0


def world_summary(world: World) -> str:
    """One line on what a world holds: ``world 'x', 1 object, 2 obstacles, ...``."""
    moves = sum(len(step.moves) for step in world.task)
    return (
        f"world {world.name!r}, {_count(len(world.objects), 'object')}, "
        f"{_count(len(world.obstacles), 'obstacle')}, {_count(len(world.task), 'task step')}, "
        f"{_count(moves, 'move')}"
        + (f", {_count(len(world.disturbances), 'disturbance')}" if world.disturbances else "")
    )


def world_cli_schema() -> int:
    """``app.py schema``: print the JSON Schema of world files to stdout; returns 0."""
    print(json.dumps(world_json_schema(), indent=2))
    return 0


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}{'' if n == 1 else 's'}"

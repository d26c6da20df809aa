"""World files: the default world loads, broken files explain themselves, nothing else escapes."""

from __future__ import annotations

import copy
import json
import math
import os
import re
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from worlds.world_file import (
    BoxShape,
    Fragility,
    MeshShape,
    ObjectState,
    PoseEntry,
    RobotModelName,
    Shape,
    SphereShape,
    World,
    WorldFileError,
    dump_world,
    load_world,
    world_cli_schema,
    world_cli_validate,
    world_json_schema,
)

REPO = Path(__file__).resolve().parents[2]
DEFAULT_WORLD = REPO / "worlds" / "parcel_pick_place.yaml"
BAD = REPO / "tests" / "data" / "bad_worlds"


def _error(path: Path | str) -> WorldFileError:
    with pytest.raises(WorldFileError) as info:
        load_world(path)
    return info.value


@pytest.fixture(scope="module")
def default_world() -> World:
    return load_world(DEFAULT_WORLD)


@pytest.fixture(scope="module")
def default_data() -> dict[str, Any]:
    data = yaml.safe_load(DEFAULT_WORLD.read_text(encoding="utf-8"))
    assert isinstance(data, dict)
    return data


# --------------------------------------------------------------------------------------------
# The default world
# --------------------------------------------------------------------------------------------


def test_default_world_matches_the_paper_setting(default_world: World) -> None:
    world = default_world
    assert world.version == 1
    assert world.name == "parcel_pick_place"
    assert world.source == DEFAULT_WORLD
    assert world.robot.model is RobotModelName.KUKA_IIWA
    parcel = world.object_named("parcel")
    assert isinstance(parcel.shape, BoxShape)
    assert_allclose(parcel.shape.size, (0.20, 0.30, 0.15))
    assert parcel.mass == 1.0
    assert parcel.friction == 0.8
    assert parcel.fragility is Fragility.ROBUST
    # The parcel rests on the table top.
    assert_allclose(parcel.pose.position[2], world.table.position[2] + parcel.shape.size[2] / 2)
    moves = world.task[0].moves
    assert len(moves) == 3
    assert [len(m.obstacles) for m in moves] == [0, 1, 1]
    starts = [parcel.pose.position] + [m.goal.position for m in moves[:-1]]
    for start, move in zip(starts, moves, strict=True):
        assert not np.allclose(start, move.goal.position), "a move must go somewhere"
        assert 0.5 <= move.goal.position[0] <= 0.7
        assert abs(move.goal.position[1]) <= 0.15 + 1e-9
    assert moves[1].goal.position[1] < 0 < moves[2].goal.position[1]  # right (-y), then left


def test_default_world_obstacles_sit_where_documented(default_world: World) -> None:
    world = default_world
    moves = world.task[0].moves
    on_path = world.obstacle_named(moves[1].obstacles[0])
    ahead = world.obstacle_named(moves[2].obstacles[0])
    assert isinstance(on_path.shape, SphereShape)
    start, goal = np.array(moves[0].goal.position), np.array(moves[1].goal.position)
    assert_allclose(on_path.position[:2], ((start + goal) / 2)[:2])
    # Its bottom clears the resting parcel's top (centre + 0.075) by 5 cm.
    assert isinstance(on_path.shape, SphereShape)
    assert_allclose(on_path.position[2] - on_path.shape.radius, goal[2] + 0.075 + 0.05)
    start, goal = np.array(moves[1].goal.position), np.array(moves[2].goal.position)
    # 0.14 m ahead of the carry: 4 cm in front of the parcel's front face (x + 0.10).
    assert_allclose(ahead.position[0] - (start + goal)[0] / 2, 0.14)


def test_pose_quaternion_is_scalar_last_extrinsic_xyz_in_degrees() -> None:
    half = math.sqrt(0.5)
    assert_allclose(PoseEntry(position=(0, 0, 0)).quaternion_xyzw(), (0, 0, 0, 1))
    assert_allclose(
        PoseEntry(position=(0, 0, 0), rpy_deg=(90, 0, 0)).quaternion_xyzw(), (half, 0, 0, half)
    )
    assert_allclose(
        PoseEntry(position=(0, 0, 0), rpy_deg=(0, 0, 90)).quaternion_xyzw(), (0, 0, half, half)
    )
    # Extrinsic: roll 90 then yaw 90 about the fixed axes = q_yaw * q_roll.
    q = PoseEntry(position=(0, 0, 0), rpy_deg=(90, 0, 90)).quaternion_xyzw()
    assert_allclose(q, (0.5, 0.5, 0.5, 0.5), atol=1e-12)


def test_round_trip_model_to_yaml_to_model(default_world: World, tmp_path: Path) -> None:
    copy_file = tmp_path / "copy.yaml"
    copy_file.write_text(dump_world(default_world), encoding="utf-8")
    loaded = load_world(copy_file)
    assert loaded.model_dump() == default_world.model_dump()
    for part in ("robot", "table", "objects", "obstacles", "task", "sim", "skills"):
        assert getattr(loaded, part) == getattr(default_world, part)
    assert loaded.source == copy_file


def test_world_built_in_code_has_no_source(default_data: dict[str, Any]) -> None:
    world = World.model_validate(default_data)
    assert world.source is None
    assert world.base_dir == Path.cwd()
    assert world == World.model_validate(default_data)


def test_models_are_frozen(default_world: World) -> None:
    with pytest.raises(ValueError, match="frozen"):
        default_world.objects[0].mass = 2.0


def test_json_world_loads() -> None:
    world = load_world(BAD / "loads_as_json.json")
    assert world.name == "json_world"
    assert world.objects[0].shape == BoxShape(size=(0.2, 0.3, 0.15))


def test_mesh_shape_resolves_relative_to_the_world_file(
    default_data: dict[str, Any], tmp_path: Path
) -> None:
    trimesh = pytest.importorskip("trimesh")
    (tmp_path / "meshes").mkdir()
    trimesh.creation.box(extents=(0.2, 0.3, 0.15)).export(tmp_path / "meshes" / "parcel.obj")
    (tmp_path / "skills_here").mkdir()
    data = copy.deepcopy(default_data)
    data["objects"][0]["shape"] = {"type": "mesh", "file": "meshes/parcel.obj", "scale": 2.0}
    data["skills"]["library"] = "skills_here"
    world_file = tmp_path / "mesh_world.yaml"
    world_file.write_text(yaml.safe_dump(data), encoding="utf-8")
    world = load_world(world_file)
    shape = world.objects[0].shape
    assert isinstance(shape, MeshShape)
    assert shape.type is Shape.MESH
    assert world.resolve_path(shape.file) == tmp_path / "meshes" / "parcel.obj"
    assert world.resolve_path(world.skills.library).is_dir()


def test_unloadable_mesh_is_reported(default_data: dict[str, Any], tmp_path: Path) -> None:
    (tmp_path / "junk.stl").write_bytes(b"\x00\x01 this is not a mesh")
    data = copy.deepcopy(default_data)
    data["obstacles"][0]["shape"] = {"type": "mesh", "file": "junk.stl"}
    world_file = tmp_path / "junk_mesh.yaml"
    world_file.write_text(yaml.safe_dump(data), encoding="utf-8")
    with pytest.raises(
        WorldFileError,
        match=r"junk_mesh\.yaml: obstacles\[0\]\.shape\.file: expected a mesh file that exists "
        r"and trimesh can load, got 'junk\.stl'",
    ):
        load_world(world_file)


# --------------------------------------------------------------------------------------------
# The corpus of broken files
# --------------------------------------------------------------------------------------------

# (file, field path, expected, received): each a regex fragment of the one-line message.
CASES = [
    ("missing_field.yaml", r"objects\[0\]\.mass", r"a value \(mass, kg, > 0\)", "nothing"),
    ("wrong_type.yaml", r"objects\[0\]\.mass", "a number", "'heavy'"),
    ("negative_mass.yaml", r"objects\[0\]\.mass", "a number greater than 0", r"-1\.0"),
    (
        "unknown_key.yaml",
        r"objects\[0\]\.colour",
        "only the keys name, category, .*",
        "unknown key 'colour'",
    ),
    ("missing_mesh.yaml", r"objects\[0\]\.shape\.file", "a mesh file that exists", ".*no_such"),
    (
        "unknown_obstacle.yaml",
        r"task\[0\]\.moves\[1\]\.obstacles\[0\]",
        r"the name of an obstacle \(one of 'ball'\)",
        "'bal'",
    ),
    ("unknown_task_object.yaml", r"task\[0\]\.object", "the name of an object", "'parcal'"),
    (
        "duplicate_names.yaml",
        r"obstacles\[1\]\.name",
        r"a name not already used \(used by objects\[0\]\)",
        "'parcel'",
    ),
    (
        "vector_length.yaml",
        r"objects\[0\]\.pose\.position",
        "a list of exactly 3 numbers",
        r"2 items \[0\.55, 0\.0\]",
    ),
    ("rates_not_multiple.yaml", r"sim\.physics_hz", r"a multiple of control_hz \(60\)", "250"),
    ("unknown_shape_type.yaml", r"obstacles\[0\]\.shape\.type", "a shape type, one of", "'cone'"),
    ("wrong_version.yaml", "version", r"1 \(the only world file version", "2"),
    (
        "trials_moves_and_regions.yaml",
        r"trials\.centre",
        "either moves or the regions centre, right and left, not both",
        r"centre beside moves \(2\)",
    ),
    ("trials_move_region.yaml", r"trials\.moves\[1\]\.y", "low <= high", r"\[-0\.12, -0\.18\]"),
    (
        "trials_obstacle_kind.yaml",
        r"trials\.moves\[0\]\.obstacles\[1\]",
        "one of 'line' or 'ahead'",
        "'above'",
    ),
    (
        "trials_move_yaw.yaml",
        r"trials\.moves\[0\]\.yaw_deg",
        r"angles within \[-360, 360\] degrees spanning at most one turn",
        r"\[-200\.0, 200\.0\]",
    ),
]


@pytest.mark.parametrize(("name", "field", "expected", "received"), CASES)
def test_broken_file_names_file_field_expectation_and_value(
    name: str, field: str, expected: str, received: str
) -> None:
    path = BAD / name
    pattern = f"^{re.escape(str(path))}: {field}: expected {expected}.*, got {received}"
    with pytest.raises(WorldFileError, match=pattern) as info:
        load_world(path)
    error = info.value
    assert error.file == str(path)
    assert error.field is not None and re.fullmatch(field, error.field)
    assert error.line is None
    assert "\n" not in str(error), "one defect, one line"


def test_yaml_syntax_error_reports_line_and_column() -> None:
    path = BAD / "bad_syntax.yaml"
    # The flow sequence opened on line 14 (the header comment is line 1) is never closed;
    # PyYAML notices on line 15 and says where the sequence started.
    with pytest.raises(
        WorldFileError,
        match=rf"^{re.escape(str(path))}:15:\d+: invalid YAML: expected ',' or '\]'.* "
        r"\(while parsing a flow sequence at line 14, column 9\)$",
    ) as info:
        load_world(path)
    assert info.value.line == 15
    assert info.value.field is None


def test_duplicate_yaml_key_is_an_error() -> None:
    path = BAD / "duplicate_key.yaml"
    with pytest.raises(
        WorldFileError, match=rf"^{re.escape(str(path))}:22:5: invalid YAML: .*duplicate key 'mass'"
    ):
        load_world(path)


def test_empty_file() -> None:
    path = BAD / "empty.yaml"
    with pytest.raises(
        WorldFileError,
        match=rf"^{re.escape(str(path))}: expected a mapping with the keys version, name, .*"
        r", got an empty file$",
    ):
        load_world(path)


def test_every_problem_is_listed_one_per_line(default_data: dict[str, Any], tmp_path: Path) -> None:
    data = copy.deepcopy(default_data)
    data["objects"][0]["mass"] = 0
    data["table"]["friction"] = -0.1
    data["sim"]["seed"] = "zero"
    path = tmp_path / "three.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    error = _error(path)
    lines = str(error).splitlines()
    assert lines == [
        f"{path}: table.friction: expected a number greater than or equal to 0, got -0.1",
        f"{path}: objects[0].mass: expected a number greater than 0, got 0",
        f"{path}: sim.seed: expected a whole number, got 'zero'",
    ]
    assert len(error.problems) == 3
    assert error.field == "table.friction"


@pytest.mark.parametrize(
    ("mutate", "match"),
    [
        (lambda d: d.update(version=True), r"version: expected a whole number, got True"),
        (lambda d: d["sim"].update(control_hz=60.0), r"sim\.control_hz: expected a whole number"),
        (
            lambda d: d["table"].update(size=[0.6, 1.0, ".6"]),
            r"table\.size\[2\]: expected a number",
        ),
        (lambda d: d["table"].update(position=[0.6, 0, 0.7]), r"table\.position\[2\]: .*size\[2\]"),
        (lambda d: d["robot"].update(model="ur5"), r"robot\.model: expected one of 'kuka_iiwa'"),
        (
            lambda d: d["robot"]["base"].update(rpy_deg=[0, float("nan"), 0]),
            r"robot\.base\.rpy_deg\[1\]: expected a finite number, got nan",
        ),
        (
            lambda d: d["objects"][0].update(state=["open", "closed"]),
            r"objects\[0\]\.state: expected at most one of 'open' and 'closed', got \['open'",
        ),
        (lambda d: d["objects"][0].update(shape=5), r"objects\[0\]\.shape: expected a mapping"),
        (lambda d: d.update(objects=[]), r"objects: expected a list with at least 1 item, got 0"),
        (lambda d: d.update(task="parcel"), r"task: expected a list, got 'parcel'"),
        (lambda d: d["skills"].update(library="nowhere"), r"skills\.library: expected \"default\""),
        (lambda d: d.update({3: "x"}), r"expected text keys, got key 3"),
        (lambda d: d.update(name=""), r"name: expected non-empty text"),
        (
            lambda d: d["trials"]["right"].update(y=[-0.12, -0.18]),
            r"trials\.right\.y: expected low <= high, got \[-0\.12, -0\.18\]",
        ),
        (
            lambda d: d["trials"].update(sphere_radius=[0.0, 0.05]),
            r"trials\.sphere_radius: expected radii > 0",
        ),
        (
            lambda d: d["trials"]["start"].update(x=[10**400, 1]),
            r"trials\.start\.x\[0\]: expected a finite number, got 1000",
        ),
        (
            lambda d: d["trials"].update(moves=[]),
            r"trials\.moves: expected a list with at least 1 item, got 0 items",
        ),
        (
            lambda d: d["trials"].update(
                moves=[{"x": [0.6, 0.7], "y": [0, 0.1], "obstacles": ["line", "line"]}]
            ),
            r"trials\.moves\[0\]\.obstacles: expected each kind at most once",
        ),
        (
            lambda d: d["trials"].update(line_gap=0.05),
            r"trials\.line_gap: expected a list of exactly 2 numbers \[low, high\], got 0\.05",
        ),
        (
            lambda d: d["table"].update(position=[10**400, 0, 0.6]),
            r"table\.position\[0\]: expected a finite number, got 1000",
        ),
    ],
)
def test_more_broken_values(
    default_data: dict[str, Any], tmp_path: Path, mutate: Any, match: str
) -> None:
    data = copy.deepcopy(default_data)
    mutate(data)
    path = tmp_path / "broken.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    with pytest.raises(WorldFileError, match=rf"^{re.escape(str(path))}: {match}"):
        load_world(path)


def test_object_state_values() -> None:
    assert {s.value for s in ObjectState} == {
        "open",
        "closed",
        "full",
        "empty",
        "hot",
        "contains_items",
    }


# --------------------------------------------------------------------------------------------
# Files that cannot be read
# --------------------------------------------------------------------------------------------


def test_missing_file(tmp_path: Path) -> None:
    path = tmp_path / "nope.yaml"
    with pytest.raises(WorldFileError, match=rf"^{re.escape(str(path))}: .*got no such file$"):
        load_world(path)


def test_directory(tmp_path: Path) -> None:
    with pytest.raises(WorldFileError, match=rf"^{re.escape(str(tmp_path))}: .*got a folder$"):
        load_world(tmp_path)


def test_not_utf8(tmp_path: Path) -> None:
    path = tmp_path / "latin1.yaml"
    path.write_bytes("name: café\n".encode("latin-1"))
    with pytest.raises(
        WorldFileError,
        match=rf"^{re.escape(str(path))}: expected a readable UTF-8 world file, got byte 0xe9",
    ):
        load_world(path)


@pytest.mark.skipif(hasattr(os, "geteuid") and os.geteuid() == 0, reason="root reads anything")
def test_unreadable(tmp_path: Path) -> None:
    path = tmp_path / "secret.yaml"
    path.write_text("version: 1\n", encoding="utf-8")
    path.chmod(0)
    with pytest.raises(WorldFileError, match="permission denied"):
        load_world(path)


def test_invalid_json_reports_line(tmp_path: Path) -> None:
    path = tmp_path / "w.json"
    path.write_text('{\n  "version": 1,\n  "name": }\n', encoding="utf-8")
    with pytest.raises(WorldFileError, match=rf"^{re.escape(str(path))}:3:\d+: invalid JSON: "):
        load_world(path)


# --------------------------------------------------------------------------------------------
# Command line and schema
# --------------------------------------------------------------------------------------------


def test_cli_validate_ok(capsys: pytest.CaptureFixture[str]) -> None:
    assert world_cli_validate(str(DEFAULT_WORLD)) == 0
    out, err = capsys.readouterr()
    assert "ok: world 'parcel_pick_place', 1 object, 2 obstacles, 1 task step, 3 moves" in out
    assert err == ""


@pytest.mark.parametrize(
    "name",
    ["negative_mass.yaml", "bad_syntax.yaml", "empty.yaml", "nope", "trials_move_region.yaml"],
)
def test_cli_validate_bad_file(name: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert world_cli_validate(str(BAD / name)) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err.startswith(str(BAD / name))
    assert "Traceback" not in err


def test_cli_schema(capsys: pytest.CaptureFixture[str]) -> None:
    assert world_cli_schema() == 0
    schema = json.loads(capsys.readouterr().out)
    assert schema == json.loads(json.dumps(world_json_schema()))


def test_json_schema_describes_the_file() -> None:
    schema = world_json_schema()
    assert schema["$schema"].startswith("https://json-schema.org/")
    assert schema["additionalProperties"] is False
    assert set(schema["required"]) == {"version", "name", "robot", "table", "objects", "task"}
    assert schema["properties"]["version"]["const"] == 1
    assert "_source" not in json.dumps(schema) and "source" not in schema["properties"]
    assert schema["$defs"]["WorldObject"]["properties"]["mass"]["exclusiveMinimum"] == 0


# --------------------------------------------------------------------------------------------
# Fuzzing: loading either succeeds or raises WorldFileError
# --------------------------------------------------------------------------------------------


def _paths(node: Any, prefix: tuple[str | int, ...] = ()) -> Iterator[tuple[str | int, ...]]:
    if prefix:
        yield prefix
    if isinstance(node, dict):
        for key, value in node.items():
            yield from _paths(value, (*prefix, key))
    elif isinstance(node, list):
        for i, value in enumerate(node):
            yield from _paths(value, (*prefix, i))


_DEFAULT_DATA = yaml.safe_load(DEFAULT_WORLD.read_text(encoding="utf-8"))
_FIELD_PATHS = list(_paths(_DEFAULT_DATA))

_SCALARS = (
    st.none()
    | st.booleans()
    | st.integers()
    | st.sampled_from([10**400, -(10**400), 2**63])
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=12)
    | st.sampled_from(["box", "mesh", "parcel", "ball_left", "kuka_iiwa", "default", "..", "/"])
)
_JSONISH = st.recursive(
    _SCALARS,
    lambda children: (
        st.lists(children, max_size=4) | st.dictionaries(st.text(max_size=8), children, max_size=3)
    ),
    max_leaves=8,
)


@pytest.fixture(scope="module")
def fuzz_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("fuzz")


@settings(
    max_examples=100, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    edits=st.lists(
        st.tuples(st.sampled_from(_FIELD_PATHS), st.booleans(), _JSONISH), min_size=1, max_size=3
    ),
    as_json=st.booleans(),
)
def test_fuzzed_fields_load_or_raise_world_file_error(
    fuzz_dir: Path, edits: list[tuple[tuple[str | int, ...], bool, Any]], as_json: bool
) -> None:
    data = copy.deepcopy(_DEFAULT_DATA)
    for path, delete, value in edits:
        parent: Any = data
        try:
            for key in path[:-1]:
                parent = parent[key]
            if delete:
                del parent[path[-1]]
            else:
                parent[path[-1]] = value
        except (KeyError, IndexError, TypeError):
            continue  # an earlier edit removed or replaced this path
    if as_json:
        world_file = fuzz_dir / "fuzzed.json"
        world_file.write_text(json.dumps(data), encoding="utf-8")
    else:
        world_file = fuzz_dir / "fuzzed.yaml"
        world_file.write_text(yaml.safe_dump(data, allow_unicode=True), encoding="utf-8")
    try:
        load_world(world_file)
    except WorldFileError as exc:
        assert str(exc).startswith(str(world_file))
        assert exc.expected


@settings(max_examples=100, deadline=None)
@given(text=st.text(max_size=200) | st.sampled_from(["", "---", "[", "{a: 1, a: 2}", "!!set {}"]))
def test_fuzzed_text_loads_or_raises_world_file_error(
    tmp_path_factory: pytest.TempPathFactory, text: str
) -> None:
    world_file = tmp_path_factory.getbasetemp() / "fuzzed_text.yaml"
    world_file.write_text(text, encoding="utf-8", errors="surrogatepass")
    with pytest.raises(WorldFileError):
        load_world(world_file)


def test_schema_field_names_match_the_brief(default_data: dict[str, Any]) -> None:
    # Another engineer writes the simulator against these names.
    assert list(default_data) == list(World.model_fields)
    assert list(default_data["robot"]) == [
        "model",
        "base",
        "arm_separation",
        "mount_height",
        "payload_kg",
        "squeeze_force_n",
        "palm_size",
    ]
    assert isinstance(World.model_validate(default_data).obstacles[0].shape, SphereShape)


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("physics_hz: 240", "physics_hz: 6000000", "sim.physics_hz: expected"),
        ("max_sim_time_s: 120.0", "max_sim_time_s: 1.0e+12", "sim.max_sim_time_s: expected"),
        (
            "position: [0.55, 0.0, 0.675]",
            "position: [1.0e+308, 0.0, 0.675]",
            "position[0]: expected",
        ),
    ],
)
def test_numbers_are_bounded_to_what_the_physics_can_mean(
    old: str, new: str, message: str, tmp_path: Path
) -> None:
    text = DEFAULT_WORLD.read_text(encoding="utf-8")
    assert old in text, old
    path = tmp_path / "w.yaml"
    path.write_text(text.replace(old, new, 1), encoding="utf-8")
    with pytest.raises(WorldFileError, match=re.escape(message)):
        load_world(path)


def test_an_icub_arm_separation_it_does_not_have_is_refused(tmp_path: Path) -> None:
    # The iCub's shoulders stand 0.24 m apart whatever the file says: 0.5 had validated and
    # done nothing.
    text = (REPO / "worlds" / "icub_parcel_pick_place.yaml").read_text(encoding="utf-8")
    path = tmp_path / "icub.yaml"
    path.write_text(re.sub(r"arm_separation: 0\.24", "arm_separation: 0.5", text), "utf-8")
    error = _error(path)
    assert error.field == "robot.arm_separation"
    assert str(error) == (
        f"{path}: robot.arm_separation: expected 0.24 for model icub (its arms stand that far "
        "apart; the field restates it), got 0.5"
    )
    path.write_text(re.sub(r"arm_separation: 0\.24", "arm_separation: 0.242", text), "utf-8")
    load_world(path)  # a restatement to the millimetre is fine


def test_an_optional_section_left_empty_is_left_out_a_required_one_is_not(
    default_data: dict[str, Any], tmp_path: Path
) -> None:
    # `trials:` with its lines commented out reads as null: it had been refused ("trials:
    # expected a mapping of keys to values, got None") where leaving it out is fine.
    data = copy.deepcopy(default_data)
    for section in ("trials", "obstacles", "disturbances", "fixtures", "sim", "skills"):
        data[section] = None
    data["task"][0]["moves"] = [{**m, "obstacles": []} for m in data["task"][0]["moves"]]
    path = tmp_path / "empty_sections.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    world = load_world(path)
    bare = {k: v for k, v in data.items() if v is not None}
    (tmp_path / "bare.yaml").write_text(yaml.safe_dump(bare), encoding="utf-8")
    assert world.model_dump() == load_world(tmp_path / "bare.yaml").model_dump()
    data["objects"] = None
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    assert "objects: expected a list, got None" in str(_error(path))


@pytest.mark.parametrize(
    ("sim", "match"),
    [
        # 60 Hz physics: the grasp never reached its squeeze; 20 Hz control: the arms flailed
        # and flung the parcel off the table (both had validated "ok").
        (
            {"physics_hz": 60, "control_hz": 60},
            r"sim\.physics_hz: expected a number greater "
            r"than or equal to 120, got 60",
        ),
        (
            {"control_hz": 20},
            r"sim\.control_hz: expected a number greater than or equal to 30, "
            r"got 20",
        ),
        # Up, a sign slip: the parcel had flown 89 m and the run failed as "arms touched".
        (
            {"gravity": 9.81},
            r"sim\.gravity: expected a number less than or equal to 0, got "
            r"9\.81",
        ),
    ],
)
def test_sim_settings_the_robot_cannot_run_are_refused(
    default_data: dict[str, Any],
    write_world: Callable[[dict[str, Any], str], Path],
    sim: dict[str, Any],
    match: str,
) -> None:
    data = copy.deepcopy(default_data)  # the module's, shared
    data["sim"].update(sim)
    path = write_world(data, "rates.yaml")
    with pytest.raises(WorldFileError, match=rf"^{re.escape(str(path))}: {match}"):
        load_world(path)


def test_the_grasp_is_reasoned_under_the_worlds_gravity(
    default_data: dict[str, Any], write_world: Callable[[dict[str, Any], str], Path]
) -> None:
    # The reasoner had weighed the parcel under 9.81 m/s^2 whatever the file said: at -40
    # it validated "ok" and slipped out of the palms.
    from skills.vocabulary import GraspType
    from worlds.feasibility import feasibility_problems

    data = copy.deepcopy(default_data)  # the module's, shared
    data["sim"]["gravity"] = -40.0
    lateral = {GraspType.TWO_PALM_LATERAL}  # the shipped tree's grasp
    (problem,) = feasibility_problems(load_world(write_world(data, "heavy_g.yaml")), lateral)
    assert "two_palm_lateral: needs 46.9 N per palm > 40 N available" in problem.received
    data["sim"]["gravity"] = 0.0  # weightless: nothing to hold up
    assert feasibility_problems(load_world(write_world(data, "no_g.yaml")), lateral) == []

"""The world file's ``disturbances`` section: what loads, what is refused and how it says so."""

from __future__ import annotations

import copy
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from numpy.testing import assert_allclose

import app
from worlds.spec import DisturbanceSpec
from worlds.testing import DEFAULT_WORLD
from worlds.world_file import WorldFileError, load_world, world_json_schema, world_spec

WriteWorld = Callable[[dict[str, Any], str], Path]

PUSH = {"at_s": 1.5, "object": "parcel", "force_n": [0.0, 5.0, 0.0], "duration_s": 0.2}


def test_a_world_without_disturbances_has_none_and_dumps_as_before(
    default_data: dict[str, Any], write_world: WriteWorld
) -> None:
    world = load_world(DEFAULT_WORLD)
    assert world.disturbances == ()
    assert world_spec(world).scene.disturbances == ()
    # The dump, whose hash names the world's trial campaigns, is the same with the empty
    # section written or left out, and has no such key.
    del default_data["disturbances"]
    without = load_world(write_world(default_data, "pushed.yaml"))
    assert world.model_dump(mode="json") == without.model_dump(mode="json")
    assert "disturbances" not in world.model_dump(mode="json")


def test_a_valid_entry_loads_into_the_scene_spec(
    default_data: dict[str, Any], write_world: WriteWorld
) -> None:
    default_data["disturbances"] = [PUSH, {**PUSH, "at_s": 0, "torque_nm": [0.1, 0, -0.2]}]
    world = load_world(write_world(default_data, "pushed.yaml"))
    first, second = world.disturbances
    assert first.object == "parcel"
    assert_allclose(first.force_n, (0.0, 5.0, 0.0))
    assert_allclose(first.torque_nm, (0.0, 0.0, 0.0))  # optional
    assert_allclose((second.at_s, second.duration_s), (0.0, 0.2))
    assert world_spec(world).scene.disturbances == (
        DisturbanceSpec("parcel", 1.5, 0.2, (0.0, 5.0, 0.0)),
        DisturbanceSpec("parcel", 0.0, 0.2, (0.0, 5.0, 0.0), (0.1, 0.0, -0.2)),
    )
    # Written back, it reads back the same.
    assert world.model_dump(mode="json")["disturbances"][1]["torque_nm"] == [0.1, 0.0, -0.2]


@pytest.mark.parametrize(
    ("entry", "match"),
    [
        (
            {**PUSH, "duration_s": -0.1},
            r"disturbances\[0\]\.duration_s: expected a number greater than 0, got -0\.1",
        ),
        (
            {**PUSH, "duration_s": 0},
            r"disturbances\[0\]\.duration_s: expected a number greater than 0, got 0",
        ),
        (
            {**PUSH, "at_s": -1.0},
            r"disturbances\[0\]\.at_s: expected a number greater than or equal to 0, got -1\.0",
        ),
        (
            {**PUSH, "object": "parcal"},
            r"disturbances\[0\]\.object: expected the name of an object \(one of 'parcel'\), "
            r"got 'parcal'",
        ),
        (
            {**PUSH, "object": "ball_left"},  # an obstacle: static, nothing to push
            r"disturbances\[0\]\.object: expected the name of an object \(one of 'parcel'\)",
        ),
        (
            {**PUSH, "force_n": [1.0, 0.0]},
            r"disturbances\[0\]\.force_n: expected a list of exactly 3 numbers \[x, y, z\], "
            r"got 2 items \[1\.0, 0\.0\]",
        ),
        (
            {**PUSH, "torque_nm": [0.0, 0.0, 0.0, 1.0]},
            r"disturbances\[0\]\.torque_nm: expected a list of exactly 3 numbers",
        ),
        (
            {**PUSH, "force_n": [0.0, float("inf"), 0.0]},
            r"disturbances\[0\]\.force_n\[1\]: expected a finite number, got inf",
        ),
        (
            {**PUSH, "colour": "red"},
            r"disturbances\[0\]\.colour: expected only the keys at_s, object, force_n, "
            r"duration_s, torque_nm, while_held, got unknown key 'colour'",
        ),
        (
            {k: v for k, v in PUSH.items() if k != "duration_s"},
            r"disturbances\[0\]\.duration_s: expected a value \(length of the window, s, > 0\)",
        ),
    ],
)
def test_a_bad_entry_names_its_field_and_what_was_expected(
    default_data: dict[str, Any], write_world: WriteWorld, entry: dict[str, Any], match: str
) -> None:
    default_data["disturbances"] = [copy.deepcopy(entry)]
    path = write_world(default_data, "pushed.yaml")
    with pytest.raises(WorldFileError, match=rf"^{re.escape(str(path))}: {match}") as info:
        load_world(path)
    assert "\n" not in str(info.value), "one defect, one line"


@pytest.mark.parametrize("command", ["validate", "run"])
def test_the_command_line_refuses_a_bad_entry_with_exit_2(
    default_data: dict[str, Any],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    command: str,
    write_world: WriteWorld,
) -> None:
    default_data["disturbances"] = [{**PUSH, "object": "parcal"}]
    path = write_world(default_data, "pushed.yaml")
    argv = [command, str(path)] + (["--out", str(tmp_path / "out")] if command == "run" else [])
    try:
        code = app.main(argv)
    except SystemExit as exit_info:
        code = int(exit_info.code or 0)
    assert code == app.EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert f"{path}: disturbances[0].object: expected the name of an object" in err
    assert "Traceback" not in err
    assert not (tmp_path / "out").exists()  # refused before running anything


def test_validate_counts_the_disturbances(
    default_data: dict[str, Any], write_world: WriteWorld, capsys: pytest.CaptureFixture[str]
) -> None:
    default_data["disturbances"] = [PUSH, PUSH]
    assert app.main(["validate", str(write_world(default_data, "pushed.yaml"))]) == app.EXIT_OK
    assert "3 moves, 2 disturbances" in capsys.readouterr().out


def test_the_json_schema_describes_the_section() -> None:
    schema = world_json_schema()
    assert "disturbances" in schema["properties"]
    assert "disturbances" not in schema["required"]
    entry = schema["$defs"]["DisturbanceEntry"]
    assert entry["additionalProperties"] is False
    assert set(entry["required"]) == {"at_s", "object", "force_n", "duration_s"}
    assert entry["properties"]["duration_s"]["exclusiveMinimum"] == 0
    assert entry["properties"]["at_s"]["minimum"] == 0
    assert entry["properties"]["force_n"]["minItems"] == 3

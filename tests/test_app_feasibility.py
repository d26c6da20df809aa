"""The command line refuses a task that cannot work before anything is simulated (exit 2)."""

from __future__ import annotations

from pathlib import Path

import pytest

import app
from planner.default_tree import PICK_AND_PLACE_XML
from tests.test_app import DEFAULT, ROOT, exit_code
from tests.worlds.test_feasibility import INFEASIBLE, PROBLEMS

SMALL_BOX = ROOT / "tests" / "data" / "worlds" / "small_box.yaml"


#: The line of the shipped tree's third move (the one a two-move world lacks).
MOVE_LEFT_LINE = next(
    i
    for i, line in enumerate(PICK_AND_PLACE_XML.read_text(encoding="utf-8").splitlines(), 1)
    if 'name="move_left"' in line
)


def two_move_world(tmp_path: Path) -> Path:
    """The default world without its third move."""
    text = Path(DEFAULT).read_text(encoding="utf-8")
    start = text.index("      - goal:                     # 3: left (+y)")
    end = text.index("\nsim:")
    path = tmp_path / "two_moves.yaml"
    path.write_text(text[:start] + text[end:], encoding="utf-8")
    return path


@pytest.mark.parametrize("name", sorted(PROBLEMS))
def test_validate_and_run_refuse_an_infeasible_world_at_once(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    world = str(INFEASIBLE / name)
    out = tmp_path / "out"
    for command in (
        ["validate", world],
        ["run", world, "--no-animation", "--out", str(out)],
        ["trials", world, "--n", "1", "--out", str(out)],
    ):
        assert exit_code(command) == app.EXIT_BAD_INPUT, command
        assert capsys.readouterr().err == f"{world}: {PROBLEMS[name]}\n"
    assert not out.exists()  # nothing simulated, nothing written


def test_validate_a_tree_against_a_world_with_fewer_moves(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    world = str(two_move_world(tmp_path))
    tree = str(PICK_AND_PLACE_XML)
    expected = (
        f'{tree}:{MOVE_LEFT_LINE}: <SubTree ID="Move" name="move_left">: move 2, '
        "but the world's task has 2 moves for parcel (indices 0..1)\n"
    )
    assert exit_code(["validate", world]) == app.EXIT_OK  # the default tree follows the task
    capsys.readouterr()
    assert exit_code(["validate", world, "--tree", tree]) == app.EXIT_BAD_INPUT
    assert capsys.readouterr().err == expected
    out = tmp_path / "out"
    assert exit_code(["run", world, "--tree", tree, "--out", str(out)]) == app.EXIT_BAD_INPUT
    assert capsys.readouterr().err == expected
    assert not out.exists()


def test_validate_a_world_with_its_tree(capsys: pytest.CaptureFixture[str]) -> None:
    code = exit_code(["validate", str(SMALL_BOX), "--tree", str(PICK_AND_PLACE_XML)])
    assert code == app.EXIT_OK
    assert capsys.readouterr().out == (
        f"{SMALL_BOX}: ok: world 'small_box_pick_place', 1 object, 2 obstacles, 1 task step, "
        f"3 moves; tree {PICK_AND_PLACE_XML} matches its task\n"
    )


def test_tree_option_needs_a_world(capsys: pytest.CaptureFixture[str]) -> None:
    tree = str(PICK_AND_PLACE_XML)
    assert exit_code(["validate", tree, "--tree", tree]) == app.EXIT_BAD_INPUT
    assert capsys.readouterr().err == (
        f"--tree: expected a world file to check the tree against, got the tree {tree}\n"
    )

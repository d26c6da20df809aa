"""Files in Groot2's saved form: no main_tree_to_execute, a <TreeNodesModel>, editor attributes;
validate (many files, --main-tree, --nodes) and run them."""

from __future__ import annotations

from pathlib import Path

import py_trees
import pytest
from py_trees.common import Status
from py_trees.ports import get_ports_registry

import app
from planner.default_tree import PICK_AND_PLACE_XML
from planner.loader import TreeFileError, load_tree
from planner.model_stubs import model_stub_classes
from planner.runner import run_tree
from planner.testing import FakeWorld
from skills.library import SkillLibrary

DATA = Path(__file__).resolve().parents[1] / "data" / "trees" / "groot2"
OTHER = DATA / "other_robot.xml"
WORLD = Path(__file__).resolve().parents[2] / "worlds" / "parcel_pick_place.yaml"


def groot_saved(tmp_path: Path, source: Path = PICK_AND_PLACE_XML) -> Path:
    """``source`` as Groot2 saves it: main_tree_to_execute dropped, the model kept at the end."""
    text = source.read_text(encoding="utf-8")
    assert 'main_tree_to_execute="' in text
    start = text.index(" main_tree_to_execute=")
    text = text[:start] + text[text.index('"', text.index('"', start) + 1) + 1 :]
    path = tmp_path / source.name
    path.write_text(text, encoding="utf-8")
    return path


def test_without_main_tree_to_execute_the_main_tree_is_asked_for(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    saved = groot_saved(tmp_path)
    assert app.main(["validate", str(saved)]) == app.EXIT_BAD_INPUT
    assert "--main-tree ID" in capsys.readouterr().err
    assert app.main(["validate", str(saved), "--main-tree", "Task"]) == app.EXIT_OK
    assert capsys.readouterr().out.startswith(f"{saved}: ok (main tree 'Task'")
    assert app.main(["validate", str(saved), "--main-tree", "Nope"]) == app.EXIT_BAD_INPUT
    assert "main tree 'Nope' not found" in capsys.readouterr().err
    assert app.main(["render-tree", str(saved), "--main-tree", "GraspObject"]) == app.EXIT_OK
    drawn = capsys.readouterr().out
    assert "grasp_retry" in drawn and "pick_and_place" not in drawn


def test_the_saved_form_runs_with_main_tree(
    tmp_path: Path, fake_world: FakeWorld, library: SkillLibrary
) -> None:
    saved = groot_saved(tmp_path)
    with pytest.raises(TreeFileError, match="cannot tell the main tree"):
        load_tree(saved)
    root = load_tree(saved, main_tree_id="Task")
    result = run_tree(root, fake_world, library, 1 / 60, 120.0, {"/object": "parcel"})
    assert result.status == Status.SUCCESS, result.reason


def test_a_single_tree_without_id_choice_runs(
    tmp_path: Path, fake_world: FakeWorld, library: SkillLibrary
) -> None:
    path = tmp_path / "grasp.xml"
    path.write_text(
        '<?xml version="1.0" encoding="UTF-8"?>\n<root BTCPP_format="4">\n'
        '  <BehaviorTree ID="Untitled" _description="saved by Groot2">\n'
        '    <Sequence name="pick">\n'
        '      <SelectSkills name="select" object="{object}" plan="{plan}"/>\n'
        '      <Approach name="approach" object="{object}" move="0"/>\n'
        '      <Grasp name="grasp" object="{object}" move="0" plan="{plan}" state="{state}"/>\n'
        "    </Sequence>\n"
        "  </BehaviorTree>\n  <!-- Description of Node Models (used by Groot) -->\n"
        '  <TreeNodesModel>\n    <Action ID="Grasp"/>\n  </TreeNodesModel>\n</root>\n',
        encoding="utf-8",
    )
    assert app.main(["validate", str(path)]) == app.EXIT_OK
    result = run_tree(load_tree(path), fake_world, library, 1 / 60, 60.0, {"/object": "parcel"})
    assert result.status == Status.SUCCESS, result.reason


def test_validate_many_files_one_line_each(capsys: pytest.CaptureFixture[str]) -> None:
    files = [str(WORLD), str(PICK_AND_PLACE_XML), str(OTHER)]
    assert app.main(["validate", *files]) == app.EXIT_BAD_INPUT  # OTHER's nodes are unknown
    captured = capsys.readouterr()
    assert captured.out.splitlines()[0].startswith(f"{WORLD}: ok")
    assert captured.out.splitlines()[1].startswith(f"{PICK_AND_PLACE_XML}: ok")
    assert len(captured.out.splitlines()) == 2
    problems = [line for line in captured.err.splitlines() if line.startswith(f"{OTHER}:")]
    assert problems[0].startswith(f"{OTHER}:5: <DockAt") and "unknown node type" in problems[0]
    assert problems[-1] == f"{OTHER}: 3 problems"  # DockAt, BatteryLow, Charge
    assert app.main(["validate", *files, "--nodes", str(OTHER)]) == app.EXIT_OK
    assert len(capsys.readouterr().out.splitlines()) == 3
    with pytest.raises(SystemExit):
        app.main(["validate"])  # at least one file


def test_nodes_model_types_are_checked(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    tree = tmp_path / "fast.xml"
    tree.write_text(OTHER.read_text().replace('speed="0.5"', 'speed="fast"'), encoding="utf-8")
    assert app.main(["validate", str(tree), "--nodes", str(OTHER)]) == app.EXIT_BAD_INPUT
    assert "cannot convert 'fast' to float" in capsys.readouterr().err
    assert app.main(["validate", str(OTHER), "--nodes", str(DATA / "bad_model.xml")]) == 2
    err = capsys.readouterr().err
    assert f"{DATA / 'bad_model.xml'}:4:" in err and "default: could not convert" in err
    assert f"{DATA / 'bad_model.xml'}:6:" in err and 'expected an ID="..."' in err
    assert app.main(["validate", str(OTHER), "--nodes", str(tmp_path / "none.xml")]) == 2
    assert "cannot read" in capsys.readouterr().err


def test_stubs_load_and_tick() -> None:
    py_trees.blackboard.Blackboard.clear()
    stubs = model_stub_classes(OTHER)
    assert sorted(stubs) == ["BatteryLow", "Charge", "DockAt"]
    assert stubs["DockAt"].input_ports()["speed"].default_value == pytest.approx(0.2)
    assert stubs["DockAt"].input_ports()["station"].data_type is str
    root = load_tree(OTHER, registry={**get_ports_registry(), **stubs})
    tree = py_trees.trees.BehaviourTree(root)
    tree.setup()
    tree.tick()
    # the stub condition succeeds, so the Inverter fails the sequence at its second child
    assert [n.status for n in root.children] == [Status.SUCCESS, Status.FAILURE, Status.INVALID]
    assert root.status == Status.FAILURE
    py_trees.blackboard.Blackboard.clear()


TWO_TREES = """<?xml version="1.0" encoding="UTF-8"?>
<root BTCPP_format="4">
  <BehaviorTree ID="Select">
    <SelectSkills name="select" object="{object}" plan="{plan}"/>
  </BehaviorTree>
  <BehaviorTree ID="Check">
    <IsHeld name="held" object="{object}"/>
  </BehaviorTree>
</root>
"""


@pytest.mark.sim
def test_trials_run_the_main_tree_named_and_keep_campaigns_apart(tmp_path: Path) -> None:
    import json

    from experiment.trials import campaign_of, campaign_results, run_trial
    from worlds.world_file import load_world

    tree = tmp_path / "two.xml"
    tree.write_text(TWO_TREES, encoding="utf-8")
    world = load_world(WORLD)
    payload = {"world": world.model_dump(mode="json"), "source": str(world.source),
               "tree": str(tree), "leaves": []}  # fmt: skip
    keys = {name: campaign_of(world, 0, tree, (), name) for name in ("Select", "Check")}
    select = run_trial(({**payload, "main_tree": "Select", "key": keys["Select"]}, 0, 0))
    check = run_trial(({**payload, "main_tree": "Check", "key": keys["Check"]}, 0, 0))
    assert (select["tree_status"], check["tree_status"]) == ("SUCCESS", "FAILURE")
    named = (select["settings"]["main_tree"], check["settings"]["main_tree"])
    assert named == ("Select", "Check")
    results = tmp_path / "results.jsonl"
    results.write_text(json.dumps(select) + "\n" + json.dumps(check) + "\n", encoding="utf-8")
    assert campaign_results(results, keys["Check"])[0]["tree_status"] == "FAILURE"
    # The file's own main tree: none ran.
    assert campaign_results(results, campaign_of(world, 0, tree)) == {}
    with pytest.raises(SystemExit) as stop:  # which tree? the file does not say
        app.main(["trials", str(WORLD), "--tree", str(tree), "--n", "1", "--out", str(tmp_path)])
    assert stop.value.code == app.EXIT_BAD_INPUT


def test_run_groot_without_pyzmq_or_with_a_bad_port_is_bad_input(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util, "find_spec", lambda name, *a: None if name == "zmq" else real(name, *a)
    )
    argv = ["run", str(WORLD), "--no-animation", "--out", str(tmp_path)]
    assert app.main([*argv, "--groot", "5555"]) == app.EXIT_BAD_INPUT
    assert "pip install 'duet-robot[groot]'" in capsys.readouterr().err
    monkeypatch.setattr(importlib.util, "find_spec", real)
    if real("zmq") is not None:
        assert app.main([*argv, "--groot", "65535"]) == app.EXIT_BAD_INPUT
        assert "expected a port 1..65534" in capsys.readouterr().err


def test_run_of_a_tree_whose_count_is_a_fraction_is_bad_input(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    # BT.CPP's getInput<int> refuses 0.333...; here it had been a TypeError's traceback, exit 1.
    tree = tmp_path / "fraction.xml"
    tree.write_text(
        '<root BTCPP_format="4"><BehaviorTree ID="Main"><Sequence>'
        '<Script code="t := 1 / 3"/><Sleep name="wait" msec="{t}"/>'
        "</Sequence></BehaviorTree></root>",
        encoding="utf-8",
    )
    out = tmp_path / "out"
    argv = ["run", str(WORLD), "--tree", str(tree), "--no-animation", "--out", str(out)]
    assert app.main(argv) == app.EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert "port 'msec': cannot convert 0.333" in err and "(float) to int" in err
    assert "Traceback" not in err
    assert (out / "run.jsonl").is_file()  # what was written is kept

"""A campaign's worker registers the user's leaves itself: a spawned process starts without."""

from __future__ import annotations

import multiprocessing as mp
from pathlib import Path

import pytest

from experiment.trials import run_trial
from tests.planner.test_user_leaves import LEAF, TREE
from worlds.world_file import load_world

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.sim
def test_a_spawned_worker_registers_the_leaves_it_is_sent(tmp_path: Path) -> None:
    (tmp_path / "my_leaves.py").write_text(LEAF, encoding="utf-8")
    tree = tmp_path / "tree.xml"
    tree.write_text(TREE.replace("{low}", "0.6"), encoding="utf-8")
    world = load_world(ROOT / "worlds" / "parcel_pick_place.yaml")
    payload = {
        "world": world.model_dump(mode="json"),
        "source": str(world.source),
        "tree": str(tree),
        "leaves": [str(tmp_path / "my_leaves.py")],
    }
    spawn = mp.get_context("spawn")
    with spawn.Pool(1) as pool:
        sent = pool.apply(run_trial, ((payload, 0, 0),))
    with spawn.Pool(1) as pool:  # a fresh process: nothing registered in it
        unsent = pool.apply(run_trial, (({**payload, "leaves": []}, 0, 1),))
    assert "unknown node type" not in sent["failure"]
    assert sent["tree_status"] == "SUCCESS"  # the user's leaf ran; the task itself is undone
    assert not sent["success"]
    assert "unknown node type 'HeightAtLeast': register it with --leaves" in unsent["failure"]


BUGGY = '''
from py_trees.common import Status

from planner.leaves import WorldLeaf


class Buggy(WorldLeaf):
    """Calls what the world does not have."""

    INPUT_PORTS: dict = {}

    def update(self) -> Status:
        return self.world.no_such_method()
'''


@pytest.mark.sim
def test_a_bug_in_a_users_leaf_stops_the_campaign_with_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Every trial had been filed as an "error" record and the campaign exited 1: the bug,
    # which every trial meets, was in results.jsonl only. A run stops on it with exit 2.
    import app

    (tmp_path / "bug.py").write_text(BUGGY, encoding="utf-8")
    tree = tmp_path / "tree.xml"
    tree.write_text(
        '<root BTCPP_format="4" main_tree_to_execute="T"><BehaviorTree ID="T">'
        '<Sequence name="s"><Buggy name="b"/></Sequence></BehaviorTree></root>',
        encoding="utf-8",
    )
    out = tmp_path / "out"
    argv = ["trials", str(ROOT / "worlds" / "parcel_pick_place.yaml"), "--n", "2"]
    argv += ["--workers", "1", "--tree", str(tree), "--leaves", str(tmp_path / "bug.py")]
    assert app.main([*argv, "--out", str(out)]) == app.EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert "trial 0: LeafCodeError: " in err and "bug.py:13: leaf 's.b' (Buggy)" in err
    assert "the campaign stopped: every trial would meet it" in err
    assert (out / "results.jsonl").read_text(encoding="utf-8") == ""

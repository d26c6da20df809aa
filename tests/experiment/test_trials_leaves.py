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

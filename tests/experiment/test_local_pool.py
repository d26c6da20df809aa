"""The local pool survives a worker killed mid-trial: the trial runs again, recorded once."""

from __future__ import annotations

import os
import signal
from pathlib import Path
from typing import Any

import pytest

from experiment import trials
from experiment.records import RUN_FIELDS
from experiment.results import read_results
from experiment.trials import POOL_RETRIES, run_campaign
from worlds.world_file import load_world

ROOT = Path(__file__).resolve().parents[2]
#: A tree that succeeds at its first tick: a trial is its world's set-up and judge alone.
QUICK_TREE = """<?xml version="1.0"?>
<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main"><AlwaysSuccess name="done"/></BehaviorTree>
</root>
"""

Job = tuple[dict[str, Any], int, int]


def _killed_once(job: Job) -> dict[str, Any]:
    """A fake trial: trial 1's worker is killed (SIGKILL) on its first attempt."""
    payload, _, trial = job
    marker = Path(payload["marker"])
    if trial == 1 and not marker.exists():
        marker.write_text(str(os.getpid()))
        os.kill(os.getpid(), signal.SIGKILL)
    return {"trial": trial, "pid": os.getpid()}


def _always_killed(job: Job) -> dict[str, Any]:
    os.kill(os.getpid(), signal.SIGKILL)
    return {}


def test_a_killed_worker_s_trial_runs_again_and_arrives_once(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # Forked workers run the module's run_trial as patched here.
    monkeypatch.setattr(trials, "run_trial", _killed_once)
    marker = tmp_path / "killed"
    got: list[dict[str, Any]] = []
    trials._run_on_pool([({"marker": str(marker)}, 0, t) for t in range(6)], 2, got.append)
    assert marker.exists()
    assert sorted(r["trial"] for r in got) == [0, 1, 2, 3, 4, 5]
    (again,) = [r for r in got if r["trial"] == 1]
    assert again["pid"] != int(marker.read_text())  # on a new worker


def test_a_trial_that_always_kills_its_worker_is_an_error_not_a_loop(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(trials, "run_trial", _always_killed)
    got: list[dict[str, Any]] = []
    with pytest.raises(
        RuntimeError,
        match=rf"local pool: trial 0 was running when its worker died {POOL_RETRIES + 1} times",
    ):
        trials._run_on_pool([({}, 0, 0)], 2, got.append)
    assert got == []


@pytest.mark.sim
def test_a_campaign_on_two_workers_survives_a_worker_dying_mid_trial(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    world = load_world(ROOT / "worlds" / "parcel_pick_place.yaml")
    tree = tmp_path / "quick.xml"
    tree.write_text(QUICK_TREE)
    marker = tmp_path / "died"
    monkeypatch.setenv("DUET_TEST_DIE_ONCE", f"1:{marker}")
    records = run_campaign(world, 3, 0, tmp_path / "out", workers=2, tree=tree)
    assert marker.exists()  # trial 1's worker died on its first attempt
    assert [r["trial"] for r in records] == [0, 1, 2]
    lines = read_results(tmp_path / "out" / "results.jsonl").records
    assert sorted(r["trial"] for r in lines) == [0, 1, 2]  # run again, written once
    # What the dead worker left is what the serial run records, wall-clock fields aside.
    monkeypatch.delenv("DUET_TEST_DIE_ONCE")
    serial = run_campaign(world, 3, 0, tmp_path / "serial", workers=1, tree=tree)
    wall = set(RUN_FIELDS)
    for a, b in zip(records, serial, strict=True):
        assert {k: v for k, v in a.items() if k not in wall} == {
            k: v for k, v in b.items() if k not in wall
        }

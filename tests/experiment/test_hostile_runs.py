"""Failure reasons that name their cause (issue 15, item 17)."""

from __future__ import annotations

import socket
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest
from py_trees.common import Status

from experiment.judge import judge
from experiment.layout import TrialLayoutError, check_trial_layout
from planner.runner import RunResult
from worlds.bodies import x_display_reachable
from worlds.safety_monitor import SafetyRecord
from worlds.sim_world import SimWorld
from worlds.world_file import load_world, world_from_data

DEFAULT = Path(__file__).resolve().parents[2] / "worlds" / "parcel_pick_place.yaml"


def _world(edit: Any) -> Any:
    world = load_world(DEFAULT)
    data = world.model_dump(mode="json")
    edit(data)
    return world_from_data(data, world.source)


def test_an_obstacle_spawned_inside_a_body_is_the_reason_not_what_it_caused() -> None:
    safety = SafetyRecord(dropped=True, dropped_object="parcel")
    safety.spawned_inside["ball_right"] = ["parcel"]
    sim: Any = SimpleNamespace(safety=safety)
    ok, failure = judge(
        RunResult(Status.FAILURE, 3.0, 1.0, 180, "x"), sim, ["parcel"], [None], [None]
    )
    assert (ok, failure) == (False, "obstacle spawned inside a body: ball_right inside parcel")


def test_a_drop_the_tree_recovered_from_is_recorded_not_failed() -> None:
    sim: Any = SimpleNamespace(safety=SafetyRecord(dropped=True, dropped_object="parcel"))
    done = RunResult(Status.SUCCESS, 3.0, 1.0, 180, "")
    assert judge(done, sim, ["parcel"], [0.004], [0.5]) == (True, "")
    # a drop is the reason whenever the task then went wrong, being its cause
    assert judge(done, sim, ["parcel"], [0.04], [0.5]) == (False, "dropped parcel")
    stuck = RunResult(Status.FAILURE, 3.0, 1.0, 180, "x")
    assert judge(stuck, sim, ["parcel"], [None], [None]) == (False, "dropped parcel")
    touched = SafetyRecord(dropped=True, dropped_object="parcel")
    touched.obstacle_contacts["parcel ~ ball_right"] = 3
    sim_touched: Any = SimpleNamespace(safety=touched)
    assert judge(done, sim_touched, ["parcel"], [0.004], [0.5]) == (False, "dropped parcel")


def test_a_run_stopped_at_its_time_limit_says_so_not_that_the_tree_was_invalid() -> None:
    sim: Any = SimpleNamespace(safety=SafetyRecord())
    stopped = RunResult(Status.INVALID, 120.0, 9.0, 7200, "time limit 120 s reached; task.x")
    assert judge(stopped, sim, ["parcel"], [None], [None]) == (
        False,
        "stopped: time limit 120 s reached; task.x",
    )


def test_a_negative_fcl_clearance_fails_the_run_when_nothing_spawned_inside() -> None:
    safety = SafetyRecord(min_obstacle_distance_m=-0.04, closest="left_arm/base ~ ball_right")
    sim: Any = SimpleNamespace(safety=safety)
    ok, failure = judge(RunResult(Status.SUCCESS, 3.0, 1.0, 180, ""), sim, ["parcel"], [0.0], [0.0])
    assert not ok
    assert failure == "obstacle penetration: left_arm/base ~ ball_right overlap by 40.0 mm (FCL)"


@pytest.mark.sim
def test_switching_on_an_obstacle_inside_the_parcel_is_recorded() -> None:
    def inside(data: dict[str, Any]) -> None:
        data["obstacles"][0]["position"] = list(data["objects"][0]["pose"]["position"])

    with SimWorld(_world(inside)) as sim:
        sim.set_active_obstacles(["ball_left"])
        assert sim.safety.spawned_inside == {}
        sim.set_active_obstacles(["ball_right"])
        assert sim.safety.spawned_inside == {"ball_right": ["parcel"]}


@pytest.mark.sim
def test_a_trials_layout_that_cannot_be_drawn_is_one_error() -> None:
    def far(data: dict[str, Any]) -> None:
        data["trials"]["clearance"] = 5.0

    with pytest.raises(
        TrialLayoutError,
        match=r"w\.yaml: trials: expected a layout whose "
        r"obstacles can be drawn, got none for trials 0 to 4 .*trials\.clearance \(5 m\)",
    ):
        check_trial_layout(_world(far), 0, "w.yaml")

    def ball(data: dict[str, Any]) -> None:
        data["objects"][0]["shape"] = {"type": "sphere", "radius": 0.08}

    with pytest.raises(
        TrialLayoutError,
        match=r"objects\[0\]\.shape: expected a box, tray, mesh or cylinder object "
        r"for trials .*got a sphere \('parcel'\)",
    ):
        check_trial_layout(_world(ball), 0, "w.yaml")
    check_trial_layout(load_world(DEFAULT), 0, "w.yaml")


def test_a_display_nothing_answers_at_is_not_reachable(tmp_path: Path) -> None:
    assert not x_display_reachable(":987")
    assert not x_display_reachable("nonsense")
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen(1)
        port = server.getsockname()[1]
        if port >= 6000:
            assert x_display_reachable(f"127.0.0.1:{port - 6000}")


@pytest.mark.sim
def test_a_full_disk_during_a_campaign_is_exit_2_keeping_the_trials_before(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import errno
    import os

    import app
    import experiment.trials as trials

    def quick(job: tuple[dict[str, Any], int, int]) -> dict[str, Any]:
        return {"trial": job[2], "seed": job[1], "tree": "", "success": True, "failure": ""}

    writes = {"n": 0}
    real_fsync = os.fsync

    def fsync(fd: int) -> None:
        writes["n"] += 1
        if writes["n"] > 1:
            raise OSError(errno.ENOSPC, "No space left on device")
        real_fsync(fd)

    monkeypatch.setattr(trials, "run_trial", quick)
    monkeypatch.setattr(os, "fsync", fsync)
    out = tmp_path / "campaign"
    code = app.main(["trials", str(DEFAULT), "--n", "3", "--workers", "1", "--out", str(out)])
    assert code == 2
    err = capsys.readouterr().err
    assert "results.jsonl: cannot append trial 1: No space left on device" in err
    monkeypatch.setattr(os, "fsync", real_fsync)
    lines = (out / "results.jsonl").read_text(encoding="utf-8").splitlines()
    assert '"trial": 0' in lines[0]

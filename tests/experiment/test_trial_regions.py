"""A world's trial regions checked before a campaign (experiment.trial_regions): on its table
and within the arms' reach at every corner, or refused naming the region, the corner and why."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from experiment.layout import TrialLayoutError, check_trial_layout
from experiment.trial_regions import region_problems
from worlds.world_file import load_world, world_from_data

ROOT = Path(__file__).resolve().parents[2]
DEFAULT = ROOT / "worlds" / "parcel_pick_place.yaml"
SHIPPED = sorted((ROOT / "worlds").glob("*.yaml")) + sorted(
    (ROOT / "bench" / "worlds").glob("*.yaml")
)


def _default_with(**changes: Any) -> Any:
    world = load_world(DEFAULT)
    data = world.model_dump(mode="json", exclude_unset=False)
    data.update(changes)
    return world_from_data(data, world.source)


def _turned_robot_without_trials() -> dict[str, Any]:
    """The default world turned a quarter turn about (0, 0) to face +y and moved 1 m along
    +x, its table and parcel with it, and no trials section."""
    data = load_world(DEFAULT).model_dump(mode="json")
    data.pop("trials")
    data["robot"]["base"] = {"position": [1.0, 0.0, 0.0], "rpy_deg": [0.0, 0.0, 90.0]}
    data["table"]["position"] = [1.0, 0.65, 0.6]
    data["table"]["size"] = [1.0, 0.6, 0.6]
    data["objects"][0]["pose"] = {"position": [1.0, 0.55, 0.675], "rpy_deg": [0.0, 0.0, 90.0]}
    data["obstacles"] = []
    data["task"] = [
        {
            "object": "parcel",
            "moves": [
                {"goal": {"position": [1.0, 0.65, 0.675], "rpy_deg": [0.0, 0.0, 90.0]}},
            ],
        }
    ]
    return data


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.name)
def test_every_shipped_world_has_its_regions_on_its_table_and_in_reach(path: Path) -> None:
    assert region_problems(load_world(path)) == []


def test_a_world_without_trials_draws_the_defaults_in_front_of_its_robot() -> None:
    data = _turned_robot_without_trials()
    world = world_from_data(data, DEFAULT)
    # the default regions turned a quarter turn with the robot and moved with it to (1, 0)
    assert world.trials.model_dump(
        mode="json", include={"start", "centre", "right", "left", "goal_yaw_deg"}
    ) == {
        "start": {"x": [0.96, 1.04], "y": [0.5, 0.6]},
        "centre": {"x": [0.97, 1.03], "y": [0.58, 0.68]},
        "right": {"x": [1.12, 1.18], "y": [0.55, 0.65]},
        "left": {"x": [0.82, 0.88], "y": [0.55, 0.65]},
        "goal_yaw_deg": [90.0, 90.0],
    }
    assert region_problems(world) == []
    check_trial_layout(world, 0, "w.yaml")
    # a robot at the origin facing +x keeps the defaults as they are
    data = load_world(DEFAULT).model_dump(mode="json")
    data.pop("trials")
    assert world_from_data(data, DEFAULT).trials == load_world(DEFAULT).trials.model_copy(
        update={"goal_yaw_deg": (0.0, 0.0)}
    )


def test_the_defaults_on_a_table_laid_out_elsewhere_are_refused_naming_each_region() -> None:
    data = _turned_robot_without_trials()
    # the table 25 cm further from the robot than the default world's
    data["table"]["position"] = [1.0, 0.9, 0.6]
    data["objects"][0]["pose"]["position"] = [1.0, 0.8, 0.675]
    data["task"][0]["moves"][0]["goal"]["position"] = [1.0, 0.9, 0.675]
    world = world_from_data(data, DEFAULT)
    problems = region_problems(world)
    fields = [p.split(":")[0] for p in problems]
    assert fields == ["trials.start", "trials.centre", "trials.right", "trials.left", "trials"]
    # the table top spans y 0.6..1.2: the start region (y 0.50-0.60) lies off its near edge
    assert problems[0] == (
        "trials.start: expected a region where parcel stands over the table and within the "
        "arms' reach at every corner, got the corner [0.96, 0.5] at yaw 90 deg: "
        "[0.96, 0.5, 0.675]: 0.1 m beyond the table's edge at y = 0.6 m"
    )
    assert "the defaults apply, placed where its robot stands" in problems[-1]
    with pytest.raises(TrialLayoutError) as err:
        check_trial_layout(world, 0, "w.yaml")
    assert str(err.value).splitlines()[0] == "w.yaml: " + problems[0]
    # the same regions written for this table pass, and the hint goes with the defaults
    data["trials"] = {
        "start": {"x": [0.96, 1.04], "y": [0.75, 0.85]},
        "centre": {"x": [0.97, 1.03], "y": [0.83, 0.93]},
        "right": {"x": [1.12, 1.18], "y": [0.8, 0.9]},
        "left": {"x": [0.82, 0.88], "y": [0.8, 0.9]},
        "goal_yaw_deg": [90.0, 90.0],
    }
    assert region_problems(world_from_data(data, DEFAULT)) == []


def test_a_region_out_of_reach_at_one_corner_is_refused_with_that_corner() -> None:
    # the left goal region stretched 0.3 m further from the robot: its far corners stay on
    # the table (x up to 0.95) but a palm there is beyond the iiwa's reach sphere
    trials = load_world(DEFAULT).trials.model_dump(mode="json")
    trials["left"] = {"x": [0.55, 0.94], "y": [0.12, 0.45]}
    problems = region_problems(_default_with(trials=trials))
    assert len(problems) == 1
    assert problems[0].startswith("trials.left: expected a region where parcel stands over ")
    assert "got the corner [0.94, 0.12] at yaw -90 deg" in problems[0]
    assert "the arm reaches at most" in problems[0]


def test_app_trials_refuses_such_a_world_with_exit_code_2(tmp_path: Path) -> None:
    import yaml

    data = _turned_robot_without_trials()
    data["table"]["position"] = [1.0, 0.9, 0.6]
    data["objects"][0]["pose"]["position"] = [1.0, 0.8, 0.675]
    data["task"][0]["moves"][0]["goal"]["position"] = [1.0, 0.9, 0.675]
    path = tmp_path / "turned.yaml"
    path.write_text(yaml.safe_dump(data))
    out = tmp_path / "out"
    run = subprocess.run(
        [sys.executable, str(ROOT / "app.py"), "trials", str(path), "--n", "2", "--out", str(out)],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=300,
    )
    assert run.returncode == 2, run.stderr
    lines = [line for line in run.stderr.splitlines() if line.startswith(str(path))]
    assert [line.split(": ")[1] for line in lines] == [
        "trials.start",
        "trials.centre",
        "trials.right",
        "trials.left",
        "trials",
    ]
    assert not (out / "results.jsonl").exists()


def test_a_size_scale_beyond_any_world_is_refused_naming_the_field() -> None:
    # A draw no world file may hold had raised pydantic's ValidationError out of the
    # campaign's preflight, a traceback.
    base = load_world(Path(__file__).resolve().parents[2] / "worlds" / "parcel_pick_place.yaml")
    data = base.model_dump(mode="json")
    data["trials"]["size_scale"] = [1e6, 1e6]
    world = world_from_data(data, base.source)
    with pytest.raises(
        TrialLayoutError,
        match=r"w.yaml: trials: expected size_scale and mass_kg ranges whose draws a world file "
        r"may hold, got trial 0's drawn world: objects\[0\].shape.size\[0\]: expected a number "
        r"less than or equal to 100",
    ):
        check_trial_layout(world, 0, "w.yaml")


def test_a_layout_is_refused_only_when_none_of_its_first_trials_draws(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # Trial 0 alone had decided it: a 14 cm cylinder's campaign that draws 7 trials of 12 was
    # refused whole when its trial 0 was one of the 5 that did not.
    import experiment.layout as layout

    base = load_world(Path(__file__).resolve().parents[2] / "worlds" / "parcel_pick_place.yaml")
    tried: list[int] = []

    def draw(world: Any, seed: int, trial: int, robot: Any = None) -> Any:
        tried.append(trial)
        if trial < drawable_from:
            raise RuntimeError(f"no room for trial {trial}'s sphere")
        return world, []

    monkeypatch.setattr(layout, "draw_trial", draw)
    drawable_from = 2
    check_trial_layout(base, 0, "w.yaml")
    assert tried == [0, 1, 2]
    tried.clear()
    drawable_from = layout.PREFLIGHT_TRIALS
    with pytest.raises(TrialLayoutError, match=r"got none for trials 0 to 4 \(trial 0: no room"):
        check_trial_layout(base, 0, "w.yaml")
    assert tried == [0, 1, 2, 3, 4]

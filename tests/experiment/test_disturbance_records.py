"""A run's summary lists the world's disturbances and the physics steps each acted on; a world
without any reads, and is keyed, as before."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
import yaml

import app
from experiment.episode import EpisodeReport
from experiment.trials import campaign_of
from worlds.testing import DEFAULT_WORLD
from worlds.world_file import load_world


def _report(disturbances: list[dict[str, Any]]) -> EpisodeReport:
    return EpisodeReport(
        True, "SUCCESS", "", [0.001], [0.1], 0.03, {}, 0, False, 2.0, 1.0,
        disturbances=disturbances,
    )  # fmt: skip


def _entry(steps: int) -> dict[str, Any]:
    return {"object": "parcel", "steps": steps, "first_step": 24 if steps else None}


def test_the_summary_counts_the_disturbances_that_acted() -> None:
    entries = [_entry(12), _entry(0)]
    assert _report(entries).summary()["disturbances"] == {"applied": 1, "entries": entries}


def test_a_world_without_disturbances_keeps_its_summary_and_campaign(tmp_path: Path) -> None:
    assert "disturbances" not in _report([]).summary()
    data = yaml.safe_load(DEFAULT_WORLD.read_text(encoding="utf-8"))
    assert data["disturbances"] == []
    del data["disturbances"]
    without = tmp_path / "without.yaml"
    without.write_text(yaml.safe_dump(data), encoding="utf-8")
    assert campaign_of(load_world(DEFAULT_WORLD), 0, None) == campaign_of(
        load_world(without), 0, None
    )


@pytest.mark.sim
def test_run_json_lists_each_disturbance_and_its_steps(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # A short run (1 s, ending in a timeout): the light push at 0.1 s acts on its 12 steps
    # (0.05 s at 240 Hz, from step 24), the one at 5 s on none.
    data = yaml.safe_load(DEFAULT_WORLD.read_text(encoding="utf-8"))
    data["sim"]["max_sim_time_s"] = 1.0
    data["disturbances"] = [
        {"at_s": 0.1, "object": "parcel", "force_n": [0.0, 1.0, 0.0], "duration_s": 0.05},
        {"at_s": 5.0, "object": "parcel", "force_n": [0.0, 1.0, 0.0], "duration_s": 0.05},
    ]
    world = tmp_path / "pushed.yaml"
    world.write_text(yaml.safe_dump(data), encoding="utf-8")
    argv = ["run", str(world), "--json", "--no-animation", "--out", str(tmp_path / "out")]
    assert app.main(argv) == app.EXIT_FAILURE
    out = capsys.readouterr().out
    summary = json.loads(out.strip().splitlines()[-1])
    pushes = summary["disturbances"]
    assert pushes["applied"] == 1
    steps = [(e["first_step"], e["last_step"], e["steps"]) for e in pushes["entries"]]
    assert steps == [(24, 35, 12), (None, None, 0)]
    assert pushes["entries"][0]["force_n"] == [0.0, 1.0, 0.0]
    assert "disturbances applied: 1 of 2" in out
    assert "parcel at 0.1 s: physics steps 24 to 35" in out
    assert "1 more set for after the run ended" in out and "at 5 s" not in out


def test_a_push_skipped_for_an_object_not_held_says_so() -> None:
    # It had said "no physics step (none of the run started inside its window)" of a push at
    # 1.1 s of a 25.8 s run, skipped because the parcel was not held then.
    from experiment.episode import EpisodeReport

    def entry(at_s: float, **more: object) -> dict[str, object]:
        return {"object": "parcel", "at_s": at_s, "steps": 0, "first_step": None,
                "last_step": None, **more}  # fmt: skip

    report = EpisodeReport(
        True, "SUCCESS", "", [0.001], [0.1], 0.05, {}, 0, False, 25.8, 2.0,
        placement_objects=["parcel"],
        disturbances=[entry(1.1, while_held=True, skipped=True), entry(30.0), entry(31.0)],
    )  # fmt: skip
    lines = report.lines("w")
    assert (
        "    parcel at 1.1 s: skipped: the object was not carried (held by both palms, off its "
        "support) when its window opened"
    ) in lines
    assert "    2 more set for after the run ended" in lines

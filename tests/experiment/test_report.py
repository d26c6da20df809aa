"""``app.py report``: old and new records, campaigns sharing a file, bad input."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from experiment.records import outcome
from experiment.results import read_results

ROOT = Path(__file__).resolve().parents[2]


def app(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, str(ROOT / "app.py"), *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )


def test_report_reads_old_records_and_draws_them(tmp_path: Path) -> None:
    old = tmp_path / "results.jsonl"
    # the oldest record kept, from before records named their world (rerun records change)
    shutil.copy(ROOT / "bench" / "results" / "trials_seed0_n100.jsonl", old)
    with open(old, "a", encoding="utf-8") as fh:
        fh.write("not a record\n")
    done = app("report", str(tmp_path), "--json")
    assert done.returncode == 0, done.stderr
    assert "skipped 1 line(s) that are not trial records" in done.stderr
    assert "100 of 100 (Wilson 95 %: 96.3-100.0 %)" in done.stdout
    summary = json.loads(done.stdout.splitlines()[-1])
    (campaign,) = summary["campaigns"]
    assert campaign["success_interval_95"] == pytest.approx([0.963, 1.0], abs=1e-4)
    assert summary["skipped_lines"] == 1
    assert (tmp_path / "report.png").stat().st_size > 10_000


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (None, "no such campaign folder or results file"),
        ("", "expected trial records"),
        (
            "{\n[1, 2]\n",
            r"found none; skipped 2 line\(s\) that are not trial records \(line 1: not JSON; "
            r"line 2: expected a JSON object, got list\)",
        ),
    ],
)
def test_report_refuses_what_holds_no_campaign(
    tmp_path: Path, content: str | None, message: str
) -> None:
    target = tmp_path / "results.jsonl"
    if content is not None:
        target.write_text(content, encoding="utf-8")
    done = app("report", str(target if content is None else tmp_path))
    assert done.returncode == 2
    assert "Traceback" not in done.stderr
    assert re.search(message, done.stderr), done.stderr


@pytest.mark.sim
def test_two_worlds_in_one_folder_never_take_each_others_records(tmp_path: Path) -> None:
    worlds = ["parcel_pick_place.yaml", "icub_parcel_pick_place.yaml"]
    runs = [
        app(
            "trials",
            str(ROOT / "worlds" / w),
            "--n",
            "1",
            "--workers",
            "1",
            "--out",
            str(tmp_path),
            "--json",
        )
        for w in worlds
    ]
    for done in runs:
        assert done.returncode in (0, 1), done.stderr
        assert json.loads(done.stdout.splitlines()[-1])["trials"] == 1
    records = read_results(tmp_path / "results.jsonl").records
    assert [r["world"] for r in records] == ["parcel_pick_place", "icub_parcel_pick_place"]
    assert records[0]["world_sha256"] != records[1]["world_sha256"]
    assert all(r["backend"] == "local" and r["host"] and len(r["goals"]) == 3 for r in records)
    # The iCub's campaign ran its own trial 0, not the iiwa's: different starts.
    assert records[0]["start"] != records[1]["start"]
    # The same command again owns its record and runs nothing.
    again = app("trials", str(ROOT / "worlds" / worlds[1]), "--n", "1", "--out", str(tmp_path))
    assert again.returncode in (0, 1)
    assert len(read_results(tmp_path / "results.jsonl").records) == 2
    report = app("report", str(tmp_path), "--json")
    assert report.returncode == 0, report.stderr
    labels = [c["campaign"] for c in json.loads(report.stdout.splitlines()[-1])["campaigns"]]
    assert [label.split(",")[0] for label in labels] == [
        "parcel_pick_place",
        "icub_parcel_pick_place",
    ]
    assert outcome(records[0]).keys() >= {"trial", "world", "success"}


def test_failures_a_fraction_of_a_millimetre_apart_still_show_in_the_histogram(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import to_rgb

    from experiment.report import Campaign, report_figure

    records: list[dict[str, Any]] = [
        {"success": True, "failure": "", "min_obstacle_distance_m": d / 1000.0}
        for d in range(1, 81)
    ]
    records += [
        {
            "success": False,
            "failure": "obstacle contact: parcel ~ ball_1",
            "min_obstacle_distance_m": -d / 10000.0,
        }
        for d in (4, 5)
    ]
    figures: list[Any] = []
    monkeypatch.setattr(plt, "close", figures.append)
    report_figure(Campaign("test", records), tmp_path / "report.png")
    near = figures[0].axes[2]
    red = [p for p in near.patches if p.get_facecolor()[:3] == to_rgb("red")]
    assert sum(p.get_height() for p in red) == 2
    # As wide as a bin of the whole range (30 bins over -0.5..80 mm), not of the failures'.
    assert max(p.get_width() for p in red) > 80.0 / 40


def test_two_campaigns_in_one_folder_are_two_pictures(tmp_path: Path) -> None:
    # The text had told them apart and report.png had drawn both worlds' trials as one.
    records = [
        json.loads(line) for line in (ROOT / "bench" / "results" / "trials_seed0_n100.jsonl").open()
    ][:6]
    other = [dict(r, world="another_world", world_sha256="0" * 64) for r in records[:3]]
    with open(tmp_path / "results.jsonl", "w", encoding="utf-8") as fh:
        for r in records + other:
            fh.write(json.dumps(r) + "\n")
    done = app("report", str(tmp_path))
    assert done.returncode == 0, done.stderr
    pictures = [
        line.split("picture: ")[1] for line in done.stdout.splitlines() if "picture: " in line
    ]
    assert pictures == [str(tmp_path / "report_1.png"), str(tmp_path / "report_2.png")]
    assert not (tmp_path / "report.png").exists()
    assert all(Path(p).stat().st_size > 10_000 for p in pictures)


def _shipped_records(n: int) -> list[dict[str, Any]]:
    with (ROOT / "bench" / "results" / "trials_seed0_n1000.jsonl").open() as fh:
        return [json.loads(next(fh)) for _ in range(n)]


@pytest.mark.parametrize(
    ("field", "value", "expected"),
    [
        ("failure", 5, "expected a string, got 5"),
        ("start", [0.5], "expected a list of at least 2 numbers, got [0.5]"),
        ("min_obstacle_distance_m", "n/a", 'expected a number or null, got "n/a"'),
        ("sim_time_s", "20 s", 'expected a number or null, got "20 s"'),
        ("compositions", [[1, 2]], "expected a list of mappings of names to numbers"),
        ("compositions", [{"transport_weight": "a"}], "expected a list of mappings of names"),
    ],
)
def test_a_record_with_a_field_of_the_wrong_type_is_skipped_saying_which(
    tmp_path: Path, field: str, value: object, expected: str
) -> None:
    # Each had been a traceback out of the summary or the picture, exit 1, in `report` and in
    # `trials` after all of a campaign's trials had run.
    from experiment.report import read_campaigns, report_figure, report_summaries

    records = _shipped_records(3)
    records[1][field] = value
    path = tmp_path / "results.jsonl"
    path.write_text("".join(json.dumps(r) + "\n" for r in records), encoding="utf-8")
    found = read_campaigns(tmp_path)
    assert found.skipped == 1
    assert found.skipped_text.startswith(
        f"skipped 1 line(s) that are not trial records (line 2: field '{field}': {expected}"
    )
    (campaign,) = found.campaigns
    assert [r["trial"] for r in campaign.records] == sorted(r["trial"] for r in records[::2])
    assert report_summaries(found.campaigns)[0]["trials"] == 2
    report_figure(campaign, tmp_path / "report.png")


def test_campaigns_of_one_label_are_told_apart_by_their_hashes_and_settings(
    tmp_path: Path,
) -> None:
    # A world copied under its name and edited: three campaigns had been printed, pictured
    # and given in --json as "parcel_pick_place, default tree, seed 0", all alike.
    from experiment.report import read_campaigns, report_summaries

    records = _shipped_records(2)
    edited = [dict(r, world_sha256="ab" * 32) for r in records]
    hard = [dict(r, world_sha256="cd" * 32, settings={"size_scale": [0.9, 1.1]}) for r in records]
    path = tmp_path / "results.jsonl"
    path.write_text(
        "".join(json.dumps(r) + "\n" for r in records + edited + hard), encoding="utf-8"
    )
    found = read_campaigns(tmp_path)
    labels = [c.label for c in found.campaigns]
    shipped = records[0]["world_sha256"][:8]
    assert labels == [
        f"parcel_pick_place, default tree, seed 0 (world {shipped})",
        "parcel_pick_place, default tree, seed 0 (world abababab)",
        'parcel_pick_place, default tree, seed 0 (world cdcdcdcd, {"size_scale":[0.9,1.1]})',
    ]
    keys = [s["key"] for s in report_summaries(found.campaigns)]
    assert [k["world_sha256"] for k in keys] == [
        records[0]["world_sha256"],
        "ab" * 32,
        "cd" * 32,
    ]


def test_a_failed_trial_marks_the_goal_it_failed_at_not_the_ones_it_never_tried() -> None:
    # Every goal of a failed trial had been drawn as a failed goal, those it never reached too.
    from experiment.report import _failed_goal

    goals = [[0.5, 0.0, 0.7], [0.6, -0.1, 0.7], [0.6, 0.1, 0.7]]
    stopped = {"goals": goals, "placement_error_m": [0.001, None, None]}
    assert _failed_goal(stopped) == ([goals[1]], [goals[0], goals[2]])
    knocked = {"goals": goals, "placement_error_m": [0.001, 0.002, 0.003]}
    assert _failed_goal(knocked) == ([goals[2]], goals[:2])
    assert _failed_goal({"goals": goals}) == (goals, [])  # an old record: it does not say


def test_a_trial_recorded_twice_differently_is_named_not_silently_replaced(
    tmp_path: Path,
) -> None:
    from experiment.report import read_campaigns

    lines = (ROOT / "bench" / "results" / "trials_seed0_n100.jsonl").read_text().splitlines()
    records = [json.loads(line) for line in lines[:3]]
    same = dict(records[0], wall_time_s=99.0)  # where and how fast it ran: the same trial
    other = dict(records[1], success=False, failure="dropped parcel")
    text = "\n".join(json.dumps(r) for r in [*records, same, other]) + "\n"
    (tmp_path / "results.jsonl").write_text(text, encoding="utf-8")
    found = read_campaigns(tmp_path)
    assert [c.split(": ")[-1] for c in found.conflicts] == ["trial 1"]
    (campaign,) = found.campaigns
    assert [r["success"] for r in campaign.records] == [True, False, True]  # the last counts
    done = app("report", str(tmp_path))
    assert done.returncode == 0, done.stderr
    assert "trial 1 is recorded more than once, and the records disagree" in done.stderr


def test_report_prints_a_campaign_as_trials_does(tmp_path: Path) -> None:
    # It had left out the compositions the moves were placed with, and the simulated time.
    with open(tmp_path / "results.jsonl", "w", encoding="utf-8") as fh:
        for record in _shipped_records(6):
            fh.write(json.dumps(record) + "\n")
    done = app("report", str(tmp_path))
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert any(line.startswith("  moves placed with") for line in lines)
    assert any(line.startswith("  pick-and-place x") for line in lines)
    assert any(line.startswith("  simulated ") and "worker time" in line for line in lines)

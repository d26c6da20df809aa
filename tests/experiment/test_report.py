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
        ("{\n[1, 2]\n", r"found none \(2 line\(s\) were not records\)"),
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

"""Campaign summaries: Wilson intervals, splits by condition, progress off and on a terminal."""

from __future__ import annotations

import io

import pytest
from numpy.testing import assert_allclose

from experiment.progress import Progress
from experiment.summary import (
    conditions,
    contact_lines,
    split_line,
    summarise,
    summary_lines,
    undrawn_kinds,
    wilson_interval,
)


def test_wilson_interval_matches_the_issue_and_the_paper() -> None:
    # The issue's lower bounds for zero failures, and the paper's 16 of 20 (58-92 %).
    assert_allclose(wilson_interval(100, 100)[0], 0.963, atol=5e-4)
    assert_allclose(wilson_interval(300, 300)[0], 0.987, atol=5e-4)
    assert_allclose(wilson_interval(1000, 1000)[0], 0.996, atol=5e-4)
    assert_allclose(wilson_interval(16, 20), (0.584, 0.919), atol=5e-4)
    assert_allclose(wilson_interval(0, 10), (0.0, 0.2775), atol=5e-4)
    with pytest.raises(ValueError, match="expected 0 <= successes <= trials"):
        wilson_interval(3, 2)
    with pytest.raises(ValueError, match="trials >= 1"):
        wilson_interval(0, 0)


def test_the_summary_splits_outcomes_by_obstacle_kind() -> None:
    records = [
        {"trial": 0, "seed": 0, "success": True, "obstacles": ["line", "none", "ahead"]},
        {
            "trial": 1,
            "seed": 0,
            "success": False,
            "obstacles": ["ahead", "line", "none"],
            "failure": "obstacle contact: parcel ~ ball_1",
        },
        {"trial": 2, "seed": 0, "success": True, "obstacles": ["line", "line", "line"]},
        {
            "trial": 3,
            "seed": 0,
            "success": True,
            "obstacles": ["line", "line", "line"],
            "mode": "hard",
        },
        {"trial": 4, "seed": 0, "success": True},  # an old record says nothing of them
    ]
    assert conditions(records[0]) == {"obstacles": "1 ahead + 1 line"}
    assert conditions(records[4]) == {}
    s = summarise(records)
    assert s["successes"] == 4 and s["trials"] == 5
    assert_allclose(s["success_interval_95"], wilson_interval(4, 5), atol=1e-4)
    split = s["by_condition"]["obstacles"]
    assert split["1 ahead + 1 line"]["trials"] == 2 and split["1 ahead + 1 line"]["successes"] == 1
    assert split["3 line"]["successes"] == 2
    assert_allclose(split["3 line"]["success_interval_95"], wilson_interval(2, 2), atol=1e-4)
    assert s["by_condition"]["mode"] == {
        "hard": {"trials": 1, "successes": 1, "success_interval_95": [0.2065, 1.0]}
    }
    text = "\n".join(summary_lines(s))
    assert "4 of 5 (Wilson 95 %: 37.6-96.4 %)" in text  # 37.55 %, from the counts
    assert "obstacle contact: parcel" in text and "1 of 2" in text


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_updates_in_place_only_on_a_terminal() -> None:
    log = io.StringIO()
    bar = Progress(log, step_percent=10.0)
    for done in range(1, 101):
        bar.update(done, 100, f"trial {done}")
    bar.close()
    lines = log.getvalue().splitlines()
    assert "\r" not in log.getvalue()
    assert (
        len(lines) == 10 and lines[0].startswith("10/100 (10 %)") and lines[-1].startswith("100/")
    )
    tty = Terminal()
    bar = Progress(tty)
    for done in range(1, 4):
        bar.update(done, 3, "ok")
    bar.close()
    assert tty.getvalue().count("\r") == 3 and tty.getvalue().endswith("\n")
    assert "[" + "#" * 30 + "] 3/3" in tty.getvalue()
    with pytest.raises(ValueError, match="step_percent"):
        Progress(log, step_percent=0.0)


def test_grip_metrics_summarise_as_median_and_worst_and_old_records_count_as_missing() -> None:
    grip = {"slip_mm": 1.0, "peak_tilt_deg": 0.5, "contact_count": 1, "regrasp_count": 0}
    records = [
        {"trial": 0, "success": True, **grip},
        {"trial": 1, "success": True, **grip, "slip_mm": 3.0, "peak_tilt_deg": None},
        {"trial": 2, "success": False, **grip, "slip_mm": 8.0, "contact_count": 3},
        {"trial": 3, "success": True},  # an older campaign's record: no metrics at all
        {"trial": 4, "success": False, "failure": "error: crashed", "slip_mm": "n/a"},
    ]
    metrics = summarise(records)["metrics"]
    assert metrics["slip_mm"] == {"median": 3.0, "max": 8.0, "trials": 3}
    assert metrics["peak_tilt_deg"] == {"median": 0.5, "max": 0.5, "trials": 2}
    assert metrics["contact_count"] == {"median": 1.0, "max": 3.0, "trials": 3}
    assert metrics["peak_jerk_mps3"] == {"median": None, "max": None, "trials": 0}
    text = "\n".join(summary_lines(summarise(records)))
    assert "median" in text and "worst" in text
    slip = next(line for line in text.splitlines() if "slip in the grip, mm" in line)
    assert slip.split()[-4:] == ["3", "8", "(3", "trials)"]
    assert "peak jerk" not in text  # no trial measured it
    old = summarise([{"trial": 0, "success": True}])
    assert all(m["trials"] == 0 for m in old["metrics"].values())
    assert "median" not in "\n".join(summary_lines(old))


def test_trials_with_an_arm_on_the_table_are_counted_and_old_records_say_nothing() -> None:
    base = {"seed": 0, "success": True, "obstacles": ["none"] * 3}
    records = [
        {**base, "trial": 0, "table_contacts": {}},
        {**base, "trial": 1, "table_contacts": {"left_arm ~ table": 8722}},
        {**base, "trial": 2, "table_contacts": {"right_arm ~ table": 23}},
    ]
    summary = summarise(records)
    assert summary["table_contacts"] == 2
    assert "  trials with an arm's link other than its hand on the table: 2" in contact_lines(
        summary
    )
    # Records made before the table was watched: no figure, and no line claiming none.
    old = summarise([{**base, "trial": 0}])
    assert old["table_contacts"] is None
    assert not any("on the table" in line for line in contact_lines(old))


def test_worker_time_splits_into_physics_control_watch_and_tree() -> None:
    # Two trials that measured their parts, one recorded before the parts were: left out.
    records = [
        {
            "trial": 0,
            "success": True,
            "wall_time_s": 10.0,
            "physics_wall_s": 3.0,
            "control_wall_s": 2.0,
            "watch_wall_s": 1.0,
        },
        {
            "trial": 1,
            "success": True,
            "wall_time_s": 6.0,
            "physics_wall_s": 2.0,
            "control_wall_s": 1.0,
            "watch_wall_s": 1.0,
        },
        {"trial": 2, "success": True, "wall_time_s": 50.0, "physics_wall_s": 9.0},
    ]
    summary = summarise(records)
    assert summary["worker_time_split"] == {
        "physics": 5.0,
        "control": 3.0,
        "watch": 2.0,
        "tree": 6.0,
    }
    assert split_line(summary) == (
        "  worker time: physics 31 %, control law 19 %, safety watch 12 %, tree and leaves 38 %"
    )
    old = summarise(records[2:])
    assert old["worker_time_split"] is None
    assert split_line(old) is None


def test_a_sphere_kind_never_drawn_over_a_campaign_is_said() -> None:
    # A world whose layout leaves no room for move 2's 'line' sphere: every draw that tried it
    # was drawn again, and the campaign reported its other kinds alone, without a word.
    listed = [("line", "ahead"), ("line", "ahead")]
    records = [{"obstacles": ["line" if k % 2 else "ahead", "ahead"]} for k in range(12)]
    (line,) = undrawn_kinds(listed, records)
    assert line.startswith("warning: move 2's 'line' sphere") and "none of 12 trials" in line
    assert undrawn_kinds(listed, records[:9]) == []  # too few trials to tell
    both = [{"obstacles": ["line", "ahead" if k % 2 else "line"]} for k in range(12)]
    (line,) = undrawn_kinds(listed, both)
    assert line.startswith("warning: move 1's 'ahead' sphere")


def test_a_campaigns_contacts_beside_a_gap_say_what_each_measures() -> None:
    # "trials with any obstacle contact: 3; closest approach 0.9 mm" read as a contradiction.
    from experiment.summary import contact_lines

    touched = {"obstacle_contacts": 3, "min_obstacle_distance_m": 0.0009}
    lines = contact_lines(touched)
    assert lines[0] == "  trials with any obstacle contact: 3; closest approach 0.9 mm"
    assert "the contacts are PyBullet's, every physics step" in lines[1]
    assert len(contact_lines({**touched, "obstacle_contacts": 0})) == 1

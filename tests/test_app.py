"""The command line: exit codes and the messages bad input gets (no physics)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import app
from duet_robot.text import printable

ROOT = Path(__file__).resolve().parents[1]
DEFAULT = str(ROOT / "worlds" / "parcel_pick_place.yaml")


def exit_code(argv: list[str]) -> int:
    """What ``app.py ARGV`` exits with (a command may return it or raise SystemExit)."""
    try:
        return app.main(argv)
    except SystemExit as exit_info:
        return int(exit_info.code or 0)


def test_validate_a_good_world_and_both_trees(capsys: pytest.CaptureFixture[str]) -> None:
    for path in (
        DEFAULT,
        ROOT / "worlds" / "icub_parcel_pick_place.yaml",
        ROOT / "planner" / "trees" / "pick_and_place.xml",
        ROOT / "planner" / "trees" / "paper_composition.xml",
    ):
        assert app.main(["validate", str(path)]) == app.EXIT_OK
    assert "ok" in capsys.readouterr().out


def test_a_bad_world_exits_2_naming_file_and_field(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = Path(DEFAULT).read_text(encoding="utf-8")
    bad = tmp_path / "bad.yaml"
    bad.write_text(text.replace("sphere_radius: [0.03, 0.05]", "sphere_radius: [0.05, 0.03]"))
    for command in (["validate", str(bad)], ["trials", str(bad), "--n", "1"]):
        assert exit_code(command) == app.EXIT_BAD_INPUT
        err = capsys.readouterr().err
        assert f"{bad}: trials.sphere_radius: expected low <= high, got [0.05, 0.03]" in err


def test_trials_refuse_a_bad_tree_before_running_anything(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    tree = tmp_path / "tree.xml"
    tree.write_text("<root BTCPP_format='4'><BehaviorTree ID='T'><Nope/></BehaviorTree></root>")
    out = tmp_path / "out"
    code = exit_code(["trials", DEFAULT, "--tree", str(tree), "--n", "1", "--out", str(out)])
    assert code == app.EXIT_BAD_INPUT
    assert str(tree) in capsys.readouterr().err
    assert not out.exists()  # nothing run, nothing written


def test_trials_refuse_nonpositive_counts(tmp_path: Path) -> None:
    assert exit_code(["trials", DEFAULT, "--n", "0", "--out", str(tmp_path)]) == 2


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["trials", DEFAULT, "--seed", "-1"], "argument --seed: expected a whole number >= 0"),
        (["run", DEFAULT, "--seed", "-1"], "argument --seed: expected a whole number >= 0"),
        (["trials", DEFAULT, "--out", ""], "argument --out: expected a path, got an empty"),
        (["run", DEFAULT, "--out", " "], "argument --out: expected a path, got an empty"),
        (["report", ""], "argument out: expected a path, got an empty string"),
    ],
)
def test_a_negative_seed_or_an_empty_path_is_refused_before_anything_runs(
    argv: list[str], says: str, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    # --seed -1 had ended a campaign in numpy's traceback; an empty --out wrote the campaign
    # into the current folder.
    with pytest.raises(SystemExit) as stop:
        app.main(argv)
    assert stop.value.code == app.EXIT_BAD_INPUT
    assert says in capsys.readouterr().err


def test_affordances_json_is_the_last_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert app.main(["affordances", DEFAULT, "--json"]) == app.EXIT_OK
    last = capsys.readouterr().out.strip().splitlines()[-1]
    assert isinstance(json.loads(last), dict | list)


def test_sim_compiled_must_be_true_or_false(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    world = tmp_path / "compiled.yaml"
    text = Path(DEFAULT).read_text(encoding="utf-8")
    world.write_text(text.replace("sim:\n", "sim:\n  compiled: fast\n", 1), encoding="utf-8")
    assert exit_code(["validate", str(world)]) == app.EXIT_BAD_INPUT
    assert f"{world}: sim.compiled: expected true or false" in capsys.readouterr().err


def test_names_from_a_file_cannot_print_lines_of_their_own(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    world = tmp_path / "spoof.yaml"
    text = Path(DEFAULT).read_text(encoding="utf-8")
    spoofed = 'name: "x: SUCCESS\\n\\u001b[2Kparcel_pick_place"'
    world.write_text(text.replace("name: parcel_pick_place", spoofed, 1), encoding="utf-8")
    assert printable("a\nb\x1b[2K") == "a\\nb\\x1b[2K"
    assert printable("café") == "café"
    code = exit_code(["validate", str(world)])
    out = capsys.readouterr()
    assert code in (0, 2)  # the world may be refused for its name; it must not spoof lines
    assert "\x1b" not in out.out + out.err


def test_out_naming_a_file_and_absurd_campaigns_are_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    a_file = tmp_path / "out"
    a_file.write_text("not a folder", encoding="utf-8")
    assert exit_code(["run", DEFAULT, "--out", str(a_file)]) == app.EXIT_BAD_INPUT
    assert f"--out {a_file}: expected a folder, got a file" in capsys.readouterr().err
    assert exit_code(["trials", DEFAULT, "--n", str(10**12), "--out", str(tmp_path / "t")]) == 2
    assert f"--n: expected a whole number 1..1000000, got {10**12}" in capsys.readouterr().err
    assert exit_code(["trials", DEFAULT, "--workers", "0", "--out", str(tmp_path / "t")]) == 2
    assert "--workers: expected a whole number 1..1024, got 0" in capsys.readouterr().err
    assert a_file.read_text(encoding="utf-8") == "not a folder"  # nothing lost


@pytest.mark.sim
def test_a_run_whose_figure_cannot_be_written_prints_its_verdict_then_exits_2(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import errno

    import experiment.episode

    def full_disk(*args: object, **kwargs: object) -> Path:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(experiment.episode, "trajectory_figure", full_disk)
    code = exit_code(["run", DEFAULT, "--no-animation", "--out", str(tmp_path), "--json"])
    out, err = capsys.readouterr()
    assert code == app.EXIT_BAD_INPUT
    assert "trajectories.png: No space left on device" in err and "not written" in err
    summary = json.loads(out.splitlines()[-1])  # the verdict and the summary came first
    assert summary["success"] is True
    assert (tmp_path / "run.jsonl").is_file()


def test_a_command_that_loads_pybullet_keeps_its_build_line_off_stderr(tmp_path: Path) -> None:
    import subprocess
    import sys

    done = subprocess.run(
        [sys.executable, str(ROOT / "app.py"), "validate", DEFAULT],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""  # PyBullet's "pybullet build time: ..." is not the user's news
    # A run loads the figure's renderer before the world's modules: a parcel too small for
    # the palms is refused after both are loaded, its one line the whole of stderr.
    small = tmp_path / "small.yaml"
    text = Path(DEFAULT).read_text()
    small.write_text(text.replace("size: [0.20, 0.30, 0.15]", "size: [0.08, 0.08, 0.15]", 1))
    refused = subprocess.run(
        [sys.executable, str(ROOT / "app.py"), "run", str(small), "--out", str(tmp_path / "o")],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=120,
    )
    assert refused.returncode == 2
    assert refused.stderr.startswith(f"{small}: objects[0]: expected a grasp"), refused.stderr
    assert len(refused.stderr.splitlines()) == 1, refused.stderr
    # and the simulator it loaded is PyBullet as ever
    probe = (
        "import worlds, pybullet as pb; c = pb.connect(pb.DIRECT); "
        "print(pb.getNumBodies(physicsClientId=c))"
    )
    shown = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, cwd=ROOT)
    assert shown.stdout.strip() == "0" and shown.stderr == "", shown.stderr


@pytest.mark.sim
def test_one_trial_of_a_campaign_runs_alone_as_the_campaign_ran_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "trial"
    argv = ["trials", DEFAULT, "--seed", "0", "--trial", "0", "--out", str(out), "--json"]
    assert exit_code(argv) == app.EXIT_OK
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    record = json.loads((ROOT / "bench" / "results" / "trials_seed0_n1000.jsonl").open().readline())
    assert record["trial"] == 0
    # the campaign's own record, bit for bit, but for where and when it ran (--json had
    # lacked the record's trial, key, start, goals and obstacles: it could not be compared)
    from experiment.records import RUN_FIELDS

    ran = {"outputs", "backend", "host", *RUN_FIELDS}
    assert {k: v for k, v in summary.items() if k not in ran} == {
        k: v for k, v in record.items() if k not in ran
    }
    assert {p.name for p in out.iterdir()} >= {"trial_0.yaml", "run.jsonl", "trajectories.png"}
    assert not (out / "results.jsonl").exists()
    # the drawn world written is the trial's: app.py run on it makes the same placements
    again = tmp_path / "again"
    argv = ["run", str(out / "trial_0.yaml"), "--out", str(again), "--no-animation", "--json"]
    assert exit_code(argv) == app.EXIT_OK
    rerun = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert rerun["placement_error_m"] == record["placement_error_m"]


def test_a_trial_number_below_zero_is_refused(capsys: pytest.CaptureFixture[str]) -> None:
    assert exit_code(["trials", DEFAULT, "--trial", "-1"]) == app.EXIT_BAD_INPUT
    assert "--trial: expected a trial number 0..999999, got -1" in capsys.readouterr().err


@pytest.mark.sim
def test_a_shorter_campaign_counts_only_its_own_trials_successes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Trials 0, 1, 4 and 5 recorded, --n 3 runs trial 2: the progress had said "successes 5".
    shipped = ROOT / "bench" / "results" / "trials_seed0_n1000.jsonl"
    kept = [line for line in shipped.open() if json.loads(line)["trial"] in (0, 1, 4, 5)]
    out = tmp_path / "c"
    out.mkdir()
    (out / "results.jsonl").write_text("".join(kept), encoding="utf-8")
    assert exit_code(["trials", DEFAULT, "--n", "3", "--workers", "1", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "resuming: 2 of 3 trials" in err
    assert "successes 3  (trial 2: ok)" in err and "successes 5" not in err


def test_report_json_is_strict_and_an_unwritten_picture_exits_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    # A campaign of no wall time had printed "realtime_factor": NaN, which strict parsers
    # refuse; a picture that could not be written had exited 0.
    import experiment.report as report

    shipped = ROOT / "bench" / "results" / "trials_seed0_n1000.jsonl"
    lines = [json.loads(line) for _, line in zip(range(3), shipped.open(), strict=False)]
    (tmp_path / "results.jsonl").write_text(
        "".join(json.dumps(dict(r, wall_time_s=0.0)) + "\n" for r in lines), encoding="utf-8"
    )
    (tmp_path / "report_2.png").write_bytes(b"an earlier report's picture")
    assert exit_code(["report", str(tmp_path), "--json"]) == app.EXIT_OK
    last = capsys.readouterr().out.splitlines()[-1]
    summary = json.loads(last, parse_constant=lambda c: pytest.fail(f"not strict JSON: {c}"))
    assert summary["campaigns"][0]["realtime_factor"] is None
    assert sorted(p.name for p in tmp_path.glob("*.png")) == ["report.png"]  # its own alone

    def refused(campaign: object, path: Path) -> None:
        raise PermissionError(1, "Operation not permitted")

    monkeypatch.setattr(report, "report_figure", refused)
    assert exit_code(["report", str(tmp_path)]) == app.EXIT_BAD_INPUT
    assert "not written: " in capsys.readouterr().err


@pytest.mark.parametrize(
    "argv",
    [
        ["run", DEFAULT, "--main-tree", "Nope"],
        ["trials", DEFAULT, "--n", "2", "--main-tree", "Nope"],
        ["validate", DEFAULT, "--main-tree", "Nope"],
    ],
)
def test_main_tree_without_a_tree_file_is_refused_not_ignored(
    argv: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # It had run the shipped task tree, and filed trials as a campaign of their own.
    if argv[0] != "validate":
        argv = [*argv, "--out", str(tmp_path / "out")]
    try:
        code = app.main(argv)
    except SystemExit as stop:  # the campaign commands exit from their preflight
        code = stop.code
    assert code == app.EXIT_BAD_INPUT
    assert "--main-tree Nope: expected with --tree" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_damaged_library_of_the_worlds_own_is_refused_before_any_trial(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # No move names one of its skills, so the library had been read by the first trial only:
    # validate said ok and a campaign filed every trial as an error.
    from skills.default_library import default_library

    library = tmp_path / "lib"
    default_library().save(library)
    text = (library / "library.json").read_text(encoding="utf-8")
    (library / "library.json").write_text(text[: len(text) // 2], encoding="utf-8")
    world = tmp_path / "w.yaml"
    world.write_text(
        Path(DEFAULT)
        .read_text(encoding="utf-8")
        .replace("  library: default ", f"  library: {library} "),
        encoding="utf-8",
    )
    assert app.main(["validate", str(world)]) == app.EXIT_BAD_INPUT
    assert "library.json:" in capsys.readouterr().err
    try:
        code = app.main(["trials", str(world), "--n", "1", "--out", str(tmp_path / "out")])
    except SystemExit as stop:
        code = stop.code
    assert code == app.EXIT_BAD_INPUT
    assert not (tmp_path / "out" / "results.jsonl").exists()

"""A skill taught from a CSV, by label, is the one a move names and Transport carries it with."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import py_trees
import pytest
from py_trees.common import Status

import app
from planner.leaves import Approach, Grasp, SelectSkills, Transport
from planner.port import Move, Pose
from planner.testing import FakeObject, FakeWorld, tick_until
from planner.wiring import wire
from skills.demos.io import write_demo_csv
from skills.library import SkillLibrary
from tests.skills.conftest import waved_carry

ROOT = Path(__file__).resolve().parents[1]
DT = 1.0 / 60.0
GOAL = Pose.of([0.55, -0.25, 0.675])  # a carry along -y, as the teacher's


@pytest.fixture(scope="module")
def taught(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A library folder: the default skills and ``my_wave``, taught by the command line."""
    folder = tmp_path_factory.mktemp("taught")
    demo = waved_carry(0.03, seed=1)
    assert demo.orientations is not None
    csv = write_demo_csv(folder / "wave.csv", demo.t, demo.positions, demo.orientations)
    argv = ["teach", str(csv), "--label", "my_wave", "--space", "absolute"]
    assert app.main([*argv, "--library", str(folder / "lib"), "--json"]) == app.EXIT_OK
    return folder / "lib"


def test_teach_takes_any_identifier_and_records_it(
    taught: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    lib = SkillLibrary.load(taught)
    wave = lib.named("my_wave")
    assert (wave.name, wave.label, wave.action.value) == ("wave", "my_wave", "transport")
    argv = ["teach", str(taught.parent / "wave.csv"), "--space", "absolute"]
    assert app.main([*argv, "--label", "my-wave", "--library", str(taught)]) == 2
    assert "--label: expected an identifier" in capsys.readouterr().err
    # Taught again, it is recognised as the skill it now is.
    assert app.main([*argv, "--label", "again", "--library", str(taught)]) == 0
    assert "not added: it is the skill 'wave' already" in capsys.readouterr().out
    assert app.main([*argv, "--label", "again", "--force", "--library", str(taught)]) == 2
    assert "--name: expected a new skill name, got 'wave'" in capsys.readouterr().err


def carry(library: SkillLibrary, move: Move, **ports: object) -> tuple[Status, str, np.ndarray]:
    """Select, approach, grasp and carry on a fresh fake world; the object's path, (N, 3)."""
    py_trees.blackboard.Blackboard.clear()
    world = FakeWorld(
        objects=[FakeObject("parcel", np.array([0.20, 0.30, 0.15]))], moves={"parcel": (move,)}
    )
    for leaf, wiring in (
        (SelectSkills("select"), {"plan": "{plan}"}),
        (Approach("approach"), {}),
        (Grasp("grasp"), {"plan": "{plan}", "state": "{state}"}),
    ):
        wire(leaf, object="parcel", **wiring)  # type: ignore[arg-type]
        leaf.setup(world=world, library=library, control_dt=DT)
        assert tick_until(leaf, world, DT).final == Status.SUCCESS
    leaf = Transport("carry")
    wire(leaf, object="parcel", move=0, plan="{plan}", from_state="{state}", **ports)  # type: ignore[arg-type]
    leaf.setup(world=world, library=library, control_dt=DT)
    path = []
    status = Status.RUNNING
    for _ in range(3000):
        leaf.tick_once()
        status = leaf.status
        path.append(world.object_pose("parcel").position.copy())
        if status != Status.RUNNING:
            break
        world.advance(DT)
    return status, leaf.feedback_message, np.array(path)


def reversals(lateral: np.ndarray) -> int:
    """How often a lateral offset, read at 5 mm resolution (past the learnt tremor), turns back."""
    steps = np.diff(np.round((lateral - lateral[0]) / 0.005))
    signs = np.sign(steps[steps != 0])
    return int(np.count_nonzero(np.diff(signs)))


def test_a_move_naming_the_taught_skill_is_carried_with_it(taught: Path) -> None:
    lib = SkillLibrary.load(taught)
    plain = carry(lib, Move(GOAL))
    waved = carry(lib, Move(GOAL, skill="my_wave"))
    for status, feedback, _ in (plain, waved):
        assert status == Status.SUCCESS, feedback
    # The carry goes along -y: the wave is in x, the teacher's 3 cm, three cycles.
    assert np.ptp(plain[2][:, 0]) < 0.005 and reversals(plain[2][:, 0]) == 0
    assert np.ptp(waved[2][:, 0]) == pytest.approx(0.049, abs=0.01)
    assert reversals(waved[2][:, 0]) >= 4
    # The port wins over the move: pick_and_place by name is the plain carry again.
    ported = carry(lib, Move(GOAL, skill="my_wave"), skill="pick_and_place")
    assert ported[0] == Status.SUCCESS
    np.testing.assert_allclose(ported[2], plain[2], atol=1e-9)


def test_an_unknown_skill_fails_naming_it_and_the_library(taught: Path) -> None:
    lib = SkillLibrary.load(taught)
    status, feedback, _ = carry(lib, Move(GOAL, skill="my_wav"))
    assert status == Status.FAILURE
    assert feedback.startswith("skill 'my_wav': expected the name or label of one of the library")
    assert "labels: transport" in feedback and "my_wave" in feedback


def test_validate_checks_the_moves_skills_against_the_worlds_library(
    taught: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = (ROOT / "worlds" / "parcel_pick_place.yaml").read_text(encoding="utf-8")
    text = text.replace("library: default", f"library: {taught}")
    text = text.replace("obstacles: [ball_right]", "obstacles: [ball_right]\n        skill: SKILL")
    for skill, code in (("my_wave", 0), ("wave", 0), ("my_wav", 2), ("avoid_obstacle", 2)):
        world = tmp_path / f"{skill}.yaml"
        world.write_text(text.replace("SKILL", skill), encoding="utf-8")
        assert app.main(["validate", str(world)]) == code, skill
    err = capsys.readouterr().err
    assert f"{tmp_path / 'my_wav.yaml'}: task[0].moves[1].skill: skill 'my_wav': expected" in err
    assert "got 'avoid_obstacle' (obstacle_steering); the library's learnt motions" in err
    bad = tmp_path / "bad.yaml"
    bad.write_text(text.replace("SKILL", "'my wave'"), encoding="utf-8")
    assert app.main(["validate", str(bad)]) == 2
    assert "task[0].moves[1].skill: expected a skill name or label" in capsys.readouterr().err


def test_validate_checks_a_trees_skill_ports_against_the_worlds_library(
    taught: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # A world's own tree (or --tree) naming a skill its library lacks had validated, then
    # failed its run at the first carry, after 18 s of simulation.
    shipped = (ROOT / "planner" / "trees" / "pick_and_place.xml").read_text(encoding="utf-8")
    text = (ROOT / "worlds" / "parcel_pick_place.yaml").read_text(encoding="utf-8")
    text = text.replace("library: default", f"library: {taught}")
    for skill, code in (("my_wave", 0), ("my_wav", 2)):
        tree = tmp_path / f"{skill}.xml"
        tree.write_text(
            shipped.replace("<Transport name=", f'<Transport skill="{skill}" name='),
            encoding="utf-8",
        )
        world = tmp_path / f"{skill}.yaml"
        world.write_text(text.replace("\ntree: null", f"\ntree: {tree.name}"), encoding="utf-8")
        assert app.main(["validate", str(world)]) == code, skill
        assert app.main(["validate", str(world), "--tree", str(tree)]) == code, skill
    err = capsys.readouterr().err
    assert f"{tmp_path / 'my_wav.xml'}:" in err
    assert ": <Transport name=\"transport\">: port 'skill': skill 'my_wav': expected" in err


@pytest.mark.sim
def test_a_taught_wave_carries_the_parcel_in_physics(taught: Path, tmp_path: Path) -> None:
    from experiment.episode import run_episode
    from worlds.world_file import load_world

    text = (ROOT / "worlds" / "parcel_pick_place.yaml").read_text(encoding="utf-8")
    text = text.replace("library: default", f"library: {taught}")
    text = text.replace("obstacles: []", "obstacles: []\n        skill: my_wave")
    path = tmp_path / "wave.yaml"
    path.write_text(text, encoding="utf-8")
    report = run_episode(load_world(path), None, out=None, animation=False)
    assert report.success, report.failure
    assert all(e is not None and e < 0.01 for e in report.placement_error_m)


def noisy_carry_csv(path: Path, sigma_m: float, seed: int) -> Path:
    """The pick-and-place teacher's carry with ``sigma_m`` of white noise on each sample's
    position, written as a demonstration CSV at ``path``."""
    demo = waved_carry(0.0, seed=2)
    assert demo.orientations is not None
    noise = sigma_m * np.random.default_rng(seed).standard_normal(demo.positions.shape)
    return write_demo_csv(path, demo.t, demo.positions + noise, demo.orientations)


def test_teach_smooths_a_noisy_recording_and_refuses_one_it_cannot_learn(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # The pick-and-place teacher's carry recorded with 0.5 mm of white noise per sample.
    csv = noisy_carry_csv(tmp_path / "noisy.csv", 5e-4, seed=0)
    argv = ["teach", str(csv), "--label", "noisy", "--space", "absolute", "--force"]
    # As recorded, the forcing fits the noise and the skill leaves its goal: nothing is saved.
    raw = tmp_path / "raw"
    assert app.main([*argv, "--library", str(raw), "--smooth-ms", "0"]) == app.EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert err.startswith(f"{csv}: expected a skill that settles at its goal"), err
    assert "try a larger --smooth-ms. Nothing was added." in err
    assert not raw.exists()
    # Smoothed (the default), it is learnt, and says how well it reproduces the recording.
    lib = tmp_path / "lib"
    assert app.main([*argv, "--library", str(lib), "--json"]) == app.EXIT_OK
    out = capsys.readouterr().out
    assert "reproduces the demonstration within" in out
    shown = json.loads(out.splitlines()[-1])["reproduction"]
    assert shown["smoothing_ms"] == 40.0
    assert shown["settle_m"] < 0.02 and shown["rms_m"] < 0.005
    assert SkillLibrary.load(lib).named("noisy").label == "noisy"
    assert app.main([*argv, "--library", str(lib), "--smooth-ms", "-5"]) == app.EXIT_BAD_INPUT
    assert "--smooth-ms: expected 0 to 1000 ms, got -5.0" in capsys.readouterr().err


@pytest.mark.parametrize("share", [0.8, 0.5])
def test_teach_says_when_a_recording_was_cut_before_the_motion_stopped(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], share: float
) -> None:
    # Cut at half its duration, near its fastest, the skill had settled well enough: it was
    # added with exit 0, a motion whose end was never shown.
    demo = waved_carry(0.0, seed=2)
    assert demo.orientations is not None
    keep = demo.t <= demo.t[0] + share * demo.duration  # stopped recording mid-carry
    csv = write_demo_csv(
        tmp_path / "cut.csv", demo.t[keep], demo.positions[keep], demo.orientations[keep]
    )
    argv = ["teach", str(csv), "--label", "cut", "--space", "absolute", "--force"]
    assert app.main([*argv, "--library", str(tmp_path / "lib")]) == app.EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert err.startswith(
        f"{csv}: expected a recording that ends at rest (over its last 100 ms under 25% of "
        "its peak speed and turn rate), got one that ends moving at "
    ), err
    assert err.rstrip().endswith("record until the motion has stopped. Nothing was added.")
    assert not (tmp_path / "lib").exists()


def test_teach_tells_a_noisy_recording_from_a_cut_one(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # With 2 mm of noise a sample's own speed at the end had been taken for a cut motion.
    csv = noisy_carry_csv(tmp_path / "noisy.csv", 2e-3, seed=1)
    argv = ["teach", str(csv), "--label", "noisy", "--space", "absolute", "--force"]
    code = app.main([*argv, "--library", str(tmp_path / "lib"), "--smooth-ms", "10"])
    err = capsys.readouterr().err
    assert code == app.EXIT_BAD_INPUT  # it strays 650 mm from its goal
    assert "ends at rest" not in err and "record until" not in err
    assert "the recording is too noisy to learn from as it is (smoothed over 10 ms); try a " in err


def test_teach_judges_a_turn_in_place_by_its_turn_not_its_positions_noise(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # A reviewer's cases: the shipped turn in place with 0.5 mm of tracker noise had been
    # refused as "ends at 0.002 m/s, its peak 0.006 m/s" (noise over noise), while the same
    # turn cut at half its duration was added with exit 0 and overshot by 4.3 degrees.
    from skills.demos.io import read_demo_csv

    demo = read_demo_csv(ROOT / "skills" / "demos" / "rotate_z.csv").demonstration
    assert demo.orientations is not None
    noisy = demo.positions + 5e-4 * np.random.default_rng(5).standard_normal(demo.positions.shape)
    keep = demo.t <= demo.t[0] + 0.5 * demo.duration
    for name, rows, positions in (
        ("noisy", slice(None), noisy),
        ("cut", keep, demo.positions[keep]),
    ):
        csv = write_demo_csv(
            tmp_path / f"{name}.csv", demo.t[rows], positions, demo.orientations[rows]
        )
        argv = ["teach", str(csv), "--label", f"my_{name}", "--space", "relative"]
        code = app.main(
            [*argv, "--action", "rotate_z", "--library", str(tmp_path / name), "--force"]
        )
        err = capsys.readouterr().err
        if name == "noisy":
            assert code == app.EXIT_OK, err
        else:
            assert code == app.EXIT_BAD_INPUT
            assert "got one that ends turning at " in err and "record until the motion" in err


def test_teach_trims_the_rest_recorded_before_and_after_the_motion(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Recorded from 2 s before the hand moved to 5 s after it stopped: the skill had kept
    # both, waiting 2 s at every use and lasting 9.5 s for 2.5 of motion (5 s before it, it
    # strayed 36 mm after its duration and was refused as "too noisy").
    from skills.demos.io import read_demo_csv
    from skills.library import SkillLibrary

    demo = read_demo_csv(ROOT / "skills" / "demos" / "pick_place.csv").demonstration
    assert demo.orientations is not None
    dt = float(np.median(np.diff(demo.t)))
    before = demo.t[0] - dt * np.arange(round(2.0 / dt), 0, -1)
    after = demo.t[-1] + dt * np.arange(1, round(5.0 / dt) + 1)
    t = np.concatenate([before, demo.t, after])
    p = np.concatenate(
        [np.repeat(demo.positions[:1], before.size, 0), demo.positions,
         np.repeat(demo.positions[-1:], after.size, 0)]
    )  # fmt: skip
    q = np.concatenate(
        [np.repeat(demo.orientations[:1], before.size, 0), demo.orientations,
         np.repeat(demo.orientations[-1:], after.size, 0)]
    )  # fmt: skip
    csv = write_demo_csv(tmp_path / "resting.csv", t, p, q)
    lib = tmp_path / "lib"
    argv = ["teach", str(csv), "--label", "resting", "--space", "absolute", "--library", str(lib)]
    assert app.main([*argv, "--force"]) == app.EXIT_OK
    out = capsys.readouterr().out
    assert "note: trimmed the rest recorded before the motion (1.9" in out
    assert "and after it (4.9" in out
    taught = SkillLibrary.load(lib).named("resting")
    assert float(taught.params["demo_tau"]) == pytest.approx(demo.duration, abs=0.35)

"""Teaching from Python (skills.teaching.teach): the command line's teach, with errors that name
the argument at fault and nothing written unless a skill is added."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from skills.demos.io import write_demo_csv
from skills.library import SkillLibrary
from skills.teaching import TeachingError, teach, teaching_action
from skills.vocabulary import Action, Space
from tests.skills.conftest import waved_carry


@pytest.fixture(scope="module")
def wave_csv(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The carry with a 3 cm lateral wave, as a CSV."""
    demo = waved_carry(0.03, seed=1)
    assert demo.orientations is not None
    folder = tmp_path_factory.mktemp("teaching")
    return write_demo_csv(folder / "wave.csv", demo.t, demo.positions, demo.orientations)


def test_teach_adds_a_new_skill_that_reproduces_its_demonstration(
    wave_csv: Path, tmp_path: Path
) -> None:
    lines: list[str] = []
    lesson = teach(wave_csv, tmp_path / "lib", "my_wave", Space.ABSOLUTE, report=lines.append)
    assert lesson.added is not None
    assert (lesson.added.name, lesson.added.label, lesson.added.action) == (
        "wave",
        "my_wave",
        Action.TRANSPORT,
    )
    # The plain carry is its closest skill, and not a match: the wave is a new shape.
    assert lesson.recognition.best == "pick_and_place" and not lesson.recognition.matched
    assert lesson.reproduction is not None and lesson.reproduction.settles
    assert lesson.reproduction.rms_m < 0.005
    saved = SkillLibrary.load(tmp_path / "lib")
    for key, values in lesson.added.arrays.items():
        np.testing.assert_array_equal(saved.named("wave").arrays[key], values, err_msg=key)
    assert lines[0].startswith("closest skill: pick_and_place")
    assert lines[-1] == (
        f"added skill 'wave' labelled 'my_wave' (transport, absolute) to {tmp_path / 'lib'}"
    )
    # Taught again into that library, it is the skill it now is: nothing is learnt or written.
    again = teach(wave_csv, tmp_path / "lib", "again", Space.ABSOLUTE)
    assert again.recognition.best == "wave" and again.recognition.matched
    assert again.added is None and again.reproduction is None
    assert "again" not in SkillLibrary.load(tmp_path / "lib")


def test_teach_errors_name_the_argument_and_write_nothing(wave_csv: Path, tmp_path: Path) -> None:
    folder = tmp_path / "lib"
    cases = [
        (dict(label="my-wave"), "label"),
        (dict(label="wave_in_palm", space=Space.RELATIVE), "action"),
        (dict(threshold=float("nan")), "threshold"),
        (dict(smoothing_s=-0.005), "smoothing_s"),
        (dict(name="pick_and_place", force=True), "name"),
        (dict(space="sideways"), "space"),
        (dict(action="fly"), "action"),
    ]
    for changes, field in cases:
        args: dict[str, object] = dict(label="my_wave", space=Space.ABSOLUTE) | changes
        with pytest.raises(TeachingError) as raised:
            teach(wave_csv, folder, **args)  # type: ignore[arg-type]
        assert raised.value.field == field, changes
        assert str(raised.value).startswith(f"{field}: expected"), str(raised.value)
        # A caller's own names for the arguments are the ones the message gives.
        with pytest.raises(TeachingError, match=rf"^--{field}: expected"):
            teach(wave_csv, folder, names={field: f"--{field}"}, **args)  # type: ignore[arg-type]
    with pytest.raises(TeachingError) as raised:
        teach(tmp_path / "missing.csv", folder, "my_wave", Space.ABSOLUTE)
    assert raised.value.field is None and "missing.csv" in str(raised.value)
    assert not folder.exists()


def test_a_recording_too_short_to_fit_names_its_file_once(tmp_path: Path) -> None:
    # Three samples that move: the file had been named twice, and the advice named an option
    # teach does not have ("lower n_basis").
    demo = waved_carry(0.03, seed=1)
    assert demo.orientations is not None
    keep = np.array([0, len(demo.t) // 2, len(demo.t) - 1])
    short = write_demo_csv(
        tmp_path / "short.csv", demo.t[keep], demo.positions[keep], demo.orientations[keep]
    )
    with pytest.raises(TeachingError) as raised:
        teach(short, tmp_path / "lib", "my_wave", Space.ABSOLUTE)
    said = str(raised.value)
    assert said.startswith(f"{short}: t: expected at least") and said.count("short.csv") == 1
    assert "record at a higher rate" in said and "lower n_basis" not in said


def test_teaching_action_follows_the_label_then_the_space() -> None:
    assert teaching_action("rotate_z", Space.RELATIVE) is Action.ROTATE_Z
    assert teaching_action("my_wave", Space.ABSOLUTE) is Action.TRANSPORT
    assert teaching_action("my_wave", Space.RELATIVE, Action.HOLD_LATERAL) is Action.HOLD_LATERAL
    with pytest.raises(TeachingError, match="for the relative skill 'my_wave'"):
        teaching_action("my_wave", Space.RELATIVE)


def test_a_label_another_skill_answers_to_says_which_one_a_move_gets(
    wave_csv: Path, tmp_path: Path
) -> None:
    # A re-recorded skill under its old label was added without a word, and a world naming
    # the label kept running the old one.
    folder = tmp_path / "lib"
    teach(wave_csv, folder, "my_wave", Space.ABSOLUTE)
    lines: list[str] = []
    teach(wave_csv, folder, "my_wave", Space.ABSOLUTE, name="wave2", force=True,
          report=lines.append)  # fmt: skip
    assert lines[-1] == (
        "note: 'my_wave' names 'wave' to a move or a tree that gives it (labelled so before); "
        "give 'wave2' to run this one"
    )
    assert SkillLibrary.load(folder).named("my_wave").name == "wave"
    lines.clear()
    teach(wave_csv, folder, "wave", Space.ABSOLUTE, name="wave3", force=True,
          report=lines.append)  # fmt: skip
    assert lines[-1].startswith("note: 'wave' names 'wave' to a move or a tree that gives it (its")


def _lift(dz: float) -> tuple[np.ndarray, np.ndarray]:
    """2 s of a 0.3 m reach along x over a 10 cm lift, ending ``dz`` m above its start."""
    t = np.linspace(0.0, 2.0, 401)
    u = t / 2.0
    jerk_free = 10 * u**3 - 15 * u**4 + 6 * u**5
    positions = np.outer(jerk_free, [0.3, 0.0, dz])
    positions[:, 2] += 0.10 * np.sin(np.pi * u) ** 2
    return t, positions


@pytest.mark.parametrize("dz", [0.0009, 0.0011, 0.003, 0.0])
def test_a_taught_lift_keeps_its_height_at_a_goal_higher_than_shown(
    tmp_path: Path, dz: float
) -> None:
    # Scaled by the new move's height change over the demonstration's (Ijspeert's amplitude
    # scaling), a lift ending 1.1 mm above its start, sent 5 cm higher, had risen 4.6 m; one
    # ending 0.9 mm above, under the 1 mm floor, 0.15 m.
    from skills import quaternion as quat
    from skills.pose_dmp import PoseState, pose_rollout

    t, positions = _lift(dz)
    demo = write_demo_csv(tmp_path / "lift.csv", t, positions, np.tile(quat.IDENTITY, (len(t), 1)))
    lines: list[str] = []
    lesson = teach(demo, tmp_path / "lib", "lift", Space.RELATIVE, "approach", report=lines.append)
    assert lesson.added is not None
    model = lesson.added.pose_model()
    goal = np.array([0.3, 0.0, 0.05])
    target = model.target(positions[0], quat.IDENTITY, goal, quat.IDENTITY, 2.0)
    path = pose_rollout(model, target, PoseState.at_rest(positions[0], quat.IDENTITY), 0.005, 600)
    assert 0.14 < path.positions[:, 2].max() < 0.16
    assert np.linalg.norm(path.positions[-1] - goal) < 0.002
    shaped = dz >= 0.001  # under the floor the height never scaled
    assert any("z replayed as shown" in line for line in lines) == shaped
    assert ("z replayed as shown" in lesson.added.provenance.method) == shaped


def test_a_taught_reach_still_scales_the_axes_it_moves_along(tmp_path: Path) -> None:
    from skills import quaternion as quat
    from skills.pose_dmp import PoseState, pose_rollout
    from skills.scaling import shape_floor

    t, positions = _lift(0.08)  # rising 8 cm over a 10 cm arc: a displacement, not a shape
    assert shape_floor(positions, positions[-1] - positions[0], 1e-3) == (1e-3, [])
    demo = write_demo_csv(tmp_path / "rise.csv", t, positions, np.tile(quat.IDENTITY, (401, 1)))
    lesson = teach(demo, tmp_path / "lib", "rise", Space.RELATIVE, "approach")
    assert lesson.added is not None and "replayed" not in lesson.added.provenance.method
    model = lesson.added.pose_model()
    goal = np.array([0.6, 0.0, 0.16])  # twice the reach: the path twice the size
    target = model.target(positions[0], quat.IDENTITY, goal, quat.IDENTITY, 2.0)
    path = pose_rollout(model, target, PoseState.at_rest(positions[0], quat.IDENTITY), 0.005, 600)
    shown = pose_rollout(
        model,
        model.target(positions[0], quat.IDENTITY, positions[-1], quat.IDENTITY, 2.0),
        PoseState.at_rest(positions[0], quat.IDENTITY),
        0.005,
        600,
    )
    np.testing.assert_allclose(path.positions, 2.0 * shown.positions, atol=1e-9)


def test_a_file_name_that_cannot_name_a_skill_says_so_before_learning(
    wave_csv: Path, tmp_path: Path
) -> None:
    # It had been learnt first, then refused as `name: ... got 'my demo (1)'` of a --name the
    # user never gave.
    spaced = tmp_path / "my demo (1).csv"
    spaced.write_bytes(wave_csv.read_bytes())
    with pytest.raises(TeachingError) as err:
        teach(spaced, tmp_path / "lib", "my_wave", Space.ABSOLUTE, names={"name": "--name"})
    assert str(err.value) == (
        "--name: expected a skill name of letters, digits, '_' or '-', got 'my demo (1)' "
        "(the file's name, without --name)"
    )
    assert err.value.field == "--name" and not (tmp_path / "lib").exists()
    lesson = teach(spaced, tmp_path / "lib", "my_wave", Space.ABSOLUTE, name="my_demo_1")
    assert lesson.added is not None and lesson.added.name == "my_demo_1"


def _turn_about_z(degrees: float, samples: int = 401) -> tuple[np.ndarray, np.ndarray]:
    """2 s of a turn of ``degrees`` about z (minimum jerk) with a 0.2 m reach along x."""
    t = np.linspace(0.0, 2.0, samples)
    u = t / 2.0
    s = 10 * u**3 - 15 * u**4 + 6 * u**5
    half = np.radians(degrees) * s / 2.0
    q = np.column_stack((np.zeros_like(t), np.zeros_like(t), np.sin(half), np.cos(half)))
    return t, q


def test_a_gap_in_the_recording_is_bridged_at_even_steps(tmp_path: Path) -> None:
    # A tracker that lost the object for 0.3 s: smoothed and differentiated across the gap as
    # recorded, the forcing was fitted to a kink and the skill strayed 0.4 m (RMS) from a
    # motion of 0.3 m; learnt from even steps, it follows it as the gapless recording does.
    t, positions = _lift(0.0)
    _, q = _turn_about_z(60.0)
    kept = (t < 0.8) | (t >= 1.1)
    gapped = write_demo_csv(tmp_path / "gapped.csv", t[kept], positions[kept], q[kept])
    lines: list[str] = []
    lesson = teach(gapped, tmp_path / "lib", "lift", Space.ABSOLUTE, report=lines.append)
    assert lesson.reproduction is not None and lesson.reproduction.rms_m < 0.003
    (note,) = [line for line in lines if "uneven" in line]
    assert "the longest at 0.80 s" in note and "at even 5 ms steps" in note


def test_an_even_recording_is_learnt_from_its_own_samples() -> None:
    from skills.demo_conditioning import even_steps
    from skills.demonstration import Demonstration

    t, positions = _lift(0.0)
    demo = Demonstration.create(t, positions, _turn_about_z(30.0)[1])
    assert even_steps(demo) == (demo, "")


@pytest.mark.parametrize("degrees", [200.0, 270.0])
def test_a_turn_past_half_a_turn_is_refused_not_learnt_the_short_way(
    tmp_path: Path, degrees: float
) -> None:
    # 2 log(g q^-1) takes the short way: 270 deg would be learnt as -90, and sent to a goal of
    # 185 deg the object turned 545 deg.
    t, positions = _lift(0.0)
    _, q = _turn_about_z(degrees)
    demo = write_demo_csv(tmp_path / "turn.csv", t, positions, q)
    with pytest.raises(TeachingError, match=rf"got one turning {degrees:.0f} deg: record it as"):
        teach(demo, tmp_path / "lib", "turn", Space.ABSOLUTE)
    assert not (tmp_path / "lib").exists()
    teach(
        write_demo_csv(tmp_path / "ok.csv", t, positions, _turn_about_z(170.0)[1]),
        tmp_path / "lib",
        "turn",
        Space.ABSOLUTE,
    )


def test_a_skill_that_does_not_follow_its_recording_is_refused(tmp_path: Path) -> None:
    # Smoothed over 0.3 s, a carry's 3 Hz sway of 8 cm is gone: the skill settles at its goal
    # but strays from the way shown, measured against the recording itself.
    t = np.linspace(0.0, 3.0, 601)
    u = np.clip((t - 0.5) / 2.0, 0.0, 1.0)
    positions = np.outer(10 * u**3 - 15 * u**4 + 6 * u**5, [0.3, 0.0, 0.0])
    positions[:, 1] += 0.08 * np.sin(2.0 * np.pi * 3.0 * 2.0 * u) * np.sin(np.pi * u)
    q = np.tile([0.0, 0.0, 0.0, 1.0], (t.size, 1))
    demo = write_demo_csv(tmp_path / "sway.csv", t, positions, q)
    with pytest.raises(TeachingError, match=r"expected a skill that follows its demonstration"):
        teach(demo, tmp_path / "lib", "sway", Space.ABSOLUTE, smoothing_s=0.3)
    assert not (tmp_path / "lib").exists()
    assert teach(demo, tmp_path / "lib", "sway", Space.ABSOLUTE).added is not None


@pytest.mark.parametrize("goal_deg", [0.0, -30.0, 60.0])
def test_a_taught_transport_turns_as_its_move_asks_not_as_it_was_shown(
    tmp_path: Path, goal_deg: float
) -> None:
    # Its orientation forcing had been replayed unscaled: a demonstrated 0 -> 30 degree turn
    # swung the object 22 degrees on a move of no turn, and overshot -30 to -49.
    from skills import quaternion as quat
    from skills.composer import DualArmComposer, grasped_state
    from skills.couplings.forcing import LearntForcing
    from skills.dual_arm import GraspGeometry

    t, positions = _lift(0.0)
    _, q = _turn_about_z(30.0)
    lesson = teach(
        write_demo_csv(tmp_path / "carry.csv", t, positions, q),
        tmp_path / "lib",
        "carry",
        Space.ABSOLUTE,
    )
    assert lesson.added is not None and lesson.added.action is Action.TRANSPORT
    grip = GraspGeometry.lateral(0.2, 0.02)
    start = grasped_state(
        [0.55, 0.0, 0.675],
        quat.IDENTITY,
        (grip.left_position, grip.left_orientation),
        (grip.right_position, grip.right_orientation),
    )
    half = np.radians(goal_deg) / 2.0
    goal = np.array([0.0, 0.0, np.sin(half), np.cos(half)])
    forcing = LearntForcing(lesson.added.pose_model())
    path = DualArmComposer.start(start, [0.7, 0.0, 0.675], goal, 4.0, [(forcing, 1.0)])
    o = path.rollout(360, 1.0 / 60.0).object_orientations
    yaw = np.degrees(2.0 * np.arctan2(o[:, 2], o[:, 3]))
    low, high = sorted((0.0, goal_deg))
    assert low - 1.0 < yaw.min() and yaw.max() < high + 1.0  # no swing, no overshoot
    assert yaw[-1] == pytest.approx(goal_deg, abs=0.5)

"""Skill library: labels, atomic save and validated load, movement recognition."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from skills import quaternion as quat
from skills.demonstration import Demonstration
from skills.library import LibraryFileError, SkillLibrary
from skills.pose_dmp import PoseState, fit_pose, pose_rollout
from skills.recognition import recognise
from skills.skill import Provenance, Skill, SkillKind, learnt_skill
from skills.vocabulary import Action, AffordanceElement, Space
from tests.skills.conftest import min_jerk, pick_place_demo

WHEN = Provenance.now(("pick_place.csv",), "ridge regression", {"rms_m": 1e-4})


def rotation_demo(angle: float = 1.4, n: int = 600) -> Demonstration:
    t = np.linspace(0, 2.0, n)
    s = min_jerk(t / 2.0)
    q = quat.from_axis_angle([0.0, 0.0, 1.0], angle * s)
    return Demonstration.create(t, np.tile([0.6, 0.0, 0.7], (n, 1)), q, name="rotate")


def small_library() -> SkillLibrary:
    lib = SkillLibrary()
    lib.add(
        learnt_skill(
            "pick_place",
            Action.TRANSPORT,
            Space.ABSOLUTE,
            fit_pose(pick_place_demo()),
            (AffordanceElement.ON_SURFACE,),
            WHEN,
        )
    )
    lib.add(
        learnt_skill(
            "rotate_z",
            Action.ROTATE_Z,
            Space.ABSOLUTE,
            fit_pose(rotation_demo()),
            (AffordanceElement.ROTATABLE,),
            WHEN,
        )
    )
    lib.add(
        Skill(
            "hold",
            Action.HOLD_LATERAL,
            Space.RELATIVE,
            SkillKind.GRASP_MAINTENANCE,
            (AffordanceElement.GRASPABLE_LATERAL,),
            {"stiffness": 400.0, "squeeze_depth_m": 0.015},
            {},
            WHEN,
        )
    )
    return lib


def test_find_by_label_and_list() -> None:
    lib = small_library()
    assert lib.names() == ("pick_place", "rotate_z", "hold")
    assert [s.name for s in lib.by_action(Action.ROTATE_Z)] == ["rotate_z"]
    assert [s.name for s in lib.by_action(Action.TRANSPORT, Space.RELATIVE)] == []
    assert lib.first(Action.HOLD_LATERAL).space is Space.RELATIVE
    assert [s.name for s in lib.serving(AffordanceElement.ROTATABLE)] == ["rotate_z"]
    with pytest.raises(ValueError, match="expected a new name, got 'hold'"):
        lib.add(lib.get("hold"))
    with pytest.raises(KeyError, match="expected a skill for action 'retreat'"):
        lib.first(Action.RETREAT)


def test_save_and_load_round_trip(tmp_path: Path) -> None:
    lib = small_library()
    lib.save(tmp_path / "lib")
    back = SkillLibrary.load(tmp_path / "lib")
    assert back.names() == lib.names()
    assert back.describe() == lib.describe()
    a, b = lib.get("pick_place").pose_model(), back.get("pick_place").pose_model()
    start = PoseState.at_rest([0.5, 0.0, 0.7])
    goal = ([0.7, 0.2, 0.7], quat.IDENTITY)
    ta = pose_rollout(a, a.target(start.position, start.orientation, *goal), start, 0.01)
    tb = pose_rollout(b, b.target(start.position, start.orientation, *goal), start, 0.01)
    assert_allclose(ta.positions, tb.positions, atol=0)
    assert back.get("hold").params["stiffness"] == 400.0


def test_save_replaces_atomically_and_refuses_foreign_folders(tmp_path: Path) -> None:
    lib = small_library()
    lib.save(tmp_path / "lib")
    smaller = SkillLibrary([lib.get("hold")])
    smaller.save(tmp_path / "lib")
    assert SkillLibrary.load(tmp_path / "lib").names() == ("hold",)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["lib"]  # no temporary leftovers
    other = tmp_path / "photos"
    other.mkdir()
    (other / "cat.jpg").write_bytes(b"x")
    with pytest.raises(
        LibraryFileError,
        match=r"photos: expected a skill library folder .*got another folder: not overwriting it",
    ):
        lib.save(other)
    assert (other / "cat.jpg").exists()


def _corrupt(tmp_path: Path, edit: object) -> Path:
    small_library().save(tmp_path / "lib")
    meta_path = tmp_path / "lib" / "library.json"
    meta = json.loads(meta_path.read_text())
    edit(meta)  # type: ignore[operator]
    meta_path.write_text(json.dumps(meta))
    return tmp_path / "lib"


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (lambda m: m.update(version=7), r"library.json: version: expected 1 or 2, got 7"),
        (lambda m: m["skills"][1].update(action="fly"), r"skills\[1\]\.action: expected one of"),
        (
            lambda m: m["skills"][0].pop("space"),
            r"skills\[0\]\.space: expected a space, got nothing",
        ),
        (
            lambda m: m["skills"][2].update(colour="red"),
            r"skills\[2\]\.colour: expected a known key",
        ),
        (
            lambda m: m["skills"][0]["arrays"].append("ghost"),
            r"pick_place/ghost: expected an array",
        ),
        (
            lambda m: m["skills"][0]["params"].update(n_basis=7),
            r"arrays.npz: pick_place/centres: expected shape \(7,\), got \(50,\)",
        ),
        (
            lambda m: m["skills"].append(m["skills"][0]),
            r"skills\[3\]\.name: expected a unique name",
        ),
    ],
)
def test_load_names_the_file_and_field(tmp_path: Path, edit: object, match: str) -> None:
    folder = _corrupt(tmp_path, edit)
    with pytest.raises(LibraryFileError, match=match):
        SkillLibrary.load(folder)


def test_load_reports_bad_json_with_its_line(tmp_path: Path) -> None:
    small_library().save(tmp_path / "lib")
    (tmp_path / "lib" / "library.json").write_text('{\n  "format": \n}')
    with pytest.raises(LibraryFileError, match=r"library.json:3:1: expected valid JSON"):
        SkillLibrary.load(tmp_path / "lib")
    with pytest.raises(LibraryFileError, match="expected a skill library folder, got no such"):
        SkillLibrary.load(tmp_path / "nope")


def test_recognition_matches_the_same_motion_elsewhere_and_rejects_a_new_one() -> None:
    lib = small_library()
    # The pick-and-place, moved, mirrored in direction, slower and larger.
    d = pick_place_demo()
    moved = d.positions.copy()
    moved[:, 0] = d.positions[0, 0] - 1.3 * (d.positions[:, 0] - d.positions[0, 0])
    moved[:, 1] = -moved[:, 1] + 0.3
    again = Demonstration.create(d.t * 1.7, moved, d.orientations, name="again")
    r = recognise(lib, again)
    assert r.best == "pick_place" and r.matched and r.similarity > 0.95
    # A rotation through a different angle is still the rotation skill.
    r2 = recognise(lib, rotation_demo(0.7))
    assert r2.best == "rotate_z" and r2.matched
    # A circle in the plane matches nothing.
    t = np.linspace(0, 2, 500)
    circle = np.stack((0.1 * np.cos(np.pi * t), 0.1 * np.sin(np.pi * t), 0 * t), axis=1)
    r3 = recognise(lib, Demonstration.create(t, circle, np.tile(quat.IDENTITY, (500, 1))))
    assert not r3.matched and r3.similarity < 0.9


def test_labels_are_identifiers_beside_the_action_kind(tmp_path: Path) -> None:
    lib = small_library()
    assert [s.label for s in lib] == ["transport", "rotate_z", "hold_lateral"]
    wave = learnt_skill(
        "wave_1",
        Action.TRANSPORT,
        Space.ABSOLUTE,
        lib.get("pick_place").pose_model(),
        (),
        WHEN,
        label="my_wave",
    )
    lib.add(wave)
    assert lib.named("my_wave").name == "wave_1"
    assert lib.named("wave_1") is lib.get("wave_1")
    assert lib.named("transport").name == "pick_place"  # the first so labelled
    with pytest.raises(
        KeyError, match=r"skill .wavy.: expected the name or label of one of the library.s skills"
    ):
        lib.named("wavy")
    with pytest.raises(
        KeyError, match=r"one of the library.s relative skills \(names: hold; labels"
    ):
        lib.named("my_wave", Space.RELATIVE)
    with pytest.raises(ValueError, match=r"skill label: expected an identifier.*got '2wave'"):
        learnt_skill("w", Action.TRANSPORT, Space.ABSOLUTE, wave.pose_model(), (), WHEN, "2wave")
    lib.save(tmp_path / "lib")
    back = SkillLibrary.load(tmp_path / "lib")
    assert back.named("my_wave").name == "wave_1" and back.describe() == lib.describe()


def test_a_version_1_library_loads_with_its_actions_as_labels(tmp_path: Path) -> None:
    folder = _corrupt(
        tmp_path, lambda m: [m.update(version=1), *(s.pop("label") for s in m["skills"])]
    )
    back = SkillLibrary.load(folder)
    assert [s.label for s in back] == ["transport", "rotate_z", "hold_lateral"]
    bad = _corrupt(tmp_path / "b", lambda m: m["skills"][0].update(label="my wave"))
    with pytest.raises(LibraryFileError, match=r"skills\[0\]\.label: expected an identifier"):
        SkillLibrary.load(bad)
    old = _corrupt(tmp_path / "c", lambda m: m.update(version=1))
    with pytest.raises(LibraryFileError, match=r"skills\[0\]\.label: expected a known key"):
        SkillLibrary.load(old)

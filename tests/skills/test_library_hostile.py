"""Hostile skill libraries (issue 15, item 11): every stored number held to what it can mean."""

from __future__ import annotations

import errno
import json
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from skills.library import LibraryFileError, SkillLibrary
from skills.skill import SkillKind, model_from_data
from skills.skill_data import SkillDataError, check_skill_data
from tests.skills.test_library import small_library


@pytest.fixture(scope="module")
def saved(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("lib") / "lib"
    small_library().save(folder)
    return folder


def _copy(saved: Path, tmp_path: Path) -> Path:
    target = tmp_path / "lib"
    target.mkdir()
    for f in saved.iterdir():
        (target / f.name).write_bytes(f.read_bytes())
    return target


def _edit_meta(folder: Path, edit: Callable[[dict[str, Any]], None]) -> None:
    path = folder / "library.json"
    meta = json.loads(path.read_text())
    edit(meta)
    path.write_text(json.dumps(meta))


def _edit_array(folder: Path, key: str, value: Any) -> None:
    with np.load(folder / "arrays.npz") as npz:
        arrays = {k: npz[k] for k in npz.files}
    arrays[key] = value
    with open(folder / "arrays.npz", "wb") as fh:
        np.savez(fh, **arrays)


def _set_param(index: int, key: str, value: Any) -> Callable[[dict[str, Any]], None]:
    return lambda m: m["skills"][index]["params"].update({key: value})


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (_set_param(0, "alpha", 1e308), r"skills\[0\]\.params\.alpha: expected a number in \(0, "),
        (_set_param(0, "alpha", float("nan")), r"skills\[0\]\.params\.alpha: .*got nan"),
        (_set_param(1, "demo_tau", 0), r"skills\[1\]\.params\.demo_tau: expected a number in"),
        (_set_param(0, "n_basis", 2.5), r"params\.n_basis: expected an integer in \[1, 10000\]"),
        (_set_param(0, "alpha", "fast"), r"params\.alpha: expected a number .*got 'fast'"),
        (_set_param(2, "stiffness", 10**400), r"params\.stiffness: .*\(401 characters\)"),
        (_set_param(2, "squeeze_force_n", 0), r"params\.squeeze_force_n: expected a number in \(0"),
        (_set_param(0, "position_scaling", "huge"), r"position_scaling: expected one of none"),
        (lambda m: m["skills"][0]["params"].pop("demo_tau"), r"demo_tau: .*nothing \(missing\)"),
        (lambda m: m.update(skills=[]), r"skills: expected at least one skill, got an empty list"),
        (
            lambda m: m["skills"][0]["provenance"].update(demonstrations=[3]),
            r"provenance\.demonstrations\[0\]: expected a file name, got 3",
        ),
        (
            lambda m: m["skills"][0]["provenance"].update(fit={"rms_m": "small"}),
            r"provenance\.fit\.rms_m: expected a finite number, got 'small'",
        ),
    ],
)
def test_bad_parameters_name_the_skill_and_field(
    saved: Path, tmp_path: Path, edit: Callable[[dict[str, Any]], None], match: str
) -> None:
    folder = _copy(saved, tmp_path)
    _edit_meta(folder, edit)
    with pytest.raises(LibraryFileError, match=match):
        SkillLibrary.load(folder)


@pytest.mark.parametrize(
    ("key", "value", "match"),
    [
        (
            "pick_place/position_weights",
            np.full((50, 3), np.nan),
            r"arrays\.npz: pick_place/position_weights: expected finite numbers, got nan",
        ),
        (
            "rotate_z/demo_goal_orientation",
            np.array([0.0, 0.0, 0.0, 2.0]),
            r"rotate_z/demo_goal_orientation: expected entries in",
        ),
        (
            "rotate_z/demo_start_orientation",
            np.array([0.0, 0.0, 0.5, 0.5]),
            r"demo_start_orientation: expected a unit quaternion, got norm 0\.707",
        ),
        ("pick_place/widths", -np.ones(50), r"pick_place/widths: expected entries in \(0, "),
        ("pick_place/centres", np.ones(7), r"pick_place/centres: expected shape \(50,\)"),
        (
            "pick_place/demo_goal_position",
            np.array([1e302, 0.0, 0.0]),
            r"demo_goal_position: expected entries in \[-100, 100\] m, got 1e\+302",
        ),
        ("pick_place/centres", np.array(["a"] * 50), r"centres: expected a numeric array"),
    ],
)
def test_bad_arrays_name_the_archive_and_key(
    saved: Path, tmp_path: Path, key: str, value: Any, match: str
) -> None:
    folder = _copy(saved, tmp_path)
    _edit_array(folder, key, value)
    with pytest.raises(LibraryFileError, match=match):
        SkillLibrary.load(folder)


def test_unreadable_files_are_one_clear_error(saved: Path, tmp_path: Path) -> None:
    folder = _copy(saved, tmp_path)
    (folder / "library.json").unlink()
    (folder / "library.json").mkdir()
    with pytest.raises(
        LibraryFileError, match=r"library\.json: expected a library\.json file, got a folder"
    ):
        SkillLibrary.load(folder)
    (folder / "library.json").rmdir()
    (folder / "library.json").write_bytes(b'{"format": "\xff"}')
    with pytest.raises(LibraryFileError, match=r"expected UTF-8 text, got byte 0xff at offset 12"):
        SkillLibrary.load(folder)
    (folder / "library.json").write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(LibraryFileError, match="expected JSON nested to a sane depth"):
        SkillLibrary.load(folder)
    (folder / "library.json").write_text('{"format": 1, "format": 2}')
    with pytest.raises(LibraryFileError, match=r"expected a key given once, got 'format' twice"):
        SkillLibrary.load(folder)
    with open(folder / "arrays.npz", "wb") as fh:
        np.save(fh, np.zeros(3))  # a .npy under the archive's name
    (folder / "library.json").write_bytes((saved / "library.json").read_bytes())
    with pytest.raises(LibraryFileError, match=r"arrays\.npz: expected an NPZ archive"):
        SkillLibrary.load(folder)
    with pytest.raises(LibraryFileError, match="expected a skill library folder, got a file"):
        SkillLibrary.load(folder / "library.json")


def test_a_failed_save_leaves_the_old_library_whole(
    saved: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    folder = _copy(saved, tmp_path)
    before = {f.name: f.read_bytes() for f in folder.iterdir()}

    def full(*args: object, **kwargs: object) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(np, "savez", full)
    with pytest.raises(OSError, match="No space left"):
        small_library().save(folder)
    assert {f.name: f.read_bytes() for f in folder.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["lib"]


def test_adding_a_skill_checks_its_data() -> None:
    lib = small_library()
    bad = next(iter(lib))
    params = dict(bad.params, alpha=-1.0)
    with pytest.raises(SkillDataError, match=r"params\.alpha: expected a number in \(0, 10000\]"):
        check_skill_data(bad.kind, params, bad.arrays)


_NUMBERS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(10**400), max_value=10**400),
    st.sampled_from([0, -1, 1e-300, 1e308, "x", True, None]),
)
_ARRAY_KEYS = (
    "position_weights",
    "widths",
    "centres",
    "demo_start_orientation",
    "demo_goal_position",
)


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    key=st.sampled_from(_ARRAY_KEYS),
    scale=st.floats(allow_nan=True, allow_infinity=True),
    shape_change=st.integers(min_value=-2, max_value=2),
    param=st.sampled_from(("alpha", "alpha_s", "n_basis", "overlap", "demo_tau", "min_amplitude")),
    value=_NUMBERS,
)
def test_fuzzed_arrays_and_parameters_load_or_raise_library_file_error(
    saved: Path, key: str, scale: float, shape_change: int, param: str, value: Any
) -> None:
    """Whatever the arrays and parameters hold, a load gives a library or a LibraryFileError."""
    lib = SkillLibrary.load(saved)
    skill = lib.get("pick_place")
    arrays = dict(skill.arrays)
    base = np.asarray(arrays[key], float)
    n = max(base.shape[0] + shape_change, 0)
    with np.errstate(all="ignore"):
        arrays[key] = np.resize(base, (n, *base.shape[1:])) * scale
    params = dict(skill.params)
    params[param] = value
    try:
        check_skill_data(SkillKind.LEARNT_DMP, params, arrays)
    except SkillDataError as err:
        assert err.field.startswith(("params.", "arrays.")) and "expected" in str(err)
        return
    # Whatever passes is usable: a model builds and its numbers are finite.
    model = model_from_data(params, arrays)
    assert np.all(np.isfinite(model.position.forcing.weights))


_ARRAYS = st.one_of(
    st.lists(st.floats(allow_nan=True, allow_infinity=True, width=64), max_size=200).map(
        np.array
    ),
    st.sampled_from(
        [np.zeros((0,)), np.zeros((50, 3, 1)), np.array(["x"]), np.array([True] * 50),
         np.full(50, 1e300), np.arange(150).reshape(50, 3)]
    ),
)  # fmt: skip


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    key=st.sampled_from([f"pick_place/{k}" for k in _ARRAY_KEYS] + ["hold/reference_object"]),
    value=_ARRAYS,
)
def test_fuzzed_library_files_load_or_raise_library_file_error(
    saved: Path, key: str, value: Any
) -> None:
    """An arrays.npz holding anything under a skill's key: a library, or one clear error."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "lib"
        folder.mkdir()
        for f in saved.iterdir():
            (folder / f.name).write_bytes(f.read_bytes())
        _edit_array(folder, key, value)
        try:
            lib = SkillLibrary.load(folder)
        except LibraryFileError as err:
            assert "arrays.npz" in str(err) and "expected" in str(err)
            return
        for skill in lib:
            assert all(np.all(np.isfinite(a)) for a in skill.arrays.values())

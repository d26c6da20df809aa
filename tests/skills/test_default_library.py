"""The default library: learnt from the shipped demonstrations, deterministically."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from skills import file_cache
from skills.default_library import (
    build_default_library,
    default_library,
    default_library_key,
    fit_grasp_maintenance,
)
from skills.demos.generate import TEACHER_DAMPING, TEACHER_STIFFNESS, write_all
from skills.demos.io import DemoFileError, read_demo_csv, write_demo_csv
from skills.library import SkillLibrary
from skills.skill import SkillKind
from skills.vocabulary import Action, Space

DEMOS = Path(__file__).resolve().parents[2] / "skills" / "demos"


def test_generator_reproduces_the_shipped_files(tmp_path: Path) -> None:
    for path in write_all(tmp_path):
        assert path.read_bytes() == (DEMOS / path.name).read_bytes(), path.name


def test_library_has_the_papers_primitives_and_link_avoidance() -> None:
    lib = build_default_library()
    assert lib.first(Action.TRANSPORT).kind is SkillKind.LEARNT_DMP
    assert lib.first(Action.ROTATE_Z).kind is SkillKind.LEARNT_DMP
    assert lib.first(Action.AVOID_OBSTACLE).kind is SkillKind.OBSTACLE_STEERING
    assert lib.first(Action.AVOID_LINKS).kind is SkillKind.POTENTIAL_FIELD
    hold = lib.first(Action.HOLD_LATERAL)
    assert hold.space is Space.RELATIVE and hold.kind is SkillKind.GRASP_MAINTENANCE
    assert all(s.provenance.learnt_at for s in lib)


def test_build_is_deterministic() -> None:
    a, b = build_default_library(), build_default_library()
    assert a.describe() == b.describe()
    for s in a:
        assert dict(s.params) == dict(b.get(s.name).params)
        for k, v in s.arrays.items():
            np.testing.assert_array_equal(v, b.get(s.name).arrays[k])


def test_grasp_maintenance_fit_recovers_the_teachers_spring() -> None:
    g = fit_grasp_maintenance(read_demo_csv(DEMOS / "grasp_maintenance.csv"))
    assert g.stiffness == pytest.approx(TEACHER_STIFFNESS, rel=0.15)
    assert g.damping == pytest.approx(TEACHER_DAMPING, rel=0.15)
    assert g.squeeze_force_n == pytest.approx(12.0, abs=0.5)
    assert g.relative_residual < 0.3


def test_demo_csv_errors_name_file_row_and_column(tmp_path: Path) -> None:
    bad = tmp_path / "bad.csv"
    bad.write_text("t,x,y,z,qx,qy,qz,qw\n0,0,0,0,0,0,0,1\n0.1,0,zero,0,0,0,0,1\n")
    with pytest.raises(DemoFileError, match=r"bad.csv:3: column y: expected a number, got 'zero'"):
        read_demo_csv(bad)
    bad.write_text("t,x,y,z,qx,qy,qw\n")
    with pytest.raises(DemoFileError, match=r"header: expected columns .* missing qz"):
        read_demo_csv(bad)
    with pytest.raises(DemoFileError, match="expected a demonstration CSV file, got no such"):
        read_demo_csv(tmp_path / "missing.csv")
    t = np.linspace(0, 1, 10)
    path = write_demo_csv(
        tmp_path / "ok.csv", t, np.zeros((10, 3)), np.tile([0, 0, 0, 1.0], (10, 1))
    )
    back = read_demo_csv(path)
    np.testing.assert_allclose(back.demonstration.t, t, atol=1e-9)
    with pytest.raises(DemoFileError, match="expected columns force for this skill"):
        fit_grasp_maintenance(back)


def _assert_same_library(a: SkillLibrary, b: SkillLibrary) -> None:
    """Every skill field equal, every array with the same dtype, shape and bytes."""
    assert a.names() == b.names()
    for s in a:
        t = b.get(s.name)
        assert (s.label, s.action, s.space, s.kind, s.elements, s.provenance) == (
            t.label,
            t.action,
            t.space,
            t.kind,
            t.elements,
            t.provenance,
        )
        assert dict(s.params) == dict(t.params)
        assert {k: type(v) for k, v in s.params.items()} == {
            k: type(v) for k, v in t.params.items()
        }
        assert sorted(s.arrays) == sorted(t.arrays)
        for k, v in s.arrays.items():
            w = t.arrays[k]
            assert (v.dtype, v.shape, v.tobytes()) == (w.dtype, w.shape, w.tobytes()), k


def test_the_cached_library_is_the_learnt_one_bit_for_bit(tmp_path: Path) -> None:
    learnt = build_default_library()
    first = default_library(cache_dir=tmp_path)  # learns it and writes the entry
    (entry,) = tmp_path.iterdir()
    assert entry.name == f"default_library_{default_library_key()}.bin"
    written = entry.stat().st_mtime_ns
    second = default_library(cache_dir=tmp_path)  # reads it back
    assert entry.stat().st_mtime_ns == written
    _assert_same_library(learnt, first)
    _assert_same_library(learnt, second)


def test_a_damaged_cached_library_is_learnt_again(tmp_path: Path) -> None:
    default_library(cache_dir=tmp_path)
    (entry,) = tmp_path.iterdir()
    data = bytearray(entry.read_bytes())
    data[-20] ^= 0xFF  # inside arrays.npz
    entry.write_bytes(bytes(data))
    _assert_same_library(build_default_library(), default_library(cache_dir=tmp_path))
    assert file_cache.read_entry(entry) is not None  # written again, whole


def test_a_changed_demonstration_names_another_library(tmp_path: Path) -> None:
    demos = tmp_path / "demos"
    demos.mkdir()
    for path in DEMOS.glob("*.csv"):
        (demos / path.name).write_bytes(path.read_bytes())
    assert default_library_key(demos) == default_library_key()
    pick = demos / "pick_place.csv"
    pick.write_bytes(pick.read_bytes() + b"\n")  # one more byte
    assert default_library_key(demos) != default_library_key()


def test_a_library_learnt_on_another_blas_kernel_is_cached_apart(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # A library learnt by a process that had not pinned OpenBLAS's kernel (its last bits
    # differ) had been cached under the pinned runs' name: trial 352 of the default world's
    # campaign then ran differently, whatever its own process pinned.
    pinned = default_library_key()
    monkeypatch.setenv("OPENBLAS_CORETYPE", "Haswell")
    haswell = default_library_key()
    assert haswell != pinned
    monkeypatch.setenv("OPENBLAS_CORETYPE", "Haswell")
    assert default_library_key() == haswell  # a name of its content, as any other

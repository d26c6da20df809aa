"""The default library: learnt from the shipped demonstrations, deterministically."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from skills.default_library import build_default_library, fit_grasp_maintenance
from skills.demos.generate import TEACHER_DAMPING, TEACHER_STIFFNESS, write_all
from skills.demos.io import DemoFileError, read_demo_csv, write_demo_csv
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

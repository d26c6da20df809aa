"""The learnt insertion skill reproduces its demonstration; its coupling is the teacher's."""

from __future__ import annotations

import numpy as np
from numpy.testing import assert_allclose

from skills.default_library import DEMOS_DIR, build_default_library
from skills.demos.insertion import TEACHER_CENTRING, TEACHER_COMPLIANCE
from skills.demos.io import columns, read_demo_csv
from skills.insertion import AdmittanceGains, admittance_step, descent_rate, shift_velocity
from skills.insertion_fit import fit_insertion
from skills.pose_dmp import PoseState, pose_rollout
from skills.vocabulary import Action, AffordanceElement, Space


def test_insert_skill_reproduces_the_teachers_descent_within_1_mm() -> None:
    demo_file = read_demo_csv(DEMOS_DIR / "insertion.csv")
    demo = demo_file.demonstration
    plan = columns(demo_file, ["bx", "by", "bz"])
    skill = build_default_library().first(Action.INSERT, Space.ABSOLUTE)
    assert AffordanceElement.IN_FIXTURE in skill.elements
    model = skill.pose_model()
    q = demo.orientations
    assert q is not None
    target = model.target(plan[0], q[0], plan[-1], q[-1])
    traj = pose_rollout(model, target, PoseState.at_rest(plan[0], q[0]), demo.t[1], len(demo.t) - 1)
    # Bound: 1 mm along the whole 6 cm descent (50 basis functions, a smooth plan).
    assert np.max(np.linalg.norm(traj.positions - plan, axis=1)) < 1e-3


def test_fit_recovers_the_teachers_admittance_within_5_percent() -> None:
    fit = fit_insertion(read_demo_csv(DEMOS_DIR / "insertion.csv"))
    assert_allclose(fit.gains.compliance, TEACHER_COMPLIANCE, rtol=0.05)
    assert_allclose(fit.gains.centring, TEACHER_CENTRING, rtol=0.05)
    assert fit.contact_samples > 50
    assert fit.relative_residual < 0.2


def test_the_coupling_yields_to_a_wall_and_stops_the_descent_above_the_bound() -> None:
    gains = AdmittanceGains(1e-3, 0.3, 5.0, 15.0)
    # A wall pushing the box towards -y: the targets shift towards -y, away from it.
    v = shift_velocity(np.array([0.0, -10.0, 0.0]), np.zeros(2), gains)
    assert_allclose(v, [0.0, -0.01])
    assert_allclose(descent_rate([0.0, 5.0, 10.0, 15.0, 30.0], gains), [1, 1, 0.5, 0, 0])
    # The sideways speed is capped.
    assert_allclose(np.linalg.norm(shift_velocity([0.0, 100.0, 0.0], [0.0, 0.0], gains)), 0.02)
    offset, rate = admittance_step(np.zeros(2), np.array([0.0, 0.0, 20.0]), [0.01, 0.0], gains, 0.1)
    assert rate == 0.0
    assert_allclose(offset, [3e-4, 0.0])

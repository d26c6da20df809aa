"""The level carry: its bound on acceleration, and the learnt skill against its demonstration."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from skills import quaternion as quat
from skills.default_library import DEMOS_DIR, default_library
from skills.demos.io import read_demo_csv
from skills.level_carry import (
    MIN_JERK_PEAK,
    LooseBall,
    level_carry_tau,
    max_carry_acceleration,
)
from skills.pose_dmp import PoseState, pose_rollout

G = 9.81


def test_a_rim_above_the_radius_leaves_the_energy_bound() -> None:
    ball = LooseBall(radius_m=0.025, rim_m=0.05, room_m=0.25)
    # g h / room on a level tray: 9.81 * 0.05 / 0.25
    assert_allclose(max_carry_acceleration(ball, 0.0, G), G * 0.2, rtol=1e-12)
    # tilted: (g h / room - g sin t) / cos t
    t = math.radians(5.0)
    assert_allclose(
        max_carry_acceleration(ball, t, G), (G * 0.2 - G * math.sin(t)) / math.cos(t), rtol=1e-12
    )


def test_a_rim_below_the_radius_is_bounded_by_the_lean_over_its_edge() -> None:
    # h = r/2: cos(alpha) = 1/2, alpha 60 degrees; the energy bound (h / room = 2.5) is larger.
    ball = LooseBall(radius_m=0.02, rim_m=0.01, room_m=0.004)
    assert_allclose(max_carry_acceleration(ball, 0.0, G), G * math.tan(math.radians(60)))


def test_a_tilt_that_alone_loses_the_ball_allows_no_acceleration() -> None:
    ball = LooseBall(radius_m=0.02, rim_m=0.001, room_m=0.2)  # g h / room = 0.05 m/s^2
    assert max_carry_acceleration(ball, math.radians(5.0), G) == 0.0


def test_the_carry_duration_keeps_the_peak_acceleration_within_the_bound() -> None:
    tau = level_carry_tau(0.3, 0.5)
    crossing = 0.7 * tau  # skills.level_carry.CARRY_SHARE
    assert_allclose(MIN_JERK_PEAK * 0.3 / crossing**2, 0.5, rtol=1e-12)
    assert level_carry_tau(0.3, math.inf) == 0.0
    with pytest.raises(ValueError, match="max_acceleration > 0"):
        level_carry_tau(0.3, 0.0)
    with pytest.raises(ValueError, match="LooseBall"):
        LooseBall(0.0, 0.1, 0.1)


def test_the_learnt_level_carry_reproduces_its_demonstration() -> None:
    skill = default_library().get("level_carry")
    assert skill.label == "keep_level"
    demo = read_demo_csv(DEMOS_DIR / "level_carry.csv").demonstration
    t, p, q = demo.t, demo.positions, demo.orientations
    model = skill.pose_model()
    target = model.target(p[0], q[0], p[-1], q[-1])
    traj = pose_rollout(
        model, target, PoseState.at_rest(p[0], q[0]), float(t[1] - t[0]), len(t) - 1
    )
    # Bound: 3 mm along the way (50 basis functions for a 0.3 m carry with 0.75 mm tremor),
    # and level within 0.3 degrees (the teacher's wobble is 0.06 degrees).
    assert np.max(np.linalg.norm(traj.positions - p, axis=1)) < 3e-3
    assert np.max(np.degrees(quat.tilt(traj.orientations))) < 0.3
    # Slower and lower than the parcel's pick-and-place: a 6 cm lift over 4 s.
    assert_allclose(np.max(traj.positions[:, 2]) - p[0, 2], 0.06, atol=3e-3)

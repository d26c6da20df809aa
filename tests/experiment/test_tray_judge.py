"""The tray carry's criteria on cases whose answer is known (no physics)."""

from __future__ import annotations

import math

import numpy as np
from numpy.testing import assert_allclose

from experiment.tray import in_tray_frame, judge_tray, off_tray
from skills import quaternion as quat
from worlds.spec import ShapeSpec
from worlds.trays import TrayFrame

TRAY = TrayFrame.of(ShapeSpec.tray((0.24, 0.30, 0.15), 0.01, 0.01))
RADIUS = 0.025
N = 50


def _tilted(deg: float) -> np.ndarray:
    """N samples of a tray tilting from level to ``deg`` about x and back."""
    angles = np.radians(deg) * np.sin(np.linspace(0.0, math.pi, N))
    return quat.from_axis_angle(np.array([1.0, 0.0, 0.0]), angles)


def _ball_on(tray_p: np.ndarray, tray_q: np.ndarray, relative: np.ndarray) -> np.ndarray:
    return tray_p + quat.rotate(tray_q, relative)


def test_tray_inside() -> None:
    assert_allclose(TRAY.inner_half, (0.11, 0.14))
    assert_allclose((TRAY.floor_z, TRAY.rim_z), (-0.065, 0.075))


def test_a_tray_tilted_4_degrees_passes_and_6_fails() -> None:
    p = np.tile([0.6, 0.0, 0.7], (N, 1))
    rel = np.tile([0.02, -0.03, TRAY.floor_z + RADIUS], (N, 1))
    for deg, ok in ((4.0, True), (6.0, False)):
        q = _tilted(deg)
        v = judge_tray("tray", "ball", TRAY, RADIUS, p, q, _ball_on(p, q, rel))
        assert v.ok is ok, v.failure
        assert_allclose(v.peak_tilt_deg, deg, rtol=1e-3)
        assert v.off_samples == 0
        assert_allclose(v.max_excursion_m, math.hypot(0.02, 0.03), atol=1e-9)
    assert "tilted 6.0 deg > 5" in v.failure


def test_a_ball_path_that_leaves_by_one_sample_fails() -> None:
    p = np.linspace([0.5, 0.0, 0.7], [0.6, -0.15, 0.7], N)
    q = np.tile(quat.IDENTITY, (N, 1))
    rel = np.tile([0.0, 0.0, TRAY.floor_z + RADIUS], (N, 1))
    rel[:, 1] = np.linspace(0.0, 0.139, N)  # up to 1 mm short of the inner wall's face
    v = judge_tray("tray", "ball", TRAY, RADIUS, p, q, p + rel)
    assert v.ok and v.off_samples == 0
    rel[N // 2, 1] = 0.141  # one sample 1 mm beyond it
    v = judge_tray("tray", "ball", TRAY, RADIUS, p, q, p + rel)
    assert not v.ok and v.off_samples == 1
    assert f"from sample {N // 2}" in v.failure
    assert_allclose(v.max_excursion_m, 0.141)


def test_a_ball_above_the_rim_by_more_than_its_radius_is_off() -> None:
    rel = np.array([[0.0, 0.0, TRAY.rim_z + RADIUS - 1e-4], [0.0, 0.0, TRAY.rim_z + RADIUS + 1e-4]])
    assert off_tray(rel, TRAY, RADIUS).tolist() == [False, True]


def test_the_ball_is_judged_in_the_tray_frame() -> None:
    q = quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), math.pi / 2)
    # A tray turned 90 degrees: world +x is the tray's -y.
    rel = in_tray_frame([[1.0, 0.0, 0.0]], q[None], [[1.1, 0.0, 0.0]])
    assert_allclose(rel, [[0.0, -0.1, 0.0]], atol=1e-12)


def test_no_samples_is_a_failure_not_a_pass() -> None:
    v = judge_tray(
        "tray", "ball", TRAY, RADIUS, np.zeros((0, 3)), np.zeros((0, 4)), np.zeros((0, 3))
    )
    assert not v.ok

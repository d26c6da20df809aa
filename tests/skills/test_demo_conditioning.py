"""Recorded demonstrations: smoothed before learning, and the learnt skill checked against them."""

from __future__ import annotations

import numpy as np
import pytest

from skills import quaternion as quat
from skills.demo_conditioning import (
    MAX_SETTLE_DEG,
    MAX_SETTLE_M,
    end_speed,
    ends_moving,
    low_pass,
    reproduction,
)
from skills.demonstration import Demonstration
from skills.pose_model import PoseModel, fit_pose
from skills.scaling import Scaling


def lifted_carry(noise_m: float = 0.0, hz: float = 100.0, jitter: float = 0.0) -> Demonstration:
    """A 3 s carry 0.25 m along x, lifted 0.2 m and waved 4 cm in y, at rest at both ends, its
    samples off by ``noise_m`` (white, per axis) and its time stamps by ``jitter`` steps."""
    rng = np.random.default_rng(3)
    t = np.linspace(0.0, 3.0, int(3.0 * hz) + 1)
    t[1:-1] += jitter / hz * rng.uniform(-0.5, 0.5, t.size - 2)
    s = 0.5 - 0.5 * np.cos(np.pi * t / 3.0)
    p = np.column_stack(
        (0.5 + 0.25 * s, 0.04 * np.sin(2 * np.pi * s), 0.7 + 0.2 * np.sin(np.pi * s))
    )
    p += noise_m * rng.standard_normal(p.shape)
    return Demonstration.create(t, p, np.tile(quat.IDENTITY, (t.size, 1)), "carry")


def learnt(demo: Demonstration) -> PoseModel:
    return fit_pose(demo, position_scaling=Scaling.ROTATION_Z, orientation_scaling=Scaling.NONE)


def test_a_clean_demonstration_is_kept_where_it_was() -> None:
    clean = lifted_carry()
    smooth = low_pass(clean)
    # Curvature is flattened a little (0.2 m of lift over 3 s), the resting ends hardly.
    assert np.max(np.abs(smooth.positions - clean.positions)) < 5e-4
    np.testing.assert_allclose(smooth.positions[[0, -1]], clean.positions[[0, -1]], atol=2e-4)
    assert low_pass(clean, 0.0) is clean
    with pytest.raises(ValueError, match="smoothing: expected a duration >= 0 s"):
        low_pass(clean, -0.01)


def test_uneven_time_stamps_are_smoothed_by_time_not_by_index() -> None:
    clean, jittered = lifted_carry(), lifted_carry(jitter=0.8)
    truth = np.column_stack(
        [np.interp(jittered.t, clean.t, clean.positions[:, k]) for k in range(3)]
    )
    assert np.max(np.abs(low_pass(jittered).positions - truth)) < 1e-3


def test_noise_in_the_samples_is_what_throws_a_learnt_skill_off_its_goal() -> None:
    # 0.5 mm of noise at 100 Hz, differentiated twice, is about 20 m/s^2 of forcing to fit.
    noisy = lifted_carry(noise_m=5e-4)
    raw = reproduction(learnt(noisy), noisy)
    assert raw.settle_m > 0.2  # it plunged a metre past its duration
    assert not raw.settles
    smooth = low_pass(noisy)
    shown = reproduction(learnt(smooth), smooth)
    assert shown.settles and shown.settle_m < MAX_SETTLE_M
    assert shown.rms_m < 2e-3
    clean = lifted_carry()
    assert np.sqrt(np.mean((smooth.positions - clean.positions) ** 2)) < 3e-4


def test_orientations_are_smoothed_as_unit_quaternions() -> None:
    # A 60 degree turn recorded with 0.17 degrees of noise per sample: learnt as recorded it
    # ends half a turn from its goal; smoothed, within a few degrees.
    rng = np.random.default_rng(5)
    clean = lifted_carry()
    yaw = np.radians(60.0) * (0.5 - 0.5 * np.cos(np.pi * clean.t / 3.0))
    q = quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), yaw)
    noise = quat.from_rotation_vector(0.003 * rng.standard_normal((q.shape[0], 3)))
    demo = Demonstration.create(clean.t, clean.positions, quat.multiply(q, noise), "turn")
    assert reproduction(learnt(demo), demo).settle_deg > 30.0
    smooth = low_pass(demo)
    assert smooth.orientations is not None
    np.testing.assert_allclose(np.linalg.norm(smooth.orientations, axis=1), 1.0, atol=1e-12)
    before = np.degrees(quat.angle_between(demo.orientations, q))
    after = np.degrees(quat.angle_between(smooth.orientations, q))
    assert np.sqrt(np.mean(after**2)) < 0.3 * np.sqrt(np.mean(before**2))
    shown = reproduction(learnt(smooth), smooth)
    assert shown.settles and shown.settle_deg < MAX_SETTLE_DEG


def test_a_recording_cut_before_the_motion_stopped_is_told_from_a_noisy_one() -> None:
    # The end's speed is its last 5 %'s mean: a sample's own speed had been the noise's, and
    # 2 mm of noise had been taken for a cut (0.032 of 0.237 m/s, "record until the motion
    # has stopped").
    for noise in (0.0, 5e-4, 2e-3):
        smooth = low_pass(lifted_carry(noise_m=noise))
        final, peak = end_speed(smooth)
        assert final < 0.05 < 0.2 < peak
        assert not ends_moving(smooth)
    whole = lifted_carry()
    for rows in (151, 261):  # cut at its fastest, and at 2.6 s of 3
        cut = low_pass(Demonstration.create(whole.t[:rows], whole.positions[:rows], None, "cut"))
        final, peak = end_speed(cut)
        assert final > 0.6 * peak and ends_moving(cut)


def test_smoothing_a_long_fast_recording_takes_memory_as_its_length_not_its_rate_squared(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # Every sample's window at once had taken N x (rate x 8 sigma) x D floats: 3.2 GB for a
    # 20000-sample, 3 s recording; a faster logger would have been killed without a word.
    import tracemalloc

    import skills.demo_conditioning as conditioning

    t = np.linspace(0.0, 3.0, 20_000)
    values = np.stack([np.sin(t), np.cos(2.0 * t), t**2, t, -t, t * t * t, np.ones_like(t)], 1)
    tracemalloc.start()
    smooth = conditioning._gaussian_means(t, values, 0.04)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 300e6, peak
    # Block by block, bit for bit what all at once gives (a block of one sample here).
    monkeypatch.setattr(conditioning, "_BLOCK_VALUES", 1)
    short = slice(0, 400)
    whole = conditioning._gaussian_means(t[short], values[short], 0.04)
    monkeypatch.setattr(conditioning, "_BLOCK_VALUES", 1 << 40)
    assert np.array_equal(whole, conditioning._gaussian_means(t[short], values[short], 0.04))
    middle = slice(2000, -2000)  # beyond 4 sigma of the held ends
    assert np.allclose(smooth[middle, :2], values[middle, :2], atol=5e-3)


def test_unevenly_stamped_samples_weigh_as_the_time_they_stand_for(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # A plain kernel mean leant towards where random stamps crowd: 4 mm off a 10 cm sine
    # (2.5 mm RMS in a taught skill where even stamps gave 0.5).
    import skills.demo_conditioning as conditioning

    rng = np.random.default_rng(3)
    t = np.sort(rng.uniform(0.0, 3.0, 301))
    t[0], t[-1] = 0.0, 3.0
    curve = 0.1 * np.sin(2.0 * t)[:, None]
    middle = (t > 0.3) & (t < 2.7)
    smooth = conditioning._gaussian_means(t, curve, 0.04)
    assert np.max(np.abs(smooth - curve)[middle]) < 1e-3
    monkeypatch.setattr(conditioning, "_EVEN_TOLERANCE", np.inf)  # as every stamp were even
    plain = conditioning._gaussian_means(t, curve, 0.04)
    assert np.max(np.abs(plain - curve)[middle]) > 3e-3

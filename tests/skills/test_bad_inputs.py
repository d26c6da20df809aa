"""Bad inputs raise ValueError naming the argument and what was expected."""

from __future__ import annotations

import numpy as np
import pytest

from skills.demonstration import Demonstration
from skills.dmp import DMPParams, fit_position
from skills.pose_dmp import PoseModel, PoseState, fit_pose
from tests.skills.conftest import pick_place_demo


def test_mismatched_lengths() -> None:
    with pytest.raises(ValueError, match=r"positions: expected shape \(10, D\) to match t"):
        Demonstration.create(np.arange(10.0), np.zeros((9, 3)))
    with pytest.raises(ValueError, match=r"orientations: expected shape \(10, 4\)"):
        Demonstration.create(np.arange(10.0), np.zeros((10, 3)), np.zeros((8, 4)))


def test_non_increasing_time() -> None:
    t = np.array([0.0, 0.1, 0.2, 0.2, 0.4])
    with pytest.raises(ValueError, match=r"t: expected times strictly increasing, got t\[3\]"):
        Demonstration.create(t, np.zeros((5, 3)))


def test_nan_in_positions_and_time() -> None:
    y = np.zeros((5, 3))
    y[2, 1] = np.nan
    says = r"positions: expected finite values, got nan at \[2, 1\] \(sample 2, y\)"
    with pytest.raises(ValueError, match=says):
        Demonstration.create(np.arange(5.0), y)
    with pytest.raises(ValueError, match=r"t: expected finite time stamps"):
        Demonstration.create([0.0, np.nan, 2.0], np.zeros((3, 3)))


def test_a_quaternion_that_is_not_unit_is_refused_naming_the_sample() -> None:
    # A zero one, one scaled by 2, a yaw in radians written into qz with qw = 1: each had been
    # normalised and learnt (the last as another angle than the one meant).
    q = np.tile([0.0, 0.0, 0.0, 1.0], (5, 1))
    q[3] = 0.0
    with pytest.raises(ValueError, match=r"got norm 0 at sample 3 \(1 of 5 samples off\)"):
        Demonstration.create(np.arange(5.0), np.zeros((5, 3)), q)
    q[3] = [0.0, 0.0, 0.0, 2.0]
    with pytest.raises(ValueError, match=r"orientations: expected unit quaternions .*norm 2 at"):
        Demonstration.create(np.arange(5.0), np.zeros((5, 3)), q)
    yaw = np.linspace(0.0, np.pi / 2, 5)
    angles = np.stack([np.zeros(5), np.zeros(5), yaw, np.ones(5)], axis=1)
    with pytest.raises(ValueError, match=r"at sample 1 \(4 of 5 samples off\)"):
        Demonstration.create(np.arange(5.0), np.zeros((5, 3)), angles)
    q[3] = [0.0, 0.0, 0.0, 1.004]  # a CSV's rounding is fine
    Demonstration.create(np.arange(5.0), np.zeros((5, 3)), q)
    q[2, 1] = np.nan
    with pytest.raises(ValueError, match=r"got nan at \[2, 1\] \(sample 2, y\)"):
        Demonstration.create(np.arange(5.0), np.zeros((5, 3)), q)


def test_fewer_samples_than_needed() -> None:
    with pytest.raises(ValueError, match="expected at least 3 samples"):
        Demonstration.create([0.0, 1.0], np.zeros((2, 3)))
    demo = Demonstration.create(np.linspace(0, 1, 20), np.zeros((20, 3)))
    with pytest.raises(ValueError, match="expected at least n_basis=50 samples"):
        fit_position(demo, DMPParams(n_basis=50))


def test_bad_params_and_targets() -> None:
    with pytest.raises(ValueError, match="alpha: expected a positive number"):
        DMPParams(alpha=-1.0)
    with pytest.raises(ValueError, match="n_basis: expected an integer >= 1"):
        DMPParams(n_basis=0)
    model = fit_pose(pick_place_demo(200))
    with pytest.raises(ValueError, match="tau: expected a positive duration"):
        model.target([0, 0, 0], [0, 0, 0, 1], [1, 0, 0], [0, 0, 0, 1], tau=0.0)
    with pytest.raises(ValueError, match="goal_orientation: expected a non-zero quaternion"):
        model.target([0, 0, 0], [0, 0, 0, 1], [1, 0, 0], [0, 0, 0, 0])
    with pytest.raises(ValueError, match="goal_position: expected 3 finite numbers"):
        PoseModel.still().target([0, 0, 0], [0, 0, 0, 1], [1, np.inf, 0], [0, 0, 0, 1])
    with pytest.raises(ValueError, match="position: expected 3 finite numbers"):
        PoseState.at_rest([0, 0])


def test_pose_fit_needs_orientations() -> None:
    demo = Demonstration.create(np.linspace(0, 1, 100), np.zeros((100, 3)), name="wave")
    with pytest.raises(ValueError, match="wave: orientations: expected"):
        fit_pose(demo)


def test_demonstrations_that_cannot_share_weights() -> None:
    a = pick_place_demo(200)
    flat = a.positions.copy()
    flat[:, 0] = flat[0, 0]  # no x displacement where the first demo has 0.4 m
    b = Demonstration.create(a.t, flat, a.orientations, name="flat")
    with pytest.raises(ValueError, match="flat: positions: its displacement"):
        fit_pose([a, b])

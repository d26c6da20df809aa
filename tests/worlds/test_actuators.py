"""The actuator model on known answers, and the controller applying it."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from worlds.actuators import ActuatorFaults, actuator_start, actuator_step, lag_gain

LIMIT = np.array([100.0, 50.0])


def _run(faults: ActuatorFaults, commanded: np.ndarray, dt: float) -> np.ndarray:
    """Applied torques (T, m) for commanded torques (T, m), one tick each."""
    gain = lag_gain(faults.lag_s, dt)
    state = actuator_start(commanded[0], faults)
    out = []
    for tau in commanded:
        state, applied = actuator_step(state, tau, faults, gain, LIMIT)
        out.append(applied)
    return np.array(out)


def _faults(**kwargs: Any) -> ActuatorFaults:
    values: dict[str, Any] = {"torque_scale": (1.0, 1.0), "torque_bias_nm": (0.0, 0.0)}
    values.update(kwargs)
    return ActuatorFaults(**values)


def test_a_step_through_the_lag_reaches_63_percent_after_the_time_constant() -> None:
    dt, lag = 0.001, 0.020
    commanded = np.zeros((60, 2))
    commanded[1:] = [10.0, -4.0]  # a step at tick 1
    applied = _run(_faults(lag_s=lag), commanded, dt)
    assert_array_equal(applied[0], [0.0, 0.0])
    # The torque applied over tick k is the lag's output at its end: 1 - exp(-k dt / lag) of
    # the step after k ticks of it, so 1 - 1/e after lag / dt = 20.
    ticks = np.arange(1, 60)
    expected = (1.0 - np.exp(-ticks * dt / lag))[:, None] * [10.0, -4.0]
    assert_allclose(applied[1:], expected, rtol=1e-12, atol=1e-12)
    assert_allclose(applied[20] / [10.0, -4.0], 1.0 - math.exp(-1.0), rtol=1e-12)


def test_latency_delays_by_exactly_its_ticks() -> None:
    rng = np.random.default_rng(5)
    commanded = rng.uniform(-40.0, 40.0, size=(30, 2))
    for ticks in (1, 3):
        applied = _run(_faults(latency_ticks=ticks), commanded, 0.004)
        assert_array_equal(applied[ticks:], commanded[:-ticks])
        # Before any older torque exists, tick 0's (held for ever at the start).
        assert_array_equal(applied[:ticks], np.repeat(commanded[:1], ticks, axis=0))
    assert_array_equal(_run(_faults(), commanded, 0.004), commanded)


def test_scale_and_bias_are_exact_and_the_limit_saturates() -> None:
    faults = _faults(torque_scale=(1.1, 0.9), torque_bias_nm=(-3.0, 1.5))
    commanded = np.array([[10.0, 20.0], [-7.0, 0.0], [95.0, -60.0]])
    applied = _run(faults, commanded, 0.004)
    assert_array_equal(applied[:2], np.array([1.1, 0.9]) * commanded[:2] + [-3.0, 1.5])
    assert_array_equal(applied[2], [100.0, -50.0])  # 101.5 and -52.5, held at the limits


def test_the_lag_gain_is_exact_for_a_held_input() -> None:
    assert lag_gain(0.0, 0.004) == 1.0
    assert_allclose(lag_gain(0.02, 0.004), 1.0 - math.exp(-0.2), rtol=1e-14)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"torque_scale": (1.0,)}, "of one equal, non-zero length, got 1 and 2"),
        ({"torque_scale": (0.0, 1.0)}, r"torque_scale finite and > 0, got \(0.0, 1.0\)"),
        ({"torque_bias_nm": (math.nan, 0.0)}, "torque_bias_nm finite"),
        ({"lag_s": -0.01}, "lag_s finite and >= 0, got -0.01"),
        ({"latency_ticks": -1}, "latency_ticks >= 0, got -1"),
        ({"latency_ticks": 1.5}, "latency_ticks an int, got 1.5"),
    ],
)
def test_bad_faults_are_refused(kwargs: dict[str, Any], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        _faults(**kwargs)


@pytest.mark.sim
def test_the_controller_applies_the_faults_and_nothing_without() -> None:
    from skills.vocabulary import ARMS
    from worlds.control import DualArmImpedanceController
    from worlds.scene import Scene
    from worlds.truth import PhysicalTruth

    def run(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
        computed, applied = [], []
        for _ in range(6):
            scene.step()
            computed.append(np.concatenate([scene.palm_state(a).joint_torques for a in ARMS]))
            applied.append(scene.controller.applied_torques())
        return np.array(computed), np.array(applied)

    with Scene() as plain:
        n = 2 * plain.controller.joint_count
        computed, applied = run(plain)
        assert_array_equal(applied, computed)
        with pytest.raises(ValueError, match=f"actuator faults for {n} joints, got 3"):
            DualArmImpedanceController(
                plain.robot,
                plain.robot_ids,
                plain.physics_dt,
                client=plain.client,
                faults=ActuatorFaults((1.0,) * 3, (0.0,) * 3),
            )
    scale = np.linspace(0.9, 1.1, n)
    bias = np.linspace(-0.5, 0.5, n)
    faults = ActuatorFaults(tuple(scale), tuple(bias), latency_ticks=1)
    with Scene(truth=PhysicalTruth(actuators=faults)) as late:
        late.controller.torque_loop = None  # the faults alone (the loop: test_torque_loop.py)
        computed, applied = run(late)
    # One tick late, scaled and biased: tick k applies what tick k - 1 computed.
    assert_allclose(applied[1:], scale * computed[:-1] + bias, rtol=0, atol=1e-12)
    assert_allclose(applied[0], scale * computed[0] + bias, rtol=0, atol=1e-12)

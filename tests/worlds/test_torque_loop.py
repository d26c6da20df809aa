"""The joint torque loop (worlds.actuators.TorqueLoop): integral action on each joint's sensed
torque, around actuators with scale, bias, lag and latency errors."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from worlds.actuators import (
    ActuatorFaults,
    TorqueLoop,
    actuator_start,
    actuator_step,
    lag_gain,
    torque_loop_start,
    torque_loop_step,
)

DT = 1.0 / 240.0
LIMIT = np.array([40.0, 40.0])


def _closed_loop(
    faults: ActuatorFaults, asked: np.ndarray, loop: TorqueLoop | None
) -> tuple[np.ndarray, np.ndarray]:
    """Ask for ``asked`` (ticks, m) through the loop (None: without) and the faulty actuators;
    the torques applied and the loop's integral, per tick."""
    gain = lag_gain(faults.lag_s, DT)
    actuators = None
    state = torque_loop_start(asked.shape[1])
    sensed = None
    applied, integral = [], []
    for want in asked:
        sent = want
        if loop is not None:
            state, sent = torque_loop_step(state, sensed, want, loop, DT, LIMIT)
        if actuators is None:
            actuators = actuator_start(sent, faults)
        actuators, sensed = actuator_step(actuators, sent, faults, gain, LIMIT)
        applied.append(sensed)
        integral.append(state.integral)
    return np.array(applied), np.array(integral)


def test_a_bias_and_a_scale_error_are_integrated_away() -> None:
    # 3 % of a 40 N m limit, and a motor 15 % weak, holding 10 N m (a gravity load).
    faults = ActuatorFaults((0.85, 1.15), (1.2, -1.2), lag_s=0.03, latency_ticks=1)
    asked = np.full((int(3.0 / DT), 2), 10.0)
    without, _ = _closed_loop(faults, asked, None)
    applied, _ = _closed_loop(faults, asked, TorqueLoop())
    assert_allclose(without[-1], [0.85 * 10 + 1.2, 1.15 * 10 - 1.2])
    # Within 1 % after 3 s (15 integral time constants), from 27 % and 3 % off without.
    assert_allclose(applied[-1], [10.0, 10.0], rtol=0.01)


def test_a_step_settles_without_ringing_at_the_worst_lag_and_scale() -> None:
    # The slowest, strongest actuator of the Hard ranges: 30 ms lag, a tick late, x1.15.
    faults = ActuatorFaults((1.15, 1.15), (1.2, 1.2), lag_s=0.03, latency_ticks=1)
    asked = np.zeros((int(4.0 / DT), 2))
    asked[int(1.0 / DT) :] = 5.0
    applied, _ = _closed_loop(faults, asked, TorqueLoop())
    after = applied[int(1.0 / DT) :, 0]
    error = after - 5.0
    # Settled: the last second within 0.5 % of the step; the error's sign changes at most
    # twice (a damped loop, not an oscillation); never beyond what the motor gives alone.
    assert np.abs(error[-240:]).max() < 0.025
    flips = np.count_nonzero(np.diff(np.sign(error[np.abs(error) > 0.05])))
    assert flips <= 2
    assert after.max() < 5.0 * 1.15 + 1.2


def test_the_proportional_part_shortens_the_lag_the_joint_sees() -> None:
    faults = ActuatorFaults((0.85, 0.85), (0.0, 0.0), lag_s=0.03, latency_ticks=1)
    asked = np.zeros((int(2.0 / DT), 2))
    asked[int(1.0 / DT) :] = 1.0

    def rise_ticks(loop: TorqueLoop) -> int:
        applied, _ = _closed_loop(faults, asked, loop)
        return int(np.argmax(applied[int(1.0 / DT) :, 0] >= 1.0 - np.exp(-1.0)))

    # 63 % of a step: 10 ticks (42 ms) through the integral alone, 6 (25 ms) at 0.5.
    assert rise_ticks(TorqueLoop(proportional=0.5)) <= 0.65 * rise_ticks(TorqueLoop())


def test_the_integral_stays_within_its_limit() -> None:
    # A motor at a tenth of its strength cannot give what is asked: the integral stops at
    # its limit instead of winding up.
    faults = ActuatorFaults((0.1, 0.1), (0.0, 0.0))
    asked = np.full((int(5.0 / DT), 2), 20.0)
    _, integral = _closed_loop(faults, asked, TorqueLoop(limit=0.25))
    assert_allclose(integral[-1], 0.25 * LIMIT)
    assert np.all(integral <= 0.25 * LIMIT + 1e-12)


def test_ideal_actuators_leave_the_loop_nothing_to_do() -> None:
    asked = np.sin(np.linspace(0.0, 20.0, 600))[:, None] * np.array([3.0, -7.0])
    faults = ActuatorFaults((1.0, 1.0), (0.0, 0.0))
    applied, integral = _closed_loop(faults, asked, TorqueLoop())
    assert_array_equal(integral, 0.0)
    assert_array_equal(applied, asked)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"integral_s": 0.0}, "integral_s"),
        ({"filter_s": -0.01}, "filter_s"),
        ({"limit": 1.5}, "limit"),
        ({"integral_s": float("nan")}, "integral_s"),
        ({"proportional": 1.0}, "proportional"),
        ({"proportional": -0.1}, "proportional"),
    ],
)
def test_bad_loops_are_refused(kwargs: dict[str, float], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        TorqueLoop(**kwargs)


@pytest.mark.sim
def test_in_physics_the_loop_holds_biased_palms_where_they_are_told() -> None:
    from skills.vocabulary import ARMS
    from worlds.scene import Scene
    from worlds.truth import PhysicalTruth

    def palm_error(loop: bool) -> float:
        with Scene() as probe:
            limits = np.array([d.max_torque for d in probe.robot.driven_joints()])
        # Every motor 3 % of its limit off, alternately up and down, and 10 % weak.
        signs = np.where(np.arange(len(limits)) % 2 == 0, 1.0, -1.0)
        faults = ActuatorFaults(
            tuple([0.9] * len(limits)),
            tuple(0.03 * limits * signs),
            lag_s=0.02,
            latency_ticks=1,
        )
        with Scene(truth=PhysicalTruth(actuators=faults)) as scene:
            if not loop:
                scene.controller.torque_loop = None
            targets = {a: scene.controller.command(a) for a in ARMS}
            scene.step(int(3.0 / scene.physics_dt))
            return max(
                float(np.linalg.norm(scene.palm_state(a).position - targets[a].position))
                for a in ARMS
            )

    without, with_loop = palm_error(False), palm_error(True)
    # The biased motors hold the palms centimetres off (49 mm when written); the loop brings
    # them to within 2 mm (0.1 mm).
    assert without > 0.01
    assert with_loop < 0.002


@pytest.mark.sim
def test_in_physics_the_icub_arms_settle_under_the_slowest_lag_only_with_their_loop() -> None:
    from skills.vocabulary import ARMS
    from worlds.impedance_values import PalmCommand
    from worlds.robots.icub import icub_model
    from worlds.scene import Scene
    from worlds.truth import PhysicalTruth
    from worlds.world_file import as_world_spec, load_world

    world = Path(__file__).resolve().parents[2] / "worlds" / "icub_parcel_pick_place.yaml"
    spec = as_world_spec(load_world(world)).scene

    def step_error(loop: TorqueLoop | None) -> float:
        with Scene(spec) as probe:
            n = len(probe.robot.driven_joints())
        faults = ActuatorFaults((1.0,) * n, (0.0,) * n, lag_s=0.03, latency_ticks=1)
        with Scene(spec, truth=PhysicalTruth(actuators=faults)) as scene:
            scene.controller.torque_loop = loop
            scene.step(120)
            targets = {}
            for arm in ARMS:
                held = scene.controller.command(arm)
                targets[arm] = held.position + np.array([0.0, 0.0, 0.03])
                scene.set_palm_command(arm, PalmCommand(targets[arm], held.quaternion))
            worst = 0.0
            for _ in range(2):  # the error over the second of the two seconds after the step
                scene.step(240)
                worst = max(
                    float(np.linalg.norm(scene.palm_state(a).position - targets[a])) for a in ARMS
                )
            return worst

    robot_loop = icub_model().torque_loop
    assert robot_loop is not None and robot_loop.proportional > 0.0
    # The integral alone leaves the palms about 1 cm off, still swinging (9.7 mm when
    # written); with the proportional part they settle to within 0.1 mm.
    assert step_error(replace(robot_loop, proportional=0.0)) > 0.005
    assert step_error(robot_loop) < 0.002


@pytest.mark.sim
@pytest.mark.parametrize("world", ["parcel_pick_place.yaml", "icub_parcel_pick_place.yaml"])
def test_in_physics_every_joint_comes_to_rest_after_a_step_under_the_slowest_lag(
    world: str,
) -> None:
    """Hard mode's slowest actuators (a 30 ms lag and a tick of latency) must not make any mode
    of the controlled arms grow: the iiwa's wrist roll on its angular spring (12 Hz) and the
    iCub's whole-body sway in the palms' null space (1.4 Hz) both grew before their gains were
    set for it, to joint rates of 0.15 and 0.27 rad/s rms four seconds after a 3 cm step of
    both palms."""
    import pybullet as pb

    from skills.vocabulary import ARMS
    from worlds.impedance_values import PalmCommand
    from worlds.scene import Scene
    from worlds.truth import PhysicalTruth
    from worlds.world_file import as_world_spec, load_world

    spec = as_world_spec(load_world(Path(__file__).resolve().parents[2] / "worlds" / world)).scene
    with Scene(spec) as probe:
        n = len(probe.robot.driven_joints())
    faults = ActuatorFaults((1.0,) * n, (0.0,) * n, lag_s=0.03, latency_ticks=1)
    with Scene(spec, truth=PhysicalTruth(actuators=faults)) as scene:
        scene.step(120)
        for arm in ARMS:
            held = scene.controller.command(arm)
            scene.set_palm_command(
                arm, PalmCommand(held.position + np.array([0.0, 0.0, 0.03]), held.quaternion)
            )
        scene.step(int(3.5 / scene.physics_dt))
        joints = [(scene.robot_ids[d.body], d.joint) for d in scene.robot.driven_joints()]
        rates = []
        for _ in range(int(0.5 / scene.physics_dt)):
            scene.step(1)
            rates.append(
                [pb.getJointState(b, j, physicsClientId=scene.client)[1] for b, j in joints]
            )
    # Every joint's rate over the last half second, rms: 0.0001 rad/s on both when written.
    assert np.sqrt(np.mean(np.square(rates), axis=0)).max() < 0.01

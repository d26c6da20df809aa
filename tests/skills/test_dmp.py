"""Positional, quaternion and pose DMPs: known answers of the maths."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from skills import quaternion as quat
from skills.couplings import LearntForcing
from skills.demonstration import Demonstration
from skills.dmp import (
    DMPParams,
    DMPState,
    PositionDMP,
    fit_position,
    position_rollout,
    second_order_filter,
)
from skills.interpreter import kernel_acceleration
from skills.pose_dmp import (
    PoseDMP,
    PoseModel,
    PoseState,
    fit_pose,
    pose_rollout,
    pose_step,
)
from skills.quaternion_dmp import fit_orientation
from skills.scaling import Scaling
from tests.skills.conftest import min_jerk, pick_place_demo

DT = 0.002


def test_reproduces_a_demonstration_within_one_millimetre(demo: Demonstration) -> None:
    model = fit_pose(demo)
    target = model.target(
        demo.positions[0], demo.orientations[0], demo.positions[-1], demo.orientations[-1]
    )
    start = PoseState.at_rest(demo.positions[0], demo.orientations[0])
    n = demo.n_samples - 1
    traj = pose_rollout(model, target, start, demo.duration / n, n)
    # Bound: 1 mm on a 0.45 m motion, 1 mrad on a 1.2 rad turn.
    assert np.max(np.linalg.norm(traj.positions - demo.positions, axis=1)) < 1e-3
    assert np.max(quat.angle_between(traj.orientations, demo.orientations)) < 1e-3


def test_positional_dmp_works_in_any_dimension() -> None:
    t = np.linspace(0, 1, 400)
    s = min_jerk(t)
    y = np.stack([s * k + np.sin(np.pi * t) ** 2 * 0.1 * k for k in range(1, 8)], axis=1)
    model = fit_position(Demonstration.create(t, y), DMPParams(n_basis=30))
    traj = position_rollout(model, DMPState.at_rest(y[0]), y[-1], 1.0, t[1], 399)
    assert traj.positions.shape == (400, 7)
    # Bound: 0.2 % of each dimension's travel (integration and finite-difference error).
    assert np.all(np.max(np.abs(traj.positions - y), axis=0) < 2e-3 * np.abs(y[-1] - y[0]))


def test_converges_to_random_goals_with_zero_final_velocity(demo: Demonstration) -> None:
    model = fit_pose(demo)
    rng = np.random.default_rng(0)
    for _ in range(20):
        goal = rng.uniform(-1.0, 1.0, 3)
        goal_q = quat.as_quaternions(rng.normal(size=4))
        start = PoseState.at_rest(demo.positions[0], demo.orientations[0])
        target = model.target(start.position, start.orientation, goal, goal_q)
        traj = pose_rollout(model, target, start, DT, int(3 * demo.duration / DT))
        assert np.linalg.norm(traj.positions[-1] - goal) < 1e-4
        assert np.linalg.norm(traj.velocities[-1]) < 1e-3
        assert quat.angle_between(traj.orientations[-1], goal_q) < 1e-4
        assert np.linalg.norm(traj.angular_velocities[-1]) < 1e-3


def test_amplitude_scaling_generalises_as_an_exact_affine_copy(demo: Demonstration) -> None:
    model = fit_position(demo)
    y0, g = demo.positions[0], demo.positions[-1]
    base = position_rollout(model, DMPState.at_rest(y0), g, dt=DT)
    new_y0 = np.array([0.1, 0.4, 0.65])
    scale = np.array([1.5, -0.7, 2.0])
    new_g = new_y0 + scale * (g - y0)
    moved = position_rollout(model, DMPState.at_rest(new_y0), new_g, dt=DT)
    # The DMP is linear: per-axis scaling of g - y0 scales the whole path about the start.
    # y and z start and end at one value in the demo, so their excursions are kept unscaled.
    still = np.abs(g - y0) < model.forcing.min_amplitude
    assert still.tolist() == [False, True, True]
    effective = np.where(still, 1.0, scale)
    assert_allclose(moved.positions, new_y0 + effective * (base.positions - y0), atol=1e-9)


def test_rotation_z_scaling_turns_the_horizontal_shape_and_keeps_the_lift() -> None:
    demo = pick_place_demo()
    model = fit_position(demo, scaling=Scaling.ROTATION_Z)
    y0, g = demo.positions[0], demo.positions[-1]
    base = position_rollout(model, DMPState.at_rest(y0), g, dt=DT)
    angle, k = 2.0, 0.6
    rot = np.array(
        [[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0], [0, 0, 1]]
    )
    m = rot @ np.diag([k, k, 1.0])
    new_y0 = np.array([0.6, 0.0, 0.7])
    new_g = new_y0 + m @ (g - y0)
    moved = position_rollout(model, DMPState.at_rest(new_y0), new_g, dt=DT)
    assert_allclose(moved.positions, new_y0 + (base.positions - y0) @ m.T, atol=1e-9)
    lift = base.positions[:, 2].max() - y0[2]
    assert moved.positions[:, 2].max() - new_y0[2] == pytest.approx(lift, abs=1e-9)


def test_amplitude_scaling_keeps_a_lift_whose_start_and_goal_share_a_height() -> None:
    t = np.linspace(0, 2, 800)
    s = min_jerk(t / 2)
    y = np.stack((0.3 * s, 0 * s, 0.1 * np.sin(np.pi * t / 2) ** 2), axis=1)
    model = fit_position(Demonstration.create(t, y))
    moved = position_rollout(model, DMPState.at_rest([0, 0, 0]), [0.6, 0, 0], dt=DT)
    assert moved.positions[:, 2].max() == pytest.approx(0.1, rel=0.02)


def _settling_time(t: np.ndarray, y: np.ndarray, goal: np.ndarray, y0: np.ndarray) -> float:
    err = np.linalg.norm(y - goal, axis=1) / np.linalg.norm(goal - y0)
    outside = np.flatnonzero(err > 0.01)
    return float(t[outside[-1] + 1])


def test_doubling_tau_doubles_the_duration(demo: Demonstration) -> None:
    model = fit_pose(demo)
    start = PoseState.at_rest(demo.positions[0], demo.orientations[0])
    times = []
    for tau in (1.5, 3.0):
        target = model.target(
            start.position, start.orientation, demo.positions[-1], demo.orientations[-1], tau
        )
        traj = pose_rollout(model, target, start, 0.0005, int(3 * tau / 0.0005))
        times.append(_settling_time(traj.t, traj.positions, demo.positions[-1], start.position))
    assert times[1] / times[0] == pytest.approx(2.0, rel=0.01)


def test_quaternion_norm_stays_unit_and_antipodal_goal_converges(demo: Demonstration) -> None:
    model = fit_pose(demo)
    start = PoseState.at_rest(demo.positions[0], demo.orientations[0])
    goal_q = -quat.as_quaternions([0.3, -0.5, 0.2, 0.7])  # w < 0: the "other" sign
    target = model.target(start.position, start.orientation, [0.2, 0.1, 0.9], goal_q)
    state = start
    norms, angles = [], []
    for _ in range(int(3 * demo.duration / DT)):  # closed-loop stepping
        state = pose_step(state, model, target, DT)
        norms.append(np.linalg.norm(state.orientation))
        angles.append(quat.angle_between(state.orientation, goal_q))
    assert np.max(np.abs(np.array(norms) - 1.0)) < 1e-9
    assert angles[-1] < 1e-4
    # It turned the short way: the angle to the goal never grew much past its start value
    # (the learnt forcing may bend the path a little; the long way would pass pi).
    assert np.max(angles) < quat.angle_between(start.orientation, goal_q) + 0.01


def test_orientation_only_dmp_reproduces_the_turn(demo: Demonstration) -> None:
    model = fit_orientation(demo)
    assert model.forcing.weights.shape == (50, 3)
    assert_allclose(model.demo_goal, demo.orientations[-1])


def test_fast_rollout_matches_stepping(demo: Demonstration) -> None:
    model = fit_pose(demo)
    start = PoseState.at_rest(demo.positions[0], demo.orientations[0])
    target = model.target(start.position, start.orientation, [0.9, 0.2, 0.75], quat.IDENTITY)
    fast = pose_rollout(model, target, start, DT, 600)
    state = start
    for i in range(1, 601):
        state = pose_step(state, model, target, DT)
        if i % 150 == 0:
            assert_allclose(state.position, fast.positions[i], atol=1e-12)
            assert_allclose(state.velocity, fast.velocities[i], atol=1e-11)
            assert_allclose(state.orientation, fast.orientations[i], atol=1e-12)
    assert len(fast.t) == len(fast.positions) == len(fast.orientations) == 601


def test_resuming_from_a_mid_motion_full_state_continues_exactly(demo: Demonstration) -> None:
    model = fit_pose(demo)
    start = PoseState.at_rest(demo.positions[0], demo.orientations[0])
    target = model.target(
        start.position, start.orientation, demo.positions[-1], demo.orientations[-1]
    )
    whole = pose_rollout(model, target, start, DT, 1000)
    mid = whole.state(400)
    rest = pose_rollout(model, target, mid, DT, 600)
    assert_allclose(rest.positions, whole.positions[400:], atol=1e-12)
    assert_allclose(rest.velocities, whole.velocities[400:], atol=1e-11)


def test_handover_to_a_new_skill_has_no_velocity_or_acceleration_jump(
    demo: Demonstration,
) -> None:
    model = fit_pose(demo)
    start = PoseState.at_rest(demo.positions[0], demo.orientations[0])
    first = PoseDMP.start(model, start, [0.8, 0.1, 0.8], quat.IDENTITY)
    for _ in range(500):
        first.step(DT)
    handed = first.state
    second = PoseDMP.start(model, handed, [0.4, -0.3, 0.75], [0, 0, 0.3826834, 0.9238795])
    nxt = second.step(DT)
    # Velocity changes by one step of acceleration; acceleration by a fraction of its size.
    assert (
        np.linalg.norm(nxt.velocity - handed.velocity)
        < np.linalg.norm(handed.acceleration) * DT * 1.05 + 1e-9
    )
    assert np.linalg.norm(nxt.acceleration - handed.acceleration) < 0.05 * max(
        1.0, np.linalg.norm(handed.acceleration)
    )
    # Without the blend the new skill's own acceleration differs a lot at the switch.
    raw = PoseDMP.start(model, handed, [0.4, -0.3, 0.75], quat.IDENTITY, blend_fraction=0.0)
    assert np.linalg.norm(raw.step(DT).acceleration - handed.acceleration) > 0.5


def test_goal_and_tau_can_change_while_running(demo: Demonstration) -> None:
    model = fit_pose(demo)
    start = PoseState.at_rest(demo.positions[0], demo.orientations[0])
    dmp = PoseDMP.start(model, start, demo.positions[-1], demo.orientations[-1])
    for _ in range(300):
        dmp.step(DT)
    dmp.set_goal([0.3, 0.3, 0.9])
    dmp.set_tau(1.0)
    for _ in range(3000):
        dmp.step(DT)
    assert np.linalg.norm(dmp.state.position - [0.3, 0.3, 0.9]) < 1e-4


@pytest.mark.parametrize("change", ["goal", "tau", "goal, unblended"])
def test_a_goal_or_tau_changed_while_running_keeps_the_acceleration_continuous(
    demo: Demonstration, change: str
) -> None:
    # The paper's full-state continuity (Sec. 3.3), as a new skill's start keeps it: a 2 cm
    # goal shift had stepped the acceleration by 0.2 m/s^2 in one step, ten times a step's
    # change before it.
    model = fit_pose(demo)
    start = PoseState.at_rest(demo.positions[0], demo.orientations[0])
    dmp = PoseDMP.start(model, start, demo.positions[-1], demo.orientations[-1])
    for _ in range(300):
        dmp.step(DT)
    before = dmp.state
    usual = np.linalg.norm(dmp.step(DT).acceleration - before.acceleration)
    before = dmp.state
    if change == "tau":
        dmp.set_tau(dmp.target.tau * 1.1)
    else:
        dmp.set_goal(
            demo.positions[-1] + [0.02, 0.0, 0.0], blend_fraction=0.0 if "un" in change else 0.1
        )
    jump = np.linalg.norm(dmp.step(DT).acceleration - before.acceleration)
    if "un" in change:
        assert jump > 5.0 * usual  # what the blend takes away
    else:
        assert jump < 2.0 * usual + 1e-9
    for _ in range(4000):
        dmp.step(DT)
    goal = demo.positions[-1] + ([0.02, 0.0, 0.0] if "goal" in change else 0.0)
    assert np.linalg.norm(dmp.state.position - goal) < 1e-4  # it still ends at the goal


def test_position_dmp_closed_loop_with_a_coupling() -> None:
    demo = pick_place_demo()
    model = fit_position(demo)
    dmp = PositionDMP.from_model(model, demo.positions[-1])
    dmp.couplings.append(lambda st: np.array([0.0, 0.0, -0.5]))  # a constant push down
    for _ in range(int(6 * demo.duration / DT)):
        dmp.step(DT)
    # Steady state: K (g - y) = 0.5  =>  offset 0.5 / K below the goal.
    k = model.params.alpha * model.params.beta / model.demo_tau**2
    assert dmp.state.position[2] == pytest.approx(demo.positions[-1, 2] - 0.5 / k, abs=1e-6)


def test_fitting_several_demonstrations_averages_them() -> None:
    a = pick_place_demo(800, 2.0)
    b = Demonstration.create(a.t * 1.5, a.positions * [1.0, 1.0, 1.0] + 0.2, a.orientations)
    m1 = fit_pose(a)
    m2 = fit_pose([a, b])
    # b is a translated, slower copy of a: same normalised forcing, so the same weights.
    assert_allclose(
        m2.position.forcing.weights,
        m1.position.forcing.weights,
        rtol=1e-3,
        atol=1e-3 * np.abs(m1.position.forcing.weights).max(),
    )


def test_amplitude_scaling_mirrors_and_stretches_every_axis() -> None:
    t = np.linspace(0, 2, 900)
    s = min_jerk(t / 2)
    bump = np.sin(np.pi * t / 2) ** 2
    y = np.stack((0.4 * s, 0.2 * s + 0.1 * bump, -0.1 * s + 0.15 * bump), axis=1)
    model = fit_position(Demonstration.create(t, y))
    base = position_rollout(model, DMPState.at_rest(y[0]), y[-1], dt=DT)
    scale = np.array([-1.0, 2.5, 0.5])
    new_y0 = np.array([0.2, -0.3, 0.8])
    moved = position_rollout(model, DMPState.at_rest(new_y0), new_y0 + scale * y[-1], dt=DT)
    assert_allclose(moved.positions, new_y0 + scale * base.positions, atol=1e-9)


def moving_state(rng: np.random.Generator) -> PoseState:
    """A random pose and twist mid-motion."""
    return PoseState(
        np.array([0.6, 0.0, 0.7]) + rng.normal(size=3) * 0.1,
        rng.normal(size=3) * 0.2,
        np.zeros(3),
        quat.as_quaternions(rng.normal(size=4)),
        rng.normal(size=3),
        np.zeros(3),
        float(rng.uniform(0.01, 1.0)),
    )


def test_learnt_forcing_is_the_model_forcing_scaled_for_the_running_target(
    demo: Demonstration,
) -> None:
    model = fit_pose(demo)
    goal_q = quat.from_axis_angle([0.0, 0.0, 1.0], 0.8)
    target = PoseModel.still().target([0.5, -0.1, 0.7], quat.IDENTITY, [0.8, 0.2, 0.6], goal_q, 1.5)
    forcing = LearntForcing(model)
    own = forcing.own_target(target)
    rng = np.random.default_rng(2)
    for _ in range(10):
        state = moving_state(rng)
        s = state.phase
        expected = np.concatenate(
            (
                model.position.forcing.value(s, own.position_matrix),
                model.orientation.forcing.value(s, own.orientation_matrix),
            )
        ) / (1.5 * 1.5)
        lin, ang = forcing.acceleration(state, target)
        tol = 1e-12 * np.abs(expected).max()
        assert_allclose([*lin, *ang], expected, rtol=1e-12, atol=tol)
        fast = np.concatenate(kernel_acceleration(forcing, state, target))
        assert_allclose(fast, expected, rtol=1e-12, atol=tol)


class Lift:
    """A state-dependent coupling of a user's own (no kernel): it runs beside the kernels."""

    def acceleration(self, state: PoseState, target: object) -> tuple[np.ndarray, np.ndarray]:
        return np.array([0.0, 0.0, 0.2 * state.velocity[0]]), np.array([0.0, 0.0, 0.05])


def test_the_compiled_pose_dmp_steps_as_the_numpy_reference(demo: Demonstration) -> None:
    model = fit_pose(demo)
    rng = np.random.default_rng(12)
    start = PoseState(
        demo.positions[0],
        rng.normal(size=3) * 0.1,
        rng.normal(size=3),
        demo.orientations[0],
        rng.normal(size=3) * 0.1,
        rng.normal(size=3),
        1.0,
    )
    goal_q = quat.from_axis_angle([0.0, 0.0, 1.0], 0.5)
    dmp = PoseDMP.start(model, start, demo.positions[-1] + 0.1, goal_q, 1.5, [Lift()])
    reference = dmp.state
    for i in range(400):
        measured = None
        if i % 50 == 25:  # closed loop on a nudged state now and then
            measured = dmp.state._replace(position=dmp.state.position + rng.normal(size=3) * 1e-3)
            reference = measured
        reference = pose_step(reference, model, dmp.target, DT, dmp.couplings)
        got = dmp.step(DT, measured)
        for a, b in zip(got, reference, strict=True):
            assert_allclose(a, b, rtol=1e-9, atol=1e-9)
        if i == 200:
            dmp.set_goal(demo.positions[-1])  # packs again


def test_the_rollout_filter_is_lfilters_bit_for_bit() -> None:
    # The filter linear_rollout runs in place of scipy.signal.lfilter: every output the same
    # float, over DMP-like and arbitrary coefficients, inputs of many scales, zeros included.
    signal = pytest.importorskip("scipy.signal")
    rng = np.random.default_rng(17)
    for trial in range(200):
        n, dims = int(rng.integers(2, 300)), int(rng.integers(1, 7))
        dt, alpha, tau = rng.choice([0.001, 0.005, 0.0123]), rng.uniform(1, 60), rng.uniform(0.2, 5)
        k_gain, d_gain = alpha * alpha / 4.0 / tau**2, alpha / tau
        a = np.array([1.0, -(2.0 - d_gain * dt - k_gain * dt * dt), 1.0 - d_gain * dt])
        if trial % 5 == 0:
            a[1:] = rng.uniform(-1.5, 1.5, size=2)
        u = rng.standard_normal((n, dims)) * 10.0 ** rng.uniform(-3, 3, size=(1, dims))
        u[rng.integers(0, n)] = 0.0
        zi = rng.standard_normal((2, dims))
        expected, _ = signal.lfilter([dt * dt], a, u, axis=0, zi=zi)
        out = np.empty((n, dims))
        second_order_filter(a, float(dt * dt), u, zi, out)
        assert out.tobytes() == expected.tobytes(), trial


def test_a_retarget_long_after_the_phase_has_run_out_stays_finite() -> None:
    # 300 s into a 1 s skill the phase is subnormal (5e-323): a blend decaying from it had
    # thrown the skill 1e44 m away.
    t = np.linspace(0.0, 1.0, 101)
    s = 10 * t**3 - 15 * t**4 + 6 * t**5
    p = np.column_stack([0.4 + 0.3 * s, 0 * s, 0.675 + 0 * s])
    q = np.tile([0.0, 0.0, 0.0, 1.0], (101, 1))
    model = fit_pose(Demonstration.create(t, p, q, "d"))
    dmp = PoseDMP.start(model, PoseState.at_rest(p[0]), p[-1], q[-1], 1.0, blend_fraction=0.0)
    for _ in range(30000):
        dmp.step(0.01)
    assert dmp.state.phase < 1e-300
    dmp.set_goal(p[-1] + [0.02, 0.0, 0.0])
    for _ in range(500):
        dmp.step(0.01)
    assert np.linalg.norm(dmp.state.position - (p[-1] + [0.02, 0.0, 0.0])) < 1e-3

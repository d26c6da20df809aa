"""Obstacle steering (Hoffmann et al. 2009) and learning it from demonstrations (Rai 2014)."""

from __future__ import annotations

import math

import hypothesis.strategies as st
import numpy as np
import pytest
from hypothesis import assume, given, settings
from numpy.testing import assert_allclose

from skills import quaternion as quat
from skills.couplings import (
    AvoidanceDemo,
    ObstacleSteering,
    demonstrated_coupling,
    fit_obstacle_steering,
    steering_accelerations,
)
from skills.couplings.term import CouplingTerm
from skills.demonstration import Demonstration
from skills.demos import avoidance_demo, straight_demo
from skills.interpreter import kernel_acceleration
from skills.pose_dmp import PoseModel, PoseState, fit_pose, pose_rollout

#: Coupling terms here ignore the DMP's target; any valid one will do.
TARGET = PoseModel.still().target(np.zeros(3), quat.IDENTITY, np.ones(3), quat.IDENTITY, 1.0)

START = np.array([0.4, -0.3, 0.8])
GOAL = np.array([0.4, 0.3, 0.8])


def moving(position: object, velocity: object) -> PoseState:
    return turning(position, velocity, quat.IDENTITY, np.zeros(3))


def test_is_a_coupling_term() -> None:
    assert isinstance(ObstacleSteering(1.0, 1.0, 0.0), CouplingTerm)


def test_deflects_away_from_an_obstacle_slightly_off_axis_and_perpendicular_to_v() -> None:
    steer = ObstacleSteering(10.0, 3.0, 0.0, [[1.0, 0.05, 0.0]], [0.1])
    v = np.array([0.5, 0.0, 0.0])
    lin, ang = steer.acceleration(moving([0, 0, 0], v), TARGET)
    assert lin[1] < -1e-3  # obstacle at +y: steer to -y
    assert_allclose(lin @ v, 0.0, atol=1e-12)
    assert_allclose(lin[2], 0.0, atol=1e-12)
    assert_allclose(ang, 0.0)


def test_magnitude_matches_the_formula_at_a_hand_computed_point() -> None:
    # Obstacle at 45 degrees: phi = pi/4, |R v| = |v| = 2, clearance 1.5 - 0.2 - 0.1 = 1.2 m.
    gamma, beta, k = 4.0, 2.0, 0.5
    o = 1.5 / math.sqrt(2.0)
    steer = ObstacleSteering(gamma, beta, k, [[o, o, 0.0]], [0.2], object_radius=0.1)
    lin, _ = steer.acceleration(moving([0, 0, 0], [2.0, 0, 0]), TARGET)
    phi = math.pi / 4
    expected = gamma * 2.0 * phi * math.exp(-beta * phi) * math.exp(-k * 1.2**2)
    assert_allclose(lin, [0.0, -expected, 0.0], rtol=1e-12, atol=1e-15)


def test_symmetric_obstacles_give_mirrored_accelerations() -> None:
    left = ObstacleSteering(5.0, 2.0, 3.0, [[0.3, 0.04, 0.02]], [0.05])
    right = left.with_obstacles([[0.3, -0.04, 0.02]], [0.05])
    state = moving([0, 0, 0], [0.4, 0.0, 0.0])
    a_left, _ = left.acceleration(state, TARGET)
    a_right, _ = right.acceleration(state, TARGET)
    assert_allclose(a_right, a_left * np.array([1.0, -1.0, 1.0]), rtol=1e-12)
    both = left.with_obstacles([[0.3, 0.04, 0.02], [0.3, -0.04, 0.02]], [0.05, 0.05])
    a_both, _ = both.acceleration(state, TARGET)
    assert_allclose(a_both, a_left + a_right, rtol=1e-12, atol=1e-12)
    assert_allclose(a_both[1], 0.0, atol=1e-12)


def test_zero_at_rest_head_on_and_without_obstacles_and_behind_with_the_cutoff() -> None:
    steer = ObstacleSteering(5.0, 2.0, 3.0, [[0.3, 0.04, 0.0]], [0.05])
    for state in (
        moving([0, 0, 0], [0, 0, 0]),  # at rest
        moving([0, 0.04, 0], [0.4, 0, 0]),  # straight at the centre: phi = 0
        moving([0, 0.04, 0], [-0.4, 0, 0]),  # straight away: phi = pi
    ):
        lin, _ = steer.acceleration(state, TARGET)
        assert_allclose(lin, 0.0, atol=1e-15)
    empty = steer.with_obstacles(np.zeros((0, 3)), np.zeros(0))
    assert_allclose(empty.acceleration(moving([0, 0, 0], [1, 0, 0]), TARGET)[0], 0.0)
    away = moving([0, 0, 0], [-0.4, 0, 0])  # phi > pi/2
    assert np.linalg.norm(steer.acceleration(away, TARGET)[0]) > 0
    cutoff = ObstacleSteering(5.0, 2.0, 3.0, [[0.3, 0.04, 0.0]], [0.05], max_angle=math.pi / 2)
    assert_allclose(cutoff.acceleration(away, TARGET)[0], 0.0, atol=0.0)


vec3 = st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3).map(np.array)


@settings(max_examples=60, deadline=None)
@given(y=vec3, v=vec3, o=vec3)
def test_always_perpendicular_to_v_and_never_towards_the_obstacle(
    y: np.ndarray, v: np.ndarray, o: np.ndarray
) -> None:
    assume(np.linalg.norm(v) > 1e-2 and np.linalg.norm(o - y) > 1e-2)
    steer = ObstacleSteering(6.0, 1.5, 1.0, [o], [0.05], max_angle=math.pi)
    lin, _ = steer.acceleration(moving(y, v), TARGET)
    scale = 6.0 * float(np.linalg.norm(v))
    assert abs(float(lin @ v)) <= 1e-9 * scale * float(np.linalg.norm(v))
    assert float(lin @ (o - y)) <= 1e-9 * scale * float(np.linalg.norm(o - y))
    assert float(np.linalg.norm(lin)) <= scale * 1.0 / (1.5 * math.e) + 1e-12  # max of phi e^-b phi


def test_one_obstacle_fast_path_matches_the_vectorised_law() -> None:
    rng = np.random.default_rng(4)
    centres = rng.normal(size=(5, 3))
    radii = rng.uniform(0.0, 0.3, 5)
    for i in range(5):
        y, v = rng.normal(size=3), rng.normal(size=3)
        one = ObstacleSteering(3.0, 1.5, 2.0, centres[i : i + 1], radii[i : i + 1], 0.1)
        many = ObstacleSteering(3.0, 1.5, 2.0, centres, radii, 0.1)
        batch = steering_accelerations(y[None], v[None], centres, radii + 0.1, 3.0, 1.5, 2.0)
        assert_allclose(
            many.acceleration(moving(y, v), TARGET)[0], batch[0], rtol=1e-10, atol=1e-14
        )
        single = steering_accelerations(
            y[None], v[None], centres[i : i + 1], radii[i : i + 1] + 0.1, 3.0, 1.5, 2.0
        )
        assert_allclose(
            one.acceleration(moving(y, v), TARGET)[0], single[0], rtol=1e-10, atol=1e-14
        )


@pytest.mark.parametrize("m", [0, 1, 4])
def test_the_kernel_and_the_term_match_the_vectorised_law(m: int) -> None:
    rng = np.random.default_rng(5)
    centres = rng.normal(size=(m, 3))
    radii = rng.uniform(0.0, 0.3, m)
    steer = ObstacleSteering(3.0, 1.5, 2.0, centres, radii, 0.1)
    for _ in range(20):
        y, v = rng.normal(size=3), rng.normal(size=3)
        law = steering_accelerations(y[None], v[None], centres, radii + 0.1, 3.0, 1.5, 2.0)[0]
        lin, ang = steer.acceleration(moving(y, v), TARGET)
        assert_allclose([*lin, *ang], [*law, 0.0, 0.0, 0.0], rtol=1e-10, atol=1e-14)
        fast = np.concatenate(kernel_acceleration(steer, moving(y, v), TARGET))
        assert_allclose(fast, [*law, 0.0, 0.0, 0.0], rtol=1e-10, atol=1e-14)
    slow = moving(y, [1e-7, 0.0, 0.0])
    assert np.all(np.concatenate(steer.acceleration(slow, TARGET)) == 0.0)
    assert np.all(np.concatenate(kernel_acceleration(steer, slow, TARGET)) == 0.0)


def test_bad_parameters_name_the_field() -> None:
    with pytest.raises(ValueError, match="gamma"):
        ObstacleSteering(0.0, 1.0, 1.0)
    with pytest.raises(ValueError, match="beta"):
        ObstacleSteering(1.0, -1.0, 1.0)
    with pytest.raises(ValueError, match="k: expected"):
        ObstacleSteering(1.0, 1.0, -1.0)
    with pytest.raises(ValueError, match="radii: expected one radius per centre"):
        ObstacleSteering(1.0, 1.0, 1.0, [[0, 0, 0]], [0.1, 0.2])
    with pytest.raises(ValueError, match="radii: expected values >= 0"):
        ObstacleSteering(1.0, 1.0, 1.0, [[0, 0, 0]], [-0.1])
    with pytest.raises(ValueError, match="max_angle"):
        ObstacleSteering(1.0, 1.0, 1.0, max_angle=4.0)
    with pytest.raises(ValueError, match="centres: expected finite"):
        ObstacleSteering(1.0, 1.0, 1.0, [[0, np.nan, 0]], [0.1])


@pytest.fixture(scope="module")
def base_model() -> PoseModel:
    """The teacher's motion without an obstacle, learnt as a pose DMP (1 s)."""
    return fit_pose(Demonstration.create(*straight_demo(START, GOAL, duration=1.0, noise=0.0)))


def test_a_demo_of_the_base_motion_itself_shows_no_coupling(base_model: PoseModel) -> None:
    target = base_model.target(START, quat.IDENTITY, GOAL, quat.IDENTITY)
    traj = pose_rollout(base_model, target, PoseState.at_rest(START), 0.001, 2000)
    demo = Demonstration.create(traj.t, traj.positions, traj.orientations)
    _, _, c = demonstrated_coupling(
        AvoidanceDemo.create(demo, [1.0, 0, 0], 0.1, tau=1.0), base_model
    )
    _, ydd = demo.position_derivatives()
    # Bound: 3 % of the motion's peak acceleration, from differencing a semi-implicit Euler
    # path and from its last sample (the goal the fit assumes) being 0.05 mm short at 2 tau.
    assert np.max(np.abs(c[5:-5])) < 0.03 * np.max(np.abs(ydd))


def test_fit_recovers_the_parameters_of_a_demo_made_with_the_law(base_model: PoseModel) -> None:
    true = ObstacleSteering(8.0, 2.0, 40.0, [[0.42, 0.0, 0.8]], [0.05])
    target = base_model.target(START, quat.IDENTITY, GOAL, quat.IDENTITY)
    dt = 0.001
    traj = pose_rollout(base_model, target, PoseState.at_rest(START), dt, 2000, [true])
    demo = Demonstration.create(traj.t, traj.positions, traj.orientations, name="law")
    fit = fit_obstacle_steering(
        AvoidanceDemo.create(demo, true.centres, true.radii, tau=1.0), model=base_model
    )
    # Bound: 5 %; the bias left (about 1 %) is finite differencing of a semi-implicit Euler path.
    assert_allclose(
        (fit.steering.gamma, fit.steering.beta, fit.steering.k), (8.0, 2.0, 40.0), rtol=0.05
    )
    assert fit.n_samples == 2001
    assert fit.relative_residual < 0.15
    assert_allclose(fit.steering.centres, true.centres)


def test_learnt_from_a_human_like_demo_it_keeps_clear_where_the_plain_dmp_collides(
    base_model: PoseModel,
) -> None:
    rng = np.random.default_rng(3)
    obstacle, radius = np.array([0.4, 0.0, 0.81]), 0.06
    t, p, q = avoidance_demo(START, GOAL, obstacle, radius, clearance=0.05, duration=1.0, rng=rng)
    fit = fit_obstacle_steering(
        AvoidanceDemo.create(Demonstration.create(t, p, q), obstacle, radius), model=base_model
    )
    # The teacher is not the law: it explains about 60 % of the coupling (RMS 0.38 left).
    assert fit.relative_residual < 0.5
    target = base_model.target(START, quat.IDENTITY, GOAL, quat.IDENTITY)
    for centre in (obstacle, np.array([0.45, 0.05, 0.79])):  # demonstrated, then a novel one
        plain = pose_rollout(base_model, target, PoseState.at_rest(START), 0.005)
        steer = fit.steering.with_obstacles([centre], [radius])
        avoid = pose_rollout(base_model, target, PoseState.at_rest(START), 0.005, 600, [steer])
        assert np.min(np.linalg.norm(plain.positions - centre, axis=1)) < radius
        assert np.min(np.linalg.norm(avoid.positions - centre, axis=1)) > radius + 0.02
        assert np.linalg.norm(avoid.positions[-1] - GOAL) < 1e-4  # after 3 tau


def test_fit_rejects_no_demos_and_no_avoidance() -> None:
    with pytest.raises(ValueError, match="demos: expected at least one"):
        fit_obstacle_steering([])
    t = np.linspace(0, 1, 50)
    still = Demonstration.create(t, np.zeros((50, 3)))
    with pytest.raises(ValueError, match="demos: expected a demonstrated coupling"):
        fit_obstacle_steering(AvoidanceDemo.create(still, [1.0, 0, 0], 0.1))
    with pytest.raises(ValueError, match="radii: expected one radius per centre"):
        AvoidanceDemo.create(still, [[1.0, 0, 0]], [0.1, 0.2])


def turning(position: object, velocity: object, q: object, omega: object) -> PoseState:
    z = np.zeros(3)
    return PoseState(
        np.asarray(position, dtype=float),
        np.asarray(velocity, dtype=float),
        z,
        np.asarray(q, dtype=float),
        np.asarray(omega, dtype=float),
        z,
    )


def _by_nearest_member(
    y: np.ndarray,
    v: np.ndarray,
    rotation: np.ndarray,
    w: np.ndarray,
    centres: np.ndarray,
    radii: np.ndarray,
    held: np.ndarray,
    held_radii: np.ndarray,
    object_radius: float,
    steer_object: bool = True,
) -> np.ndarray:
    """The held assembly's steering by hand: each obstacle steered by its nearest member."""
    total = np.zeros(3)
    for c, r in zip(centres, radii, strict=True):
        members = [(y, v, r + object_radius)]
        for h, rho in zip(held, held_radii, strict=True):
            arm = rotation @ h
            members.append((y + arm, v + np.cross(w, arm), r + rho))
        gaps = [np.linalg.norm(c - p) - reach for p, _, reach in members]
        k = int(np.argmin(gaps))
        if k == 0 and not steer_object:
            continue
        p, u, reach = members[k]
        total += steering_accelerations(
            p[None], u[None], c[None], np.array([reach]), 3.0, 1.5, 2.0
        )[0]
    return total


@pytest.mark.parametrize("steer_object", [True, False])
def test_each_obstacle_is_steered_by_the_nearest_member_of_the_held_assembly(
    steer_object: bool,
) -> None:
    rng = np.random.default_rng(8)
    held = rng.normal(scale=0.3, size=(2, 3))
    held_radii = np.array([0.05, 0.09])
    owners = set()
    for _ in range(20):
        centres = rng.normal(scale=0.6, size=(4, 3))
        radii = rng.uniform(0.0, 0.1, 4)
        steer = ObstacleSteering(
            3.0,
            1.5,
            2.0,
            centres,
            radii,
            0.1,
            held=held,
            held_radii=held_radii,
            steer_object=steer_object,
        )
        y, v, w = rng.normal(scale=0.1, size=3), rng.normal(size=3), rng.normal(size=3)
        q = quat.exp(rng.normal(size=3))
        rotation = quat.to_matrix(q)
        law = _by_nearest_member(
            y, v, rotation, w, centres, radii, held, held_radii, 0.1, steer_object
        )
        for c, r in zip(centres, radii, strict=True):
            gaps = [np.linalg.norm(c - y) - r - 0.1] + [
                np.linalg.norm(c - y - rotation @ h) - r - rho
                for h, rho in zip(held, held_radii, strict=True)
            ]
            owners.add(int(np.argmin(gaps)))
        state = turning(y, v, q, w)
        lin, ang = steer.acceleration(state, TARGET)
        assert_allclose([*lin, *ang], [*law, 0.0, 0.0, 0.0], rtol=1e-9, atol=1e-12)
        fast = np.concatenate(kernel_acceleration(steer, state, TARGET))
        assert_allclose(fast, [*law, 0.0, 0.0, 0.0], rtol=1e-9, atol=1e-12)
    assert owners == {0, 1, 2}  # the draws exercised every member


def test_without_held_spheres_the_term_is_the_objects_alone() -> None:
    rng = np.random.default_rng(9)
    centres, radii = rng.normal(size=(2, 3)), rng.uniform(0.0, 0.2, 2)
    plain = ObstacleSteering(3.0, 1.5, 2.0, centres, radii, 0.1)
    empty = ObstacleSteering(3.0, 1.5, 2.0, centres, radii, 0.1, held=np.zeros((0, 3)))
    for _ in range(10):
        state = turning(rng.normal(size=3), rng.normal(size=3), quat.IDENTITY, rng.normal(size=3))
        law = steering_accelerations(
            state.position[None], state.velocity[None], centres, radii + 0.1, 3.0, 1.5, 2.0
        )[0]
        fast = np.concatenate(kernel_acceleration(plain, state, TARGET))
        assert np.array_equal(fast, np.concatenate(kernel_acceleration(empty, state, TARGET)))
        assert_allclose(fast[:3], law, rtol=1e-10, atol=1e-14)


def test_a_hand_standing_above_the_object_steers_around_the_ball_it_nears() -> None:
    # The object passes 20 cm below a ball, a hand held 15 cm above it nearer the ball: the
    # hand, not the object, is steered around it; a ball at the object's height is the
    # object's to steer around, so the hands' term (steer_object=False) leaves it.
    state = turning([0.0, -0.3, 0.0], [0.0, 0.5, 0.0], quat.IDENTITY, np.zeros(3))
    hand = {"held": [[0.0, 0.0, 0.15]], "held_radii": [0.05]}
    above = ObstacleSteering(3.0, 1.5, 20.0, [[0.0, 0.0, 0.2]], [0.02], 0.05, **hand)
    at_hand = steering_accelerations(
        np.array([[0.0, -0.3, 0.15]]),
        np.array([[0.0, 0.5, 0.0]]),
        np.array([[0.0, 0.0, 0.2]]),
        np.array([0.07]),
        3.0,
        1.5,
        20.0,
    )[0]
    lin = above.acceleration(state, TARGET)[0]
    assert_allclose(lin, at_hand, rtol=1e-12)
    assert lin[2] < 0.0  # steered down, away from the ball
    level = ObstacleSteering(
        3.0, 1.5, 20.0, [[0.0, 0.0, 0.02]], [0.02], 0.05, steer_object=False, **hand
    )
    assert np.all(level.acceleration(state, TARGET)[0] == 0.0)


def test_bad_held_spheres_name_the_field() -> None:
    with pytest.raises(ValueError, match="held_radii: expected one radius per held sphere"):
        ObstacleSteering(1.0, 1.0, 1.0, held=[[0, 0, 0]], held_radii=[0.1, 0.2])
    with pytest.raises(ValueError, match="held_radii: expected values >= 0"):
        ObstacleSteering(1.0, 1.0, 1.0, held=[[0, 0, 0]], held_radii=[-0.1])
    with pytest.raises(ValueError, match="held: expected finite"):
        ObstacleSteering(1.0, 1.0, 1.0, held=[[0, np.inf, 0]], held_radii=[0.1])

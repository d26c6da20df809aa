"""Dynamic potential field (Park et al. 2008) on points attached to the object."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from skills import quaternion as quat
from skills.couplings import PotentialFieldAvoidance, SphereObstacles
from skills.couplings.potential import point_accelerations, potential
from skills.couplings.term import CouplingTerm
from skills.interpreter import kernel_acceleration
from skills.pose_dmp import PoseModel, PoseState
from skills.types import Array

#: Coupling terms here ignore the DMP's target; any valid one will do.
TARGET = PoseModel.still().target(np.zeros(3), quat.IDENTITY, np.ones(3), quat.IDENTITY, 1.0)

OBSTACLE = np.array([0.5, 0.0, 0.0])
RADIUS = 0.05


def sphere(points: Array) -> tuple[Array, Array]:
    """Distances and closest points on a sphere: the shape of an FCL query."""
    d = points - OBSTACLE
    n = np.linalg.norm(d, axis=1)
    return n - RADIUS, OBSTACLE + RADIUS * d / n[:, None]


def state(
    position: object, velocity: object, yaw: float = 0.0, omega: object = (0, 0, 0)
) -> PoseState:
    z = np.zeros(3)
    return PoseState(
        np.asarray(position, dtype=float),
        np.asarray(velocity, dtype=float),
        z,
        quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), yaw),
        np.asarray(omega, dtype=float),
        z,
    )


def one_point(**kwargs: float) -> PotentialFieldAvoidance:
    return PotentialFieldAvoidance(sphere, np.zeros((1, 3)), **kwargs)


def test_is_a_coupling_term() -> None:
    assert isinstance(one_point(), CouplingTerm)


def test_head_on_pushes_opposite_to_the_velocity_with_lambda_v_over_p_squared() -> None:
    field = one_point(gain=0.05, influence=math.inf)
    lin, ang = field.acceleration(state([0.25, 0, 0], [0.4, 0, 0]), TARGET)
    p = 0.25 - RADIUS
    assert_allclose(lin, [-0.05 * 0.4 / p**2, 0.0, 0.0], rtol=1e-12)
    assert_allclose(ang, 0.0)  # a point at the origin has no lever arm


def test_zero_when_moving_away_sideways_still_or_beyond_the_influence() -> None:
    field = one_point(gain=0.05, influence=0.3)
    for s in (
        state([0.25, 0, 0], [-0.4, 0, 0]),  # away
        state([0.25, 0, 0], [0, 0.4, 0]),  # tangential: theta = pi/2
        state([0.25, 0, 0], [0, 0, 0]),  # still
        state([0.1, 0, 0], [0.4, 0, 0]),  # approaching but 0.35 m from the surface
    ):
        lin, ang = field.acceleration(s, TARGET)
        assert_allclose(lin, 0.0, atol=0.0)
        assert_allclose(ang, 0.0, atol=0.0)


def test_approaching_at_an_angle_is_pushed_away_and_turned_aside() -> None:
    field = one_point(gain=0.05, influence=0.3)
    lin, _ = field.acceleration(state([0.3, 0.1, 0], [0.4, -0.1, 0]), TARGET)
    away = np.array([0.3, 0.1, 0]) - OBSTACLE
    assert lin @ away > 0.0
    assert lin[1] > 0.0  # the obstacle is at -y of the path: turn to +y


@pytest.mark.parametrize("beta", [1.0, 2.0, 3.5])
@pytest.mark.parametrize("influence", [math.inf, 0.8])
def test_gradient_matches_finite_differences(beta: float, influence: float) -> None:
    rng = np.random.default_rng(7)
    centre = np.zeros((1, 3))  # a point obstacle: the closest point does not move
    for _ in range(20):
        x = rng.normal(size=(1, 3)) * 0.3
        v = -x * rng.uniform(0.5, 2.0) + rng.normal(size=(1, 3)) * 0.2
        if float(np.sum(v * x)) >= -1e-3:
            continue

        def u(y: Array, v: Array = v) -> float:
            d = np.linalg.norm(y - centre, axis=1)
            return float(potential(y, v, centre, d, 0.05, beta, influence)[0])

        h = 1e-6
        fd = np.array([(u(x + h * e) - u(x - h * e)) / (2 * h) for e in np.eye(3)])
        a = point_accelerations(x, v, centre, np.linalg.norm(x, axis=1), 0.05, beta, influence)
        assert_allclose(a[0], -fd, rtol=1e-6, atol=1e-9 * np.abs(fd).max())


def test_rigid_points_move_with_the_object_pose_and_twist() -> None:
    offsets = np.array([[0.1, 0.0, 0.0], [0.0, 0.2, 0.0]])
    field = PotentialFieldAvoidance(sphere, offsets)
    s = state([1.0, 2.0, 3.0], [0.1, 0.0, 0.0], yaw=math.pi / 2, omega=[0.0, 0.0, 2.0])
    arms, x, v = field.world_points(s)
    assert_allclose(arms, [[0.0, 0.1, 0.0], [-0.2, 0.0, 0.0]], atol=1e-15)
    assert_allclose(x, arms + [1.0, 2.0, 3.0])
    assert_allclose(v, [[0.1 - 0.2, 0.0, 0.0], [0.1, -0.4, 0.0]], atol=1e-15)  # v + w x r


def test_a_forearm_point_near_the_obstacle_pushes_and_turns_the_whole_system() -> None:
    # The object is far from the obstacle; a point 0.3 m to its +x side is not.
    offsets = np.array([[0.3, 0.0, 0.0], [-0.3, 0.0, 0.0]])
    field = PotentialFieldAvoidance(sphere, offsets, gain=0.05, influence=0.3)
    s = state([0.0, 0.1, 0.0], [0.0, -0.4, 0.0])
    lin, ang = field.acceleration(s, TARGET)
    x = np.array([0.3, 0.1, 0.0])
    a = point_accelerations(x[None], np.array([[0, -0.4, 0]]), *_closest(x), 0.05, 2.0, 0.3)[0]
    assert_allclose(lin, a, rtol=1e-12)  # only the near point contributes
    rho2 = 0.3**2
    assert_allclose(ang, np.cross([0.3, 0.0, 0.0], a) / rho2, rtol=1e-12)
    n = (x - OBSTACLE) / np.linalg.norm(x - OBSTACLE)
    assert lin @ n > 0.0  # pushed away from the obstacle

    def approach(v: Array) -> float:  # -cos(theta)
        return float(-(v @ n) / np.linalg.norm(v))

    v = np.array([0.0, -0.4, 0.0])
    assert approach(v + 1e-3 * lin) < approach(v)  # and turned away from it


def _closest(x: Array) -> tuple[Array, Array]:
    d, c = sphere(x[None])
    return c, d


def test_with_points_and_with_query_replace_what_they_say() -> None:
    field = one_point()
    moved = field.with_points([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0]])
    assert moved.points_object.shape == (2, 3)
    assert moved.gain == field.gain
    empty = field.with_points(np.zeros((0, 3)))
    assert_allclose(empty.acceleration(state([0.25, 0, 0], [0.4, 0, 0]), TARGET)[0], 0.0)
    far = field.with_query(lambda p: (np.full(len(p), 10.0), p + 10.0))
    assert_allclose(far.acceleration(state([0.25, 0, 0], [0.4, 0, 0]), TARGET)[0], 0.0)


def test_contact_stays_finite() -> None:
    lin, _ = one_point(min_distance=1e-3).acceleration(
        state([0.5 - RADIUS, 0, 0], [0.4, 0, 0]), TARGET
    )
    assert np.all(np.isfinite(lin))


def test_a_point_inside_is_pushed_out_never_further_in() -> None:
    # A negative distance (inside) puts the surface's nearest point beyond the point: the
    # offset from it pointed in, and the field had pushed a point moving out back in (the
    # compiled kernel too) and let one moving in go deeper.
    field = one_point(gain=0.05, influence=0.04)
    inside = [0.5 - RADIUS + 0.005, 0.0, 0.0]  # 5 mm in through the face at x 0.45
    deeper, _ = field.acceleration(state(inside, [0.1, 0, 0]), TARGET)
    leaving, _ = field.acceleration(state(inside, [-0.1, 0, 0]), TARGET)
    assert deeper[0] < 0.0 and np.allclose(deeper[1:], 0.0)  # pushed back out, along -x
    assert_allclose(leaving, 0.0)  # on its way out: U is flat
    for velocity in ([0.1, 0, 0], [-0.1, 0, 0], [0.02, 0.1, 0]):
        lin, ang = kernel_acceleration(field, state(inside, velocity), TARGET)
        expected = field.acceleration(state(inside, velocity), TARGET)
        assert_allclose(lin, expected[0], rtol=1e-12, atol=1e-12)
        assert_allclose(ang, expected[1], atol=1e-12)
    # Outside the same point moving in is pushed out as before, and the push grows inwards.
    outside, _ = field.acceleration(state([0.5 - RADIUS - 0.005, 0, 0], [0.1, 0, 0]), TARGET)
    assert outside[0] < 0.0 and abs(deeper[0]) >= abs(outside[0])


def test_bad_parameters_name_the_field() -> None:
    with pytest.raises(ValueError, match="gain"):
        one_point(gain=0.0)
    with pytest.raises(ValueError, match="beta: expected a finite number >= 1"):
        one_point(beta=0.5)
    with pytest.raises(ValueError, match="influence"):
        one_point(influence=-1.0)
    with pytest.raises(ValueError, match="min_distance"):
        one_point(min_distance=0.0)
    with pytest.raises(ValueError, match=r"points_object: expected shape \(N, 3\), got \(1, 2\)"):
        one_point().with_points([[1.0, 2.0]])
    with pytest.raises(ValueError, match="gyration_radius"):
        one_point(gyration_radius=-0.1)
    with pytest.raises(ValueError, match="points_object: expected finite"):
        PotentialFieldAvoidance(sphere, [[0.0, np.inf, 0.0]])
    with pytest.raises(ValueError, match="query: expected a callable"):
        PotentialFieldAvoidance(None, np.zeros((1, 3)))  # type: ignore[arg-type]


def random_state(rng: np.random.Generator) -> PoseState:
    """Near the obstacle, any orientation, moving and turning."""
    z = np.zeros(3)
    return PoseState(
        OBSTACLE + rng.normal(size=3) * 0.15,
        rng.normal(size=3) * 0.3,
        z,
        quat.as_quaternions(rng.normal(size=4)),
        rng.normal(size=3),
        z,
    )


@pytest.mark.parametrize("beta", [1.0, 2.0, 3.5])
@pytest.mark.parametrize("influence", [math.inf, 0.3])
def test_the_kernel_matches_the_vectorised_field(beta: float, influence: float) -> None:
    rng = np.random.default_rng(11)
    pushed = 0
    for n in (1, 3, 8, 12):
        for _ in range(12):
            field = PotentialFieldAvoidance(
                sphere, rng.normal(size=(n, 3)) * 0.15, 0.05, beta, influence
            )
            s = random_state(rng)
            expected = np.concatenate(field.acceleration(s, TARGET))
            fast = np.concatenate(kernel_acceleration(field, s, TARGET))
            assert_allclose(fast, expected, rtol=1e-9, atol=1e-12 * np.abs(expected).max())
            pushed += bool(np.any(expected))
            spheres = field.with_query(SphereObstacles([[0.0, 0.0, 0.0]], [0.05]))
            fast = np.concatenate(kernel_acceleration(spheres, s, TARGET))
            expected = np.concatenate(spheres.acceleration(s, TARGET))
            assert_allclose(fast, expected, rtol=1e-9, atol=1e-12 * np.abs(expected).max())
    assert pushed >= 24  # half the draws or more have a point approaching within the influence


def test_the_kernel_is_zero_without_points_or_nearby_obstacles() -> None:
    s = state([0.25, 0, 0], [0.4, 0, 0])
    empty = one_point().with_points(np.zeros((0, 3)))
    assert np.all(np.concatenate(kernel_acceleration(empty, s, TARGET)) == 0.0)
    far = one_point().with_query(lambda p: (np.full(len(p), 10.0), p + 10.0))
    assert np.all(np.concatenate(kernel_acceleration(far, s, TARGET)) == 0.0)
    assert np.all(np.concatenate(far.acceleration(s, TARGET)) == 0.0)


def test_sphere_obstacles_give_each_point_its_nearest_surface() -> None:
    spheres = SphereObstacles([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]], [0.1, 0.3])
    points = np.array([[0.0, 0.5, 0.0], [1.0, 0.0, 0.5], [0.6, 0.0, 0.0], [1.1, 0.0, 0.0]])
    d, c = spheres(points)
    # 0.4 above the first; 0.2 above the second; between them 0.5 - 0.1 = 0.4 from the first,
    # 0.4 - 0.3 = 0.1 from the second; inside the second, 0.1 from its centre: -0.2.
    assert_allclose(d, [0.4, 0.2, 0.1, -0.2], atol=1e-15)
    assert_allclose(
        c, [[0.0, 0.1, 0.0], [1.0, 0.0, 0.3], [0.7, 0.0, 0.0], [1.3, 0.0, 0.0]], atol=1e-15
    )


def test_sphere_obstacles_without_spheres_are_infinitely_far() -> None:
    d, c = SphereObstacles(np.zeros((0, 3)), [])(np.ones((2, 3)))
    assert np.all(np.isinf(d)) and np.all(np.isnan(c))
    field = PotentialFieldAvoidance(SphereObstacles(np.zeros((0, 3)), []), [[0.1, 0.0, 0.0]])
    lin, ang = field.acceleration(state([0.0, 0.0, 0.0], [1.0, 0.0, 0.0]), TARGET)
    assert not np.any(lin) and not np.any(ang)


def test_sphere_obstacles_name_bad_fields() -> None:
    with pytest.raises(ValueError, match="radii: expected one radius per centre"):
        SphereObstacles([[0.0, 0.0, 0.0]], [0.1, 0.2])
    with pytest.raises(ValueError, match="radii: expected values >= 0"):
        SphereObstacles([[0.0, 0.0, 0.0]], [-0.1])
    with pytest.raises(ValueError, match="centres: expected finite values"):
        SphereObstacles([[0.0, np.nan, 0.0]], [0.1])


def test_a_field_on_sphere_obstacles_is_the_field_on_their_query() -> None:
    pts = [[0.0, 0.1, 0.0], [0.1, -0.1, 0.05]]
    closed = PotentialFieldAvoidance(SphereObstacles(OBSTACLE[None], [RADIUS]), pts, gain=0.1)
    by_hand = PotentialFieldAvoidance(sphere, pts, gain=0.1)
    s = state([0.2, 0.0, 0.0], [0.4, 0.05, 0.0], 0.3, (0.0, 0.0, 0.5))
    for got, want in zip(
        closed.acceleration(s, TARGET), by_hand.acceleration(s, TARGET), strict=True
    ):
        assert_allclose(got, want, rtol=1e-12, atol=1e-15)
    assert np.linalg.norm(closed.acceleration(s, TARGET)[0]) > 0.0

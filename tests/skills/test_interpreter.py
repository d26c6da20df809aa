"""The compiled interpreter gives every term's numpy reference within 1e-9, whole moves long."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from numpy.testing import assert_allclose

from skills import quaternion as quat
from skills.composer import DualArmComposer, DualArmState, grasped_state, reference_step
from skills.couplings import (
    GraspMaintenance,
    LearntForcing,
    ObstacleSteering,
    PotentialFieldAvoidance,
    Saturated,
    SphereObstacles,
    WorkspaceRepulsion,
)
from skills.couplings.term import CouplingTerm, Weighted
from skills.default_library import build_default_library
from skills.dual_arm import GraspGeometry
from skills.interpreter import kernel_acceleration
from skills.program import Kind
from skills.state import PoseState, PoseTarget
from skills.types import Array
from skills.vocabulary import ARMS, Action

DT = 1.0 / 60.0
OBSTACLE = np.array([0.62, -0.08, 0.82])
TOL = 1e-9


class Push:
    """A term of a user's own: numpy only, no kernel."""

    def __init__(self, lin: list[float], ang: list[float]) -> None:
        self.lin, self.ang = np.array(lin), np.array(ang)

    def acceleration(self, state: PoseState, target: PoseTarget) -> tuple[Array, Array]:
        return self.lin * (1.0 + state.position[2]), self.ang


def sphere(points: Array) -> tuple[Array, Array]:
    """A 4 cm sphere behind a plain callable, as an FCL query would be."""
    d = points - OBSTACLE
    n = np.linalg.norm(d, axis=1)
    return n - 0.04, OBSTACLE + 0.04 * d / n[:, None]


def composition(query: object = sphere, extra: tuple[tuple[CouplingTerm, float], ...] = ()):
    lib = build_default_library()
    g = GraspGeometry.lateral(0.30, 0.02)
    state = grasped_state(
        [0.65, 0.0, 0.675],
        quat.IDENTITY,
        (g.left_position, g.left_orientation),
        (g.right_position, g.right_orientation),
    )
    steer = lib.first(Action.AVOID_OBSTACLE).params
    steering = ObstacleSteering(
        float(steer["gamma"]), float(steer["beta"]), float(steer["k"]), object_radius=0.1
    ).with_obstacles(OBSTACLE[None], [0.04])
    rng = np.random.default_rng(1)
    links = np.array([-0.15, 0.0, 0.1]) + rng.normal(size=(8, 3)) * [0.1, 0.2, 0.05]
    field = PotentialFieldAvoidance(query, links, gain=0.4)  # type: ignore[arg-type]
    limits = WorkspaceRepulsion([0.3, -0.5, 0.66], [0.9, 0.5, 1.2], margin=0.05, gain=0.05)
    absolute = [
        (LearntForcing(lib.first(Action.TRANSPORT).pose_model()), 1.0),
        (LearntForcing(lib.first(Action.ROTATE_Z).pose_model()), 0.8),
        (Saturated([(steering, 1.0), (field, 1.2)], 3.0, 0.2, 0.05), 1.0),
        (Saturated([(limits, 1.0), (Saturated([(field, 0.5)], 1.0, 0.1), 2.0)], 3.0, 0.2), 1.0),
        (field.with_points(links[:3]), 0.7),
        (Push([0.0, 0.02, 0.0], [0.0, 0.0, 0.05]), 0.5),
        *extra,
    ]
    relative = {
        arm: [
            (GraspMaintenance(g.position(arm), g.orientation(arm), 0.015), 1.0),
            (Push([0.0, 0.0, 0.01], [0.0, 0.0, 0.0]), 2.0),
        ]
        for arm in ARMS
    }
    goal_q = quat.from_axis_angle([0.0, 0.0, 1.0], 0.4)
    return DualArmComposer.start(state, [0.6, -0.15, 0.675], goal_q, 2.5, absolute, relative)


def assert_states_close(got: DualArmState, want: DualArmState) -> None:
    for a, b in zip(
        (got.object, got.left, got.right), (want.object, want.left, want.right), strict=True
    ):
        for x, y in zip(a, b, strict=True):
            assert_allclose(x, y, rtol=TOL, atol=TOL)


def perturbed(state: DualArmState, rng: np.random.Generator) -> DualArmState:
    def one(p: PoseState) -> PoseState:
        return p._replace(
            position=p.position + rng.normal(size=3) * 0.01,
            velocity=p.velocity + rng.normal(size=3) * 0.05,
            orientation=quat.as_quaternions(p.orientation + rng.normal(size=4) * 0.02),
            angular_velocity=p.angular_velocity + rng.normal(size=3) * 0.1,
        )

    return DualArmState(one(state.object), one(state.left), one(state.right))


def test_a_whole_move_open_and_closed_loop_stays_with_the_reference() -> None:
    composer = composition()
    rng = np.random.default_rng(3)
    for i in range(int(2.5 / DT) + 30):
        measured = perturbed(composer.state, rng) if i % 7 == 3 else None
        want, want_cmd = reference_step(composer, DT, measured)
        cmd = composer.step(DT, measured)
        assert_states_close(composer.state, want)
        for name in ("positions", "orientations", "twists", "object_twist"):
            assert_allclose(getattr(cmd, name), getattr(want_cmd, name), rtol=TOL, atol=TOL)


def test_a_rollout_with_every_term_in_kernels_is_its_steps() -> None:
    composer = composition(SphereObstacles(OBSTACLE[None], [0.04]))
    composer.absolute = tuple(w for w in composer.absolute if not isinstance(w.term, Push))
    composer.relative = {arm: terms[:1] for arm, terms in composer.relative.items()}
    assert not composer.program().hooks  # one compiled call for the whole rollout
    start = composer.state
    path = composer.rollout(150, DT)
    composer.state = start
    for i in range(150):
        want, _ = reference_step(composer, DT)
        composer.step(DT)
        assert_states_close(composer.state, want)
        assert_allclose(path.values[i, :60], composer.state.values(), rtol=TOL, atol=TOL)


def test_a_subclass_keeps_its_kernel_and_a_term_of_your_own_runs_beside_them() -> None:
    class Mine(ObstacleSteering):
        """A user's subclass that changes nothing of the maths."""

    base = ObstacleSteering(3.0, 1.5, 2.0, OBSTACLE[None], [0.04], 0.1)
    mine = Mine(3.0, 1.5, 2.0, OBSTACLE[None], [0.04], 0.1)
    composer = composition(extra=((mine, 1.0),))
    kinds = composer.program().rows[:, 1].tolist()
    assert kinds.count(int(Kind.STEERING)) == 2
    assert kinds.count(int(Kind.EXTERNAL)) == 3  # a Push in each space
    s = composer.state.object._replace(velocity=np.array([0.0, -0.2, 0.3]))
    target = composer.target
    assert_allclose(
        np.concatenate(kernel_acceleration(mine, s, target)),
        np.concatenate(base.acceleration(s, target)),
        rtol=TOL,
        atol=1e-15,
    )


class Links:
    """A sphere query that also has points of its own, moving in the world (arm links)."""

    def __init__(self, points: Array) -> None:
        self.points = points

    def __call__(self, points: Array) -> tuple[Array, Array]:
        return sphere(points)

    def moving_points(self) -> Array:
        return self.points


def test_moving_points_come_through_the_query_before_each_closed_loop_step() -> None:
    rng = np.random.default_rng(4)
    links = Links(OBSTACLE + rng.normal(size=(5, 3)) * 0.1)
    field = PotentialFieldAvoidance(links, np.zeros((0, 3)), gain=0.4)
    composer = composition(extra=((field, 1.0),))
    composer.absolute = composer.absolute[-1:]
    pushed = 0
    for _ in range(30):
        links.points = links.points + rng.normal(size=(5, 3)) * 0.002
        obj = composer.state.object
        in_object = quat.rotate(quat.conjugate(obj.orientation), links.points - obj.position)
        frozen = replace(composer, absolute=(Weighted(field.with_points(in_object), 1.0),))
        want, _ = reference_step(frozen, DT)
        composer.step(DT)
        assert_states_close(composer.state, want)
        pushed += bool(np.any(field.with_points(in_object).acceleration(obj, composer.target)[0]))
    assert pushed >= 10  # the links were near enough to be pushed from
    links.points = links.points[:3]
    with pytest.raises(ValueError, match="moving_points: expected 5 points"):
        composer.step(DT)


def test_a_term_without_an_acceleration_is_refused_by_name() -> None:
    composer = composition(extra=((object(), 1.0),))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="term: expected a coupling term"):
        composer.step(DT)

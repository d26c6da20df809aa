"""Link-level avoidance steers what is welded to the palms (a hand) with the object."""

from __future__ import annotations

import numpy as np
from numpy.testing import assert_allclose

from planner.port import ObstacleInfo
from planner.skill_terms import held_spheres, held_steering
from skills import quaternion as quat
from skills.composer import DualArmState
from skills.library import SkillLibrary
from skills.pose_dmp import PoseState
from skills.vocabulary import Arm


class _Hands:
    """What the composition asks of the world here: obstacles and welded spheres."""

    def __init__(self, local: np.ndarray, radius: float) -> None:
        self.local, self.radius = local, radius

    def obstacles(self) -> tuple[ObstacleInfo, ...]:
        return (ObstacleInfo("ball", np.array([0.0, 0.0, 0.3]), 0.02),)

    def welded_spheres(self, arm: Arm) -> tuple[np.ndarray, np.ndarray]:
        return self.local[None].copy(), np.array([self.radius])


def _still(position: object, orientation: object) -> PoseState:
    z = np.zeros(3)
    return PoseState(np.asarray(position, float), z, z, np.asarray(orientation, float), z, z)


def test_held_spheres_are_placed_in_the_object_frame_by_the_grip() -> None:
    # The left palm turned a quarter about x in {O}: its sphere turns with it.
    q_left = quat.from_axis_angle(np.array([1.0, 0.0, 0.0]), np.pi / 2)
    state = DualArmState(
        _still([0.0, 0.0, 0.0], quat.IDENTITY),
        _still([0.0, 0.1, 0.0], q_left),
        _still([0.0, -0.1, 0.0], quat.IDENTITY),
    )
    local = np.array([-0.05, 0.01, -0.03])
    centres, radii = held_spheres(_Hands(local, 0.09), state)  # type: ignore[arg-type]
    assert_allclose(centres[0], [0.0, 0.1, 0.0] + quat.to_matrix(q_left) @ local, atol=1e-12)
    assert_allclose(centres[1], [0.0, -0.1, 0.0] + local, atol=1e-12)
    assert_allclose(radii, [0.09, 0.09])


def test_the_hands_are_steered_with_the_librarys_learnt_gains(library: SkillLibrary) -> None:
    held = (np.array([[0.0, 0.1, 0.1]]), np.array([0.05]))
    term = held_steering(library, _Hands(np.zeros(3), 0.05), held)  # type: ignore[arg-type]
    assert term is not None and not term.steer_object
    learnt = library.get("avoid_obstacle").params
    assert term.gamma == float(learnt["gamma"]) and term.k == float(learnt["k"])
    assert_allclose(term.held, held[0])
    # Moving along y under the ball: the object's centre alone would be steered too; here
    # only the hand is, so the object 0.3 m below gets exactly the hand's steering.
    state = PoseState(
        np.array([0.0, -0.2, 0.0]),
        np.array([0.0, 0.5, 0.0]),
        np.zeros(3),
        quat.IDENTITY.copy(),
        np.zeros(3),
        np.zeros(3),
    )
    lin, _ = term.acceleration(state, None)  # type: ignore[arg-type]
    assert lin[2] < 0.0  # the hand is steered down, away from the ball above it
    none = (np.zeros((0, 3)), np.zeros(0))
    assert held_steering(library, _Hands(np.zeros(3), 0.05), none) is None  # type: ignore[arg-type]

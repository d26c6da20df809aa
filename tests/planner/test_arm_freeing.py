"""A via-point motion whose palm stopped short frees its arm in joint space before failing."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest
from numpy.testing import assert_allclose
from py_trees.common import Status

from planner.leaves import Retreat
from planner.leaves.palm_motion import ArmsHome
from planner.port import ArmJoints, ObstacleInfo, PalmControl, Pose, offers
from planner.testing import FakeWorld, RoleView
from planner.testing.fake_world import FakeObject
from planner.testing.harness import TickLog, set_up
from skills.library import SkillLibrary
from skills.types import Array
from skills.vocabulary import ARMS, Arm

Tick = Callable[..., TickLog]
DT = 1.0 / 60.0
JOINTS = 7


class PinnedArmWorld(FakeWorld):
    """The fake world with arm joints: a pinned arm's palm ignores its commands (as an arm
    folded against its limits with its forearm on the table does) until its joints are
    commanded home, where its palm then is; ``unpins`` False keeps it pinned whatever."""

    def __init__(self, pinned: Arm, unpins: bool = True) -> None:
        super().__init__(objects=[FakeObject("parcel", np.array([0.2, 0.3, 0.15]))])
        self.pinned: set[Arm] = {pinned}
        self.unpins = unpins
        self.joints = {arm: np.full(JOINTS, -1.0) for arm in ARMS}
        self.joint_commands: list[tuple[Arm, Array]] = []
        for arm, side in ((Arm.LEFT, 1.0), (Arm.RIGHT, -1.0)):
            rest = self.rest_palm_pose(arm)
            self.command_palm(arm, Pose.of([0.55, side * 0.21, 0.675], rest.orientation))
        super().advance(DT)
        self.commands.clear()
        self.stuck_at = {arm: self.palm_pose(arm) for arm in self.pinned}

    def advance(self, dt: float) -> None:
        super().advance(dt)
        for arm in self.pinned:
            self._palms[arm] = self.stuck_at[arm]

    def arm_joints(self, arm: Arm) -> Array:
        return self.joints[arm].copy()

    def rest_joints(self, arm: Arm) -> Array:
        return np.zeros(JOINTS)

    def command_joints(self, arm: Arm, q: Array) -> None:
        self.joint_commands.append((arm, np.asarray(q, dtype=float)))
        self.joints[arm] = np.asarray(q, dtype=float)
        if self.unpins and np.allclose(q, 0.0) and arm in self.pinned:
            self.pinned.discard(arm)
            self._palms[arm] = self._targets[arm] = self.rest_palm_pose(arm)


def test_a_pinned_arm_is_freed_home_and_the_retreat_arrives(tick_leaf: Tick) -> None:
    world = PinnedArmWorld(Arm.LEFT)
    assert isinstance(world, ArmJoints)
    log = tick_leaf(Retreat("back_off"), world, segment_s=1.0)
    assert log.final == Status.SUCCESS, log.feedback
    assert log.feedback == "palms at rest (left arm freed)"
    # Only the pinned arm went home in joint space, from where its joints were, smoothly.
    arms = {arm for arm, _ in world.joint_commands}
    assert arms == {Arm.LEFT}
    path = np.array([q for _, q in world.joint_commands])
    assert_allclose(path[-1], 0.0, atol=1e-12)
    steps = np.diff(np.concatenate([np.full((1, JOINTS), -1.0), path]), axis=0)
    assert np.all(steps >= -1e-12), "the way home overshoots or turns back"
    assert steps.max() < 1.875 * ArmsHome.SPEED * DT * 1.01
    # The palms at rest (the free one as the motion left it, within its 2 mm), and the palm
    # law given both back at their last poses.
    for arm in ARMS:
        rest = world.rest_palm_pose(arm).position
        assert world.palm_pose(arm).position == pytest.approx(rest, abs=2e-3)
        assert world.palm_target(arm).position == pytest.approx(rest, abs=1e-12)


def test_an_arm_still_pinned_after_going_home_fails_saying_it_was_freed(
    tick_leaf: Tick,
) -> None:
    world = PinnedArmWorld(Arm.RIGHT, unpins=False)
    log = tick_leaf(Retreat("back_off"), world, segment_s=1.0)
    assert log.final == Status.FAILURE
    assert log.feedback.startswith("the right palm stopped")
    assert "its arm did not follow the motion" in log.feedback
    assert log.feedback.endswith("(right arm freed)")
    # Freed once only, then failed.
    homes = [q for _, q in world.joint_commands if np.allclose(q, 0.0)]
    assert 1 <= len(homes) <= round(ArmsHome.SETTLE_S / DT) + 2


def test_a_world_without_joints_fails_at_once_as_before(tick_leaf: Tick) -> None:
    world = PinnedArmWorld(Arm.LEFT)

    class NoJoints(FakeWorld):
        pass

    plain = NoJoints(objects=[FakeObject("parcel", np.array([0.2, 0.3, 0.15]))])
    assert not isinstance(plain, ArmJoints)
    # The same pinned palm in a world that offers no joints: the leaf fails, nothing freed.
    plain._palms = world._palms
    plain._targets = dict(world._targets)
    pinned = world.palm_pose(Arm.LEFT)
    advance = plain.advance

    def held(dt: float) -> None:
        advance(dt)
        plain._palms[Arm.LEFT] = pinned

    plain.advance = held  # type: ignore[method-assign]
    log = tick_leaf(Retreat("back_off"), plain, segment_s=1.0)
    assert log.final == Status.FAILURE
    assert "freed" not in log.feedback
    assert "the left palm stopped" in log.feedback


def test_the_way_home_takes_the_farthest_joint_at_the_mean_speed() -> None:
    home = ArmsHome({Arm.LEFT: np.array([0.0, 2.0])}, {Arm.LEFT: np.array([1.0, 0.0])})
    assert home.duration == pytest.approx(2.0 / ArmsHome.SPEED)
    near = ArmsHome({Arm.LEFT: np.zeros(2)}, {Arm.LEFT: np.full(2, 0.01)})
    assert near.duration == ArmsHome.LEAST_S
    dt = home.duration / 200
    q = [home.step(dt)[Arm.LEFT] for _ in range(200)]
    assert_allclose(q[-1], [1.0, 0.0], atol=1e-9)
    assert_allclose(q[99], [0.5, 1.0], atol=1e-9)  # a minimum-jerk path's middle
    assert not home.arrived()
    for _ in range(round(ArmsHome.SETTLE_S / dt) + 1):
        home.step(dt)
    assert home.arrived()


def test_a_leaf_halted_on_the_way_home_gives_the_arm_back_where_it_is(
    library: SkillLibrary,
) -> None:
    world = PinnedArmWorld(Arm.LEFT, unpins=False)
    leaf = set_up(Retreat("back_off"), world, library, segment_s=1.0)
    for _ in range(2000):
        leaf.tick_once()
        if "going home in joint space" in leaf.feedback_message:
            break
        world.advance(DT)
    else:
        pytest.fail("the retreat never started freeing its arm")
    for _ in range(10):
        world.advance(DT)
        leaf.tick_once()
    assert leaf.status == Status.RUNNING
    stuck_at = world.palm_pose(Arm.LEFT).position
    leaf.stop(Status.INVALID)  # a parent's Timeout
    # The palm law holds the arm where it is, not at the rest pose it could not reach.
    assert world.palm_target(Arm.LEFT).position == pytest.approx(stuck_at, abs=1e-12)
    assert leaf.freeing is None


def test_after_going_home_the_last_stretch_must_be_clear(tick_leaf: Tick) -> None:
    class ComesHomeAside(PinnedArmWorld):
        """Going home brings the palm 20 cm beside its rest pose, behind a sphere."""

        def command_joints(self, arm: Arm, q: Array) -> None:
            super().command_joints(arm, q)
            if arm not in self.pinned and arm is Arm.LEFT and not self.moved_aside:
                rest = self.rest_palm_pose(arm)
                aside = Pose(rest.position + np.array([0.0, 0.2, 0.0]), rest.orientation)
                self._palms[arm] = self._targets[arm] = aside
                self.moved_aside = True

    world = ComesHomeAside(Arm.LEFT)
    world.moved_aside = False
    rest = world.rest_palm_pose(Arm.LEFT).position
    world._all_obstacles["ball"] = ObstacleInfo("ball", rest + np.array([0.0, 0.1, 0.0]), 0.03)
    world.set_active_obstacles(["ball"])
    log = tick_leaf(Retreat("back_off"), world, segment_s=1.0, margin_m=0.01)
    assert log.final == Status.FAILURE
    assert log.feedback.startswith(
        "left arm freed and home, but the way from there to the last poses is not clear"
    ), log.feedback


def test_a_world_offers_a_role_through_a_role_view_only_if_the_view_declares_it() -> None:
    world = PinnedArmWorld(Arm.LEFT)
    assert offers(world, ArmJoints)
    assert offers(RoleView(world, Retreat.WORLD_ROLES), ArmJoints)
    assert not offers(RoleView(world, (PalmControl,)), ArmJoints)
    assert not offers(FakeWorld(), ArmJoints)

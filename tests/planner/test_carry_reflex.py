"""The obstacle reflex: a carried or squeezed object that strays within REFLEX_BAND_M of an
obstacle, as measured, or would within REFLEX_HORIZON_S at its measured closing speed, is
pushed out by shifting both palms' targets (Transport and Grasp); the composition runs on."""

from __future__ import annotations

import numpy as np
import py_trees
import pytest
from numpy.testing import assert_allclose
from py_trees.common import Status

from planner.leaves import Approach, Grasp, Transport
from planner.leaves.reflex import (
    REFLEX_BAND_M,
    REFLEX_GAIN,
    REFLEX_HORIZON_S,
    REFLEX_MAX_M,
    REFLEX_TAU_S,
)
from planner.port import Move, ObstacleGap, ObstacleInfo, Pose
from planner.testing import CONTROL_DT, FakeWorld, grasp_object, select_skills, set_up, set_up_carry
from planner.testing.fake_world import FakeObject
from planner.testing.harness import tick_until
from planner.wiring import wire
from skills.composer import commands_for
from skills.library import SkillLibrary
from skills.vocabulary import ARMS


class _Gaps:
    """A world whose only answers are the gap and the object's velocity it is told to give."""

    def __init__(self) -> None:
        self.gap: ObstacleGap | None = None
        self.velocity = np.zeros(3)

    def obstacle_gap(self, name: str, within_m: float) -> ObstacleGap | None:
        if self.gap is None or self.gap.distance_m >= within_m:
            return None
        return self.gap

    def object_twist(self, name: str) -> np.ndarray:
        return np.concatenate([self.velocity, np.zeros(3)])


def _reflex_leaf(world: _Gaps) -> Transport:
    leaf = Transport("carry")
    wire(leaf, object="parcel", move=0, plan="{plan}", from_state="{state}")
    leaf.setup(world=world, control_dt=CONTROL_DT)
    leaf.reflex_offset = np.zeros(3)
    return leaf


def test_the_shift_follows_the_depth_in_the_band_with_its_lag_and_cap() -> None:
    world = _Gaps()
    leaf = _reflex_leaf(world)
    away = np.array([0.0, -1.0, 0.0])
    # Clear of the band: no shift.
    assert_allclose(leaf._reflex("parcel"), 0.0)
    world.gap = ObstacleGap(REFLEX_BAND_M + 1e-3, away, "ball")
    assert_allclose(leaf._reflex("parcel"), 0.0)
    # 4 mm from the obstacle: 6 mm into the band, a want of GAIN x 6 mm, reached at the rate
    # dt / tau a tick (first order), the whole of it after a few tau.
    world.gap = ObstacleGap(0.004, away, "ball")
    want = REFLEX_GAIN * (REFLEX_BAND_M - 0.004) * away
    rate = CONTROL_DT / REFLEX_TAU_S
    assert_allclose(leaf._reflex("parcel"), rate * want, atol=1e-12)
    for _ in range(int(10 * REFLEX_TAU_S / CONTROL_DT)):
        shift = leaf._reflex("parcel")
    assert_allclose(shift, want, atol=1e-4)
    # Touching or inside: at most REFLEX_MAX_M.
    world.gap = ObstacleGap(-0.05, away, "ball")
    for _ in range(int(10 * REFLEX_TAU_S / CONTROL_DT)):
        shift = leaf._reflex("parcel")
    assert_allclose(shift, REFLEX_MAX_M * away, atol=1e-4)
    # Clear again: it fades back to none.
    world.gap = None
    for _ in range(int(20 * REFLEX_TAU_S / CONTROL_DT)):
        shift = leaf._reflex("parcel")
    assert np.linalg.norm(shift) < 1e-6


def test_an_object_closing_fast_is_pushed_as_if_the_horizon_had_passed() -> None:
    world = _Gaps()
    leaf = _reflex_leaf(world)
    away = np.array([0.0, -1.0, 0.0])
    rate = CONTROL_DT / REFLEX_TAU_S
    # 25 mm from the ball, beyond the band: nothing while still or moving along it.
    world.gap = ObstacleGap(0.025, away, "ball")
    world.velocity = np.array([0.3, 0.0, 0.0])
    assert_allclose(leaf._reflex("parcel"), 0.0)
    # Closing at 0.4 m/s: in REFLEX_HORIZON_S it would be 20 mm nearer, 5 mm from the ball.
    world.velocity = np.array([0.3, 0.4, 0.0])
    ahead = 0.025 - REFLEX_HORIZON_S * 0.4
    want = REFLEX_GAIN * (REFLEX_BAND_M - ahead) * away
    assert_allclose(leaf._reflex("parcel"), rate * want, atol=1e-12)
    # Moving away as fast: the gap as measured, beyond the band, so the shift fades.
    world.velocity = np.array([0.0, -0.4, 0.0])
    before = leaf.reflex_offset.copy()
    assert_allclose(leaf._reflex("parcel"), (1.0 - rate) * before, atol=1e-12)


def _carry_towards_a_ball(gap_at_goal: float) -> tuple[FakeWorld, float]:
    """The first move's goal put with its +x face ``gap_at_goal`` m short of a ball."""
    goal = np.array([0.65, 0.0, 0.675])
    radius = 0.04
    ball = ObstacleInfo("ball", goal + [0.10 + radius + gap_at_goal, 0.0, 0.0], radius)
    world = FakeWorld(
        objects=[FakeObject("parcel", np.array([0.20, 0.30, 0.15]))],
        obstacles=[ball],
        moves={"parcel": (Move(Pose.of(goal), ("ball",)),)},
    )
    return world, radius


@pytest.mark.usefixtures("clean_blackboard")
def test_a_carry_that_ends_too_near_an_obstacle_is_held_out_of_the_band(
    library: SkillLibrary,
) -> None:
    # The goal itself lies 3 mm from the ball: the composition (no avoidance) runs to it, the
    # measured parcel is pushed back to where the shift balances the depth in the band.
    world, _ = _carry_towards_a_ball(0.003)
    grasp_object(world, library)
    leaf = set_up_carry(
        world,
        library,
        avoid_gain=0.0,
    )
    closest = np.inf
    for _ in range(1500):
        leaf.tick_once()
        gap = world.obstacle_gap("parcel", 1.0)
        assert gap is not None
        closest = min(closest, gap.distance_m)
        if leaf.status != Status.RUNNING:
            break
        world.advance(CONTROL_DT)
    assert leaf.status == Status.SUCCESS, leaf.feedback_message
    # Balance: shift s = GAIN (band - (0.003 + s)), so s = GAIN (band - 0.003) / (1 + GAIN).
    shift = REFLEX_GAIN * (REFLEX_BAND_M - 0.003) / (1.0 + REFLEX_GAIN)
    assert closest > 0.003 + 0.8 * shift, closest
    assert world.object_pose("parcel").position[0] == pytest.approx(0.65 - shift, abs=1e-3)


@pytest.mark.usefixtures("clean_blackboard")
def test_a_grasp_closing_near_an_obstacle_shifts_its_palms_away_and_hands_them_on_so(
    library: SkillLibrary,
) -> None:
    # The parcel rests with its +x face 3 mm from a ball: inside the band from the start.
    radius = 0.04
    start = np.array([0.55, 0.0, 0.675])
    ball = ObstacleInfo("ball", start + [0.10 + radius + 0.003, 0.0, 0.0], radius)
    world = FakeWorld(
        objects=[FakeObject("parcel", np.array([0.20, 0.30, 0.15]))],
        obstacles=[ball],
        moves={"parcel": (Move(Pose.of([0.65, 0.0, 0.675]), ("ball",)),)},
    )
    world.set_active_obstacles(["ball"])
    select_skills(world, library)
    assert (
        tick_until(
            set_up(Approach("approach"), world, library, object="parcel"), world, CONTROL_DT
        ).final
        == Status.SUCCESS
    )
    world.commands.clear()
    grasp = set_up(Grasp("grasp"), world, library, object="parcel", plan="{plan}", state="{state}")
    log = tick_until(grasp, world, CONTROL_DT)
    assert log.final == Status.SUCCESS, log.feedback
    shift = grasp.reflex_offset
    # Away from the ball (-x), by up to the gain times the depth in the band.
    assert shift[0] < -1e-3 and abs(shift[1]) < 1e-9 and abs(shift[2]) < 1e-9
    assert -shift[0] <= REFLEX_GAIN * (REFLEX_BAND_M - 0.003) + 1e-9
    # The state handed on puts the palms where they were last sent, shift included.
    state = py_trees.blackboard.Blackboard.get("/state")
    handed = commands_for(state)
    for i, arm in enumerate(ARMS):
        sent = [c.pose.position for c in world.commands if c.arm is arm][-1]
        assert_allclose(handed.positions[i], sent, atol=1e-9)

"""An arm held in joint space goes to its joint targets, its palm's command set aside, and
the palm law takes it back where it then is; on the iiwas and on the iCub's shared torso."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from skills.vocabulary import ARMS, Arm
from worlds.scene import Scene
from worlds.sim_world import SimWorld
from worlds.world_file import load_world

pytestmark = pytest.mark.sim

WORLDS = Path(__file__).resolve().parents[2] / "worlds"


@pytest.mark.parametrize("world_file", ["parcel_pick_place.yaml", "icub_parcel_pick_place.yaml"])
def test_an_arm_goes_to_its_joint_targets_and_back_under_the_palm_law(world_file: str) -> None:
    world = load_world(WORLDS / world_file)
    with SimWorld(world) as sim:
        scene: Scene = sim.scene
        sim.advance(0.25)
        rest = sim.rest_joints(Arm.LEFT)
        # Near the rest posture (the iCub's arm drifts along its palm's null space).
        assert sim.arm_joints(Arm.LEFT) == pytest.approx(rest, abs=0.15)
        other = sim.palm_pose(Arm.RIGHT).position
        # Bend three joints 0.2 rad from rest, each away from its nearer limit, holding there
        # in joint space; the palm's own command (its rest pose) would pull it back, and
        # must not.
        rows = scene.controller._arm_rows[0]
        lower, upper = scene.controller._lower[rows], scene.controller._upper[rows]
        away = np.where(upper - rest > rest - lower, 1.0, -1.0)
        target = rest.copy()
        target[1:4] += 0.2 * away[1:4]
        sim.command_joints(Arm.LEFT, target)
        assert scene.controller.in_joint_space(Arm.LEFT)
        sim.advance(2.0)
        reached = sim.arm_joints(Arm.LEFT)
        assert np.max(np.abs(reached - target)) < 0.03, reached - target
        home = sim.rest_palm_pose(Arm.LEFT).position
        moved = np.linalg.norm(sim.palm_pose(Arm.LEFT).position - home)
        assert moved > 0.03  # the palm went with the joints, not to its command
        # The other arm's palm held its pose meanwhile (the iCub's torso serving it alone).
        assert np.linalg.norm(sim.palm_pose(Arm.RIGHT).position - other) < 0.01
        # A palm command ends the hold: the palm law takes the palm to it.
        here = sim.palm_pose(Arm.LEFT)
        sim.command_palm(Arm.LEFT, sim.rest_palm_pose(Arm.LEFT))
        assert not scene.controller.in_joint_space(Arm.LEFT)
        sim.advance(2.0)
        back = np.linalg.norm(sim.palm_pose(Arm.LEFT).position - home)
        assert back < 0.005, (back, here.position)
        for arm in ARMS:
            assert np.linalg.norm(sim.palm_twist(arm)) < 0.05

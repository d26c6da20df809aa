"""The world port by role: the roles make up the port; each leaf needs only the roles it names."""

from __future__ import annotations

from pathlib import Path

import py_trees
import pytest
from numpy.testing import assert_allclose
from py_trees.common import Status

from planner.composition import grip_acceleration_limit
from planner.leaves.base import WorldLeaf
from planner.loader import load_tree
from planner.port import Clock, ObjectSensing, ObstacleScene, PalmControl, WorldPort
from planner.testing import FakeWorld, RoleView, role_methods
from skills.library import SkillLibrary

DT = 1.0 / 60.0
TREES = Path(__file__).resolve().parents[2] / "planner" / "trees"
ROLES = (Clock, ObjectSensing, PalmControl, ObstacleScene)


def test_the_port_is_its_roles_and_no_method_has_two() -> None:
    per_role = [role_methods(r) for r in ROLES]
    assert sum(len(m) for m in per_role) == len(role_methods(WorldPort))
    assert frozenset().union(*per_role) == role_methods(WorldPort)
    assert "palm_stiffness" not in role_methods(WorldPort)


def test_the_fake_world_plays_every_role(fake_world: FakeWorld) -> None:
    for role in (*ROLES, WorldPort):
        assert isinstance(fake_world, role), role.__name__


def test_a_role_view_offers_its_roles_alone(fake_world: FakeWorld) -> None:
    view = RoleView(fake_world, (Clock,))
    assert view.time() == fake_world.time()
    with pytest.raises(AttributeError, match="object_pose: not a method of the roles Clock"):
        view.object_pose("parcel")


@pytest.mark.parametrize("tree", ["pick_and_place.xml", "paper_composition.xml"])
def test_each_leaf_does_its_job_through_the_roles_it_names(
    fake_world: FakeWorld, library: SkillLibrary, tree: str
) -> None:
    root = load_tree(TREES / tree)
    py_trees.blackboard.Blackboard.set("/object", "parcel")
    bt = py_trees.trees.BehaviourTree(root)
    bt.setup(world=fake_world, library=library, control_dt=DT, clock=fake_world.time)
    leaves = [n for n in root.iterate() if isinstance(n, WorldLeaf)]
    assert {type(n).__name__ for n in leaves} >= {"SelectSkills", "Grasp", "Transport"}
    for leaf in leaves:
        assert type(leaf).WORLD_ROLES != (WorldPort,), f"{type(leaf).__name__} names no roles"
        leaf.setup(world=RoleView(fake_world, type(leaf).WORLD_ROLES))
    for _ in range(120 * 60):
        bt.tick()
        if root.status in (Status.SUCCESS, Status.FAILURE):
            break
        fake_world.advance(DT)
    assert root.status == Status.SUCCESS, [
        f"{n.name}: {n.feedback_message}" for n in leaves if n.status == Status.FAILURE
    ]


def test_the_grip_limit_is_the_spare_acceleration_of_the_declared_grip(
    fake_world: FakeWorld,
) -> None:
    # The paper's 1 kg parcel (mu 0.8) in palms of mu 0.8 at 15 N each, under 9.81 m/s^2:
    # (2 * 0.64 * 15 - 9.81) / 1 over the margin of 4.
    assert_allclose(grip_acceleration_limit(fake_world, "parcel", 15.0), (19.2 - 9.81) / 4.0)
    assert grip_acceleration_limit(fake_world, "parcel", 0.0) == 0.5  # the floor
    assert grip_acceleration_limit(fake_world, "parcel", 100.0) == 3.0  # the arms' ceiling

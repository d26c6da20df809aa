"""Test support: an in-memory world and helpers to tick one leaf (see also tests/planner)."""

from planner.testing.fake_world import FakeObject, FakeWorld
from planner.testing.harness import (
    CONTROL_DT,
    grasp_object,
    select_skills,
    set_up,
    set_up_carry,
    tick_until,
)
from planner.testing.roles import RoleView, role_methods

__all__ = [
    "CONTROL_DT",
    "FakeObject",
    "FakeWorld",
    "RoleView",
    "grasp_object",
    "role_methods",
    "select_skills",
    "set_up",
    "set_up_carry",
    "tick_until",
]

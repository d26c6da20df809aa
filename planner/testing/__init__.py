"""Test support: an in-memory world and helpers to tick one leaf (see also tests/planner)."""

from planner.testing.fake_world import FakeObject, FakeWorld
from planner.testing.harness import tick_until
from planner.testing.roles import RoleView, role_methods

__all__ = ["FakeObject", "FakeWorld", "RoleView", "role_methods", "tick_until"]

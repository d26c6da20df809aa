"""Test support: an in-memory world and helpers to tick one leaf (see also tests/planner)."""

# isort: off
from duet_robot.blas import pin_blas_kernel

# pytest loads its plugins (planner.testing.fixtures among them) before any conftest.py: the
# kernel app.py pins (duet_robot.blas), asked for here, before this package loads numpy.
pin_blas_kernel()
from planner.testing.fake_world import FakeObject, FakeWorld  # noqa: E402
from planner.testing.harness import (  # noqa: E402
    CONTROL_DT,
    grasp_object,
    select_skills,
    set_up,
    set_up_carry,
    tick_until,
)
from planner.testing.roles import RoleView, role_methods  # noqa: E402

# isort: on

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

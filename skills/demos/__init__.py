"""Synthetic human-like teachers: seeded demonstrations with known shapes."""

from skills.demos.avoidance import avoidance_demo, straight_demo
from skills.demos.rotation import rotation_demo

__all__ = ["avoidance_demo", "rotation_demo", "straight_demo"]

"""Affordance reasoning: object context to semantic actions. Never imports pybullet."""

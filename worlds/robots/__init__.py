"""Robot models: the types (:mod:`worlds.robots.model`) and a builder by name.

A :class:`RobotModel` is a frozen description (URDF files, base poses, joint indices, palm links,
rest posture, limits). Builders such as :func:`worlds.robots.kuka.kuka_iiwa_model` write it; the
scene loads its bodies and the controller drives its arms.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

from worlds.robots.icub import icub_model
from worlds.robots.kuka import kuka_iiwa_model
from worlds.robots.model import ArmSpec, BodySpec, FloatArray, RobotModel
from worlds.spec import RobotModelName, RobotSpec


def build_robot_model(model: RobotModelName, **params: Any) -> RobotModel:
    """Build a robot model by name.

    Parameters
    ----------
    model : RobotModelName
        The model (its value, ``"kuka_iiwa"`` or ``"icub"``, is accepted too).
    **params
        Passed to the model's builder (e.g. ``arm_separation``, ``mount_height``, ``palm_size``).

    Returns
    -------
    RobotModel
    """
    if model == RobotModelName.KUKA_IIWA:
        return kuka_iiwa_model(**params)
    if model == RobotModelName.ICUB:
        return icub_model(**params)
    known = [m.value for m in RobotModelName]
    raise ValueError(f"build_robot_model: expected model in {known}, got {model!r}")


@lru_cache(maxsize=8)
def robot_model_of(spec: RobotSpec) -> RobotModel:
    """The robot model a world's robot section describes (built once per spec; no PyBullet)."""
    return build_robot_model(
        spec.model,
        base_position=spec.base_position,
        base_rpy_deg=spec.base_rpy_deg,
        arm_separation=spec.arm_separation,
        mount_height=spec.mount_height,
        palm_size=spec.palm_size,
    )


__all__ = ["ArmSpec", "BodySpec", "FloatArray", "RobotModel", "build_robot_model", "robot_model_of"]

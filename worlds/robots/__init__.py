"""Robot models: the types (:mod:`worlds.robots.model`) and a builder by name.

A :class:`RobotModel` is a frozen description (URDF files, base poses, joint indices, palm links,
rest posture, limits). Builders such as :func:`worlds.robots.kuka.kuka_iiwa_model` write it; the
scene loads its bodies and the controller drives its arms.
"""

from __future__ import annotations

from typing import Any

from worlds.robots.icub import icub_model
from worlds.robots.kuka import kuka_iiwa_model
from worlds.robots.model import ArmSpec, BodySpec, FloatArray, RobotModel


def build_robot_model(model: str, **params: Any) -> RobotModel:
    """Build a robot model by name.

    Parameters
    ----------
    model : str
        ``"kuka_iiwa"`` or ``"icub"``.
    **params
        Passed to the model's builder (e.g. ``arm_separation``, ``mount_height``, ``palm_size``).

    Returns
    -------
    RobotModel
    """
    if model == "kuka_iiwa":
        return kuka_iiwa_model(**params)
    if model == "icub":
        return icub_model(**params)
    raise ValueError(f"build_robot_model: expected model in ['kuka_iiwa', 'icub'], got {model!r}")


__all__ = ["ArmSpec", "BodySpec", "FloatArray", "RobotModel", "build_robot_model"]

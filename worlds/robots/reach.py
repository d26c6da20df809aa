"""How far each arm can reach, from its kinematic chain alone (no simulation).

An arm's *shoulder* is the last point of its chain that stays put whatever its joints do: the
origin of its first moving joint, moved on along the chain while the next joint's origin lies
on the axis of every moving joint before it (rotation about an axis leaves the axis's points
where they are). For the iiwa that is its second joint, 0.36 m above the base; for the iCub
the shoulder pitch joint. The *reach* is the sum of the lengths of the chain's segments from
the shoulder to the palm centre: by the triangle inequality no posture puts the palm farther
from the shoulder, so a palm pose beyond it is out of reach for certain (the converse need not
hold: joint limits and collisions cut the sphere down).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from skills import quaternion as quat
from skills.vocabulary import ARMS, Arm
from worlds.robots.model import RobotModel

#: Name of the palm link at the end of every arm's chain (worlds/robots/model.py).
PALM_LINK = "palm"
_MOVING = ("revolute", "continuous", "prismatic")
#: A point this close to a joint's axis line is on it, m.
_ON_AXIS_M = 1e-6


@dataclass(frozen=True)
class ArmReach:
    """The sphere an arm's palm centre stays in.

    Attributes
    ----------
    shoulder : tuple of float
        (3,) centre, world frame, m: the last point of the chain fixed in the world.
    radius_m : float
        Sum of the chain's segment lengths from the shoulder to the palm centre, m.
    joint : str
        The URDF joint whose origin is that centre: the iiwa's second joint, but the iCub's
        torso joint (the torso moves both shoulders), which a message names.
    """

    shoulder: tuple[float, float, float]
    radius_m: float
    joint: str = ""

    def distance_m(self, point: tuple[float, float, float]) -> float:
        """Distance of a world point from the shoulder, m."""
        return math.dist(self.shoulder, point)


@dataclass(frozen=True)
class _Joint:
    name: str
    kind: str
    parent: str
    child: str
    xyz: tuple[float, float, float]
    rpy: tuple[float, float, float]
    axis: tuple[float, float, float]
    travel_m: float


def _floats(text: str | None, default: tuple[float, float, float]) -> tuple[float, float, float]:
    if not text:
        return default
    x, y, z = (float(v) for v in text.split())
    return (x, y, z)


@lru_cache(maxsize=8)
def _joints_by_child(urdf: Path) -> dict[str, _Joint]:
    joints: dict[str, _Joint] = {}
    for element in ET.parse(urdf).getroot().findall("joint"):
        origin = element.find("origin")
        axis = element.find("axis")
        limit = element.find("limit")
        parent, child = element.find("parent"), element.find("child")
        if parent is None or child is None:
            raise ValueError(f"{urdf}: joint {element.get('name')!r} needs a parent and a child")
        travel = 0.0
        if element.get("type") == "prismatic" and limit is not None:
            travel = max(abs(float(limit.get("lower", 0))), abs(float(limit.get("upper", 0))))
        joint = _Joint(
            name=element.get("name", ""),
            kind=element.get("type", "fixed"),
            parent=parent.get("link", ""),
            child=child.get("link", ""),
            xyz=_floats(origin.get("xyz") if origin is not None else None, (0.0, 0.0, 0.0)),
            rpy=_floats(origin.get("rpy") if origin is not None else None, (0.0, 0.0, 0.0)),
            axis=_floats(axis.get("xyz") if axis is not None else None, (1.0, 0.0, 0.0)),
            travel_m=travel,
        )
        joints[joint.child] = joint
    return joints


def _chain(urdf: Path, palm: str = PALM_LINK) -> list[_Joint]:
    """The joints from the root link to the palm, root first."""
    joints = _joints_by_child(urdf)
    if palm not in joints:
        raise ValueError(f"{urdf}: expected a link named {palm!r} on a joint")
    chain = []
    link = palm
    while link in joints:
        chain.append(joints[link])
        link = joints[link].parent
    return chain[::-1]


def _distance_to_line(point: np.ndarray, origin: np.ndarray, direction: np.ndarray) -> float:
    offset = point - origin
    return float(np.linalg.norm(offset - np.dot(offset, direction) * direction))


def chain_reach(
    urdf: Path,
    base2world_position: tuple[float, float, float],
    base2world_quaternion: tuple[float, float, float, float],
    palm: str = PALM_LINK,
) -> ArmReach:
    """The reach sphere of the chain from a URDF's root link to its ``palm`` link.

    Parameters
    ----------
    urdf : Path
        The body's URDF.
    base2world_position : tuple of float
        (3,) root link frame origin in the world, m.
    base2world_quaternion : tuple of float
        (4,) root link frame orientation in the world, scalar-last.

    Returns
    -------
    ArmReach
    """
    # skills.quaternion, not scipy's Rotation: importing scipy.spatial costs every run's
    # start-up a fifth of a second for these few products.
    rotation = quat.as_quaternions(base2world_quaternion, "base2world_quaternion")
    position = np.asarray(base2world_position, dtype=float)
    chain = _chain(urdf, palm)
    origins: list[np.ndarray] = []
    axes: list[np.ndarray] = []
    # World frames with every joint at zero: the fixed points and segment lengths found below
    # do not depend on the posture.
    for joint in chain:
        position = position + quat.rotate(rotation, joint.xyz)
        rotation = quat.multiply(rotation, quat.from_rpy(joint.rpy))
        axis = quat.rotate(rotation, joint.axis)
        origins.append(position)
        axes.append(axis / np.linalg.norm(axis))
    moving = [j.kind in _MOVING for j in chain]
    if not any(moving):
        raise ValueError(f"{urdf}: expected a moving joint between the root and the palm")
    centre = moving.index(True)
    # Every point of the chain up to the centre lies on the axis of each moving joint so far;
    # a prismatic joint moves everything after it.
    fixed_axes = [axes[centre]]
    for k in range(centre + 1, len(origins)):
        if chain[k - 1].kind == "prismatic" or chain[centre].kind == "prismatic":
            break
        if not all(
            _distance_to_line(origins[k], origins[centre], a) < _ON_AXIS_M for a in fixed_axes
        ):
            break
        centre = k
        if moving[k]:
            fixed_axes.append(axes[k])
    travel = sum(j.travel_m for j in chain[centre:])
    lengths = [
        float(np.linalg.norm(origins[k + 1] - origins[k])) for k in range(centre, len(origins) - 1)
    ]
    x, y, z = (float(v) for v in origins[centre])
    return ArmReach((x, y, z), sum(lengths) + travel, chain[centre].name)


def arm_reach(model: RobotModel) -> dict[Arm, ArmReach]:
    """Each arm's reach sphere, from its body's URDF and base pose (see the module docstring)."""
    reach = {}
    for arm in ARMS:
        spec = model.arms[arm]
        body = model.bodies[spec.body]
        reach[arm] = chain_reach(
            body.urdf_path,
            body.base2world_position,
            body.base2world_quaternion,
            spec.palm_link_name,
        )
    return reach


__all__ = ["ArmReach", "arm_reach", "chain_reach"]

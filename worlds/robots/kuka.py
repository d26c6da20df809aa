"""Two KUKA iiwa arms with flat palms, mounted like a humanoid's arms behind a table.

The URDF is generated at run time from pybullet_data's ``kuka_iiwa/model.urdf``: mesh paths made
absolute, a pedestal box added under the base and a palm box on a fixed joint after the last link.
The palm frame sits at the palm box centre with z along the outward normal of the contact face; its
centre is offset along the flange's x axis so that, with x pointing down, the palm sits below the
wrist axis and the wrist housing clears the table.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pybullet_data

from skills import quaternion as quat
from skills.vocabulary import Arm, EndEffector
from worlds.actuators import TorqueLoop
from worlds.robots.cache import cached_urdf
from worlds.robots.model import ArmSpec, BodySpec, RobotModel

N_JOINTS = 7
#: Flange face along the last link's z axis, m (link_7 mesh extent).
FLANGE_Z = 0.045
#: Palm centre offset along the flange's x axis (down when grasping), m.
PALM_DROP = 0.04
#: Torque limits: the URDF says 300 N m for every joint; the real iiwa 14 wrist is weaker.
MAX_TORQUE = (320.0, 320.0, 176.0, 176.0, 110.0, 40.0, 40.0)
#: Forward lean of the arm bases, degrees: upright arms miss the far low corner of the table
#: workspace by 5 cm; 9 degrees brings every corner within about 1 cm (tests/worlds).
MOUNT_PITCH_DEG = 9.0
#: Rest posture of the left arm, rad: palm facing -y with its x axis down, near the parcel.
LEFT_REST = (0.03, 0.93, -0.07, -1.61, 1.59, -1.51, -0.45)
#: The links counted as an arm's forearm in the trials' figures: the last three (the palm apart).
FOREARM_LINKS = frozenset({"lbr_iiwa_link_5", "lbr_iiwa_link_6", "lbr_iiwa_link_7"})
#: Each arm ends in a flat palm box: it presses, it cannot close around anything.
END_EFFECTOR = EndEffector.FLAT_PALM


def _iiwa_source() -> Path:
    return Path(pybullet_data.getDataPath()) / "kuka_iiwa" / "model.urdf"


def _origin(parent: ET.Element, xyz: tuple[float, ...], rpy: tuple[float, ...] = (0, 0, 0)) -> None:
    ET.SubElement(
        parent,
        "origin",
        xyz=" ".join(f"{v:.6g}" for v in xyz),
        rpy=" ".join(f"{v:.6g}" for v in rpy),
    )


def _box_geometry(parent: ET.Element, size: tuple[float, ...]) -> None:
    geometry = ET.SubElement(parent, "geometry")
    ET.SubElement(geometry, "box", size=" ".join(f"{v:.6g}" for v in size))


def kuka_palm_urdf_text(
    palm_size: tuple[float, float, float],
    mount_height: float,
    palm_friction: float,
    mount_pitch_deg: float = 0.0,
) -> str:
    """URDF text of one iiwa arm on a pedestal with a palm box after link 7.

    Parameters
    ----------
    palm_size : tuple of float
        (3,) palm box extent along the palm frame's x, y, z, m.
    mount_height : float
        Pedestal height under the arm base, m.
    palm_friction : float
        Lateral friction coefficient of the palm (Bullet multiplies it with the object's).
    mount_pitch_deg : float
        Forward lean of the arm base, degrees; the pedestal stays vertical.

    Returns
    -------
    str
    """
    source = _iiwa_source()
    tree = ET.parse(source)
    robot = tree.getroot()
    robot.set("name", "duet_kuka_iiwa_palm")
    mesh_dir = source.parent
    for mesh in robot.iter("mesh"):
        mesh.set("filename", str((mesh_dir / mesh.get("filename", "")).resolve()))
    # All damping comes from the controller, which treats it implicitly; PyBullet's explicit
    # joint damping (0.5 N m s/rad in the source) diverges on the light last joint at 240 Hz.
    for joint in robot.findall("joint"):
        for dynamics in joint.findall("dynamics"):
            joint.remove(dynamics)
    links = {link.get("name"): link for link in robot.findall("link")}

    base = links["lbr_iiwa_link_0"]
    pedestal_size = (0.26, 0.26, mount_height)
    pitch = math.radians(mount_pitch_deg)
    # The base frame leans forward by `pitch`; the pedestal hangs vertically below its origin.
    pedestal_centre = (
        math.sin(pitch) * mount_height / 2.0,
        0.0,
        -math.cos(pitch) * mount_height / 2.0,
    )
    for tag in ("visual", "collision"):
        element = ET.SubElement(base, tag)
        _origin(element, pedestal_centre, (0.0, -pitch, 0.0))
        _box_geometry(element, pedestal_size)

    palm = ET.SubElement(robot, "link", name="palm")
    inertial = ET.SubElement(palm, "inertial")
    _origin(inertial, (0.0, 0.0, 0.0))
    ET.SubElement(inertial, "mass", value="0.2")
    ET.SubElement(
        inertial, "inertia", ixx="2e-4", ixy="0", ixz="0", iyy="3e-4", iyz="0", izz="4e-4"
    )
    for tag in ("visual", "collision"):
        element = ET.SubElement(palm, tag)
        _origin(element, (0.0, 0.0, 0.0))
        _box_geometry(element, palm_size)
    contact = ET.SubElement(palm, "contact")
    ET.SubElement(contact, "lateral_friction", value=f"{palm_friction:.6g}")

    joint = ET.SubElement(robot, "joint", name="palm_joint", type="fixed")
    ET.SubElement(joint, "parent", link="lbr_iiwa_link_7")
    ET.SubElement(joint, "child", link="palm")
    _origin(joint, palm2flange_position(palm_size))
    return ET.tostring(robot, encoding="unicode")


def palm2flange_position(palm_size: tuple[float, float, float]) -> tuple[float, float, float]:
    """Palm frame origin in the link-7 frame, m, shape (3,)."""
    return (PALM_DROP, 0.0, FLANGE_Z + palm_size[2] / 2.0)


def write_kuka_palm_urdf(
    palm_size: tuple[float, float, float] = (0.12, 0.09, 0.02),
    mount_height: float = 0.6,
    palm_friction: float = 1.0,
    cache_dir: Path | None = None,
    mount_pitch_deg: float = 0.0,
) -> Path:
    """Write the palm-arm URDF into a cache folder (once per parameter set) and return its path.

    Parameters
    ----------
    palm_size : tuple of float
        (3,) palm box extent, m.
    mount_height : float
        Pedestal height, m.
    palm_friction : float
        Palm lateral friction coefficient.
    cache_dir : Path, optional
        Folder for generated files; default :func:`worlds.robots.cache.default_cache_dir`.
    mount_pitch_deg : float
        Forward lean of the arm base, degrees.

    Returns
    -------
    Path
    """
    text = kuka_palm_urdf_text(palm_size, mount_height, palm_friction, mount_pitch_deg)
    return cached_urdf(text, "kuka_iiwa_palm", cache_dir)


def kuka_iiwa_model(
    base_position: tuple[float, float, float] = (0.0, 0.0, 0.0),
    base_rpy_deg: tuple[float, float, float] = (0.0, 0.0, 0.0),
    arm_separation: float = 0.7,
    mount_height: float = 0.6,
    palm_size: tuple[float, float, float] = (0.12, 0.09, 0.02),
    palm_friction: float = 1.0,
    cache_dir: Path | None = None,
    mount_pitch_deg: float = MOUNT_PITCH_DEG,
) -> RobotModel:
    """Two iiwa arms at robot-frame y = +-arm_separation/2 on pedestals, facing +x.

    The arm bases lean forward by ``mount_pitch_deg`` about the robot's y axis: upright arms
    fall up to 5 cm short of the far, low corner of the table workspace.

    Parameters
    ----------
    base_position : tuple of float
        (3,) robot frame origin in the world (floor level, between the arms), m.
    base_rpy_deg : tuple of float
        (3,) robot frame roll, pitch, yaw in the world, degrees (only yaw is meaningful).
    arm_separation : float
        Distance between the two arm bases, m.
    mount_height : float
        Height of the arm bases above the robot frame origin, m.
    palm_size : tuple of float
        (3,) palm box extent, m.
    palm_friction : float
        Palm lateral friction coefficient.
    cache_dir : Path, optional
        Where the generated URDF goes.
    mount_pitch_deg : float
        Forward lean of both arm bases, degrees.

    Returns
    -------
    RobotModel
    """
    if arm_separation <= 0.0 or mount_height <= 0.0:
        raise ValueError(
            "kuka_iiwa_model: expected arm_separation > 0 and mount_height > 0, "
            f"got {arm_separation} and {mount_height}"
        )
    if min(palm_size) <= 0.0:
        raise ValueError(f"kuka_iiwa_model: expected positive palm_size, got {palm_size}")
    palm_size = (float(palm_size[0]), float(palm_size[1]), float(palm_size[2]))
    urdf = write_kuka_palm_urdf(
        palm_size, mount_height, palm_friction, cache_dir, mount_pitch_deg=mount_pitch_deg
    )
    robot2world_quaternion = quat.from_rpy(np.radians(base_rpy_deg))
    lean = quat.from_axis_angle([0.0, 1.0, 0.0], math.radians(mount_pitch_deg))
    x, y, z, w = quat.multiply(robot2world_quaternion, lean).tolist()
    base2world_quaternion = (x, y, z, w)
    bodies = []
    for side in (1.0, -1.0):
        offset = (0.0, side * arm_separation / 2.0, mount_height)
        position = quat.rotate(robot2world_quaternion, offset).tolist()
        bodies.append(
            BodySpec(
                urdf_path=urdf,
                base2world_position=(
                    base_position[0] + position[0],
                    base_position[1] + position[1],
                    base_position[2] + position[2],
                ),
                base2world_quaternion=base2world_quaternion,
            )
        )
    lower = (
        -2.96705972839,
        -2.09439510239,
        -2.96705972839,
        -2.09439510239,
        -2.96705972839,
        -2.09439510239,
        -3.05432619099,
    )
    upper = tuple(-v for v in lower)
    # Mirror about the x-z plane: the joints whose axes lie in that plane at zero (1, 3, 5, 7)
    # flip sign. The palm offset is along the flange's x axis, so the mirrored palm still has
    # its x axis down and needs no extra turn of the last joint.
    mirror = (-1.0, 1.0, -1.0, 1.0, -1.0, 1.0, -1.0)
    right_rest = tuple(m * q for m, q in zip(mirror, LEFT_REST, strict=True))
    arms = {
        arm: ArmSpec(
            body=index,
            joint_indices=tuple(range(N_JOINTS)),
            palm_link=N_JOINTS,
            rest_posture=rest,
            lower=lower,
            upper=upper,
            max_torque=MAX_TORQUE,
            palm_size=palm_size,
            end_effector=END_EFFECTOR,
        )
        for index, (arm, rest) in enumerate(((Arm.LEFT, LEFT_REST), (Arm.RIGHT, right_rest)))
    }
    return RobotModel(
        name="kuka_iiwa",
        bodies=tuple(bodies),
        arms=arms,
        palm2flange_position=palm2flange_position(palm_size),
        forearm_link_names={arm: FOREARM_LINKS for arm in (Arm.LEFT, Arm.RIGHT)},
        # The LBR iiwa senses the torque at every joint.
        torque_loop=TorqueLoop(),
    )


__all__ = ["kuka_iiwa_model", "kuka_palm_urdf_text", "palm2flange_position", "write_kuka_palm_urdf"]

"""The iCub humanoid with flat palms, fixed at its waist behind a table, its torso driven.

The URDF is generated at run time from the ``icub-models`` package (``iCubGazeboV2_5``):

* Only links with mass are kept; the sensor, skin and DH frames (massless links on fixed joints,
  about 170 of them) are dropped, so PyBullet loads the robot without
  ``URDF_MERGE_FIXED_LINKS`` (which would also merge the palm boxes into the hands and lose the
  palm frames the controller needs).
* The torso's three joints (pitch, roll, yaw) and the two 7-DoF arms move; every other joint
  (legs, neck) becomes a fixed joint: the task does not use them, and a fixed joint cannot sag.
* A thin palm box (``l_palm``, ``r_palm``) is added on a fixed joint on the inner face of each
  hand: the hand mesh's convex hull (fingers curled, thumb out) is no flat contact face.
* The robot is one body: the torso moves both shoulders, so one controller drives the torso
  and both arms together (:class:`worlds.robots.model.SharedJointsSpec`). Its links are ordered
  trunk first, then the left arm shoulder to palm, then the right arm: the FCL mirror
  (:mod:`worlds.collision`) takes the links just before each palm as its forearm. The two arms'
  links collide with each other and with nothing else of the body (:mod:`worlds.bodies`).

Frames: the iCub's root link has x backwards, y to the robot's right and z up; the robot frame
of the world file (x forward, left arm at +y) is the root link turned by 180 degrees about z.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from skills import quaternion as quat
from skills.vocabulary import Arm, EndEffector
from worlds.actuators import TorqueLoop
from worlds.robots.cache import cached_urdf
from worlds.robots.model import ArmSpec, BodySpec, RobotModel, SharedJointsSpec

#: The icub-models robot the model is built from.
ICUB_VARIANT = "iCubGazeboV2_5"
ARM_JOINTS = (
    "shoulder_pitch",
    "shoulder_roll",
    "shoulder_yaw",
    "elbow",
    "wrist_prosup",
    "wrist_pitch",
    "wrist_yaw",
)
#: Links of one arm, shoulder to hand, without the side prefix.
ARM_LINKS = (
    "shoulder_1",
    "shoulder_2",
    "shoulder_3",
    "upper_arm",
    "elbow_1",
    "forearm",
    "wrist_1",
    "hand",
)
#: The links of an arm counted as its forearm in the trials' figures (the palm apart).
FOREARM_LINKS = ("forearm", "wrist_1", "hand")
#: The torso's joints, root first: they move both shoulders.
TORSO_JOINTS = ("torso_pitch", "torso_roll", "torso_yaw")
#: Torque limits per arm joint, N m. The URDF says 50000; these are of the order of the real
#: iCub's motors (shoulder and elbow tens of N m, the wrist a few).
MAX_TORQUE = (30.0, 30.0, 15.0, 15.0, 6.0, 6.0, 6.0)
#: Torque limits of the torso joints, N m: the pitch holds the chest, head and both arms
#: (about 13 kg, their centre some 0.1 m ahead of the axis once leaning); of the order of the
#: real iCub's torso motors.
TORSO_MAX_TORQUE = (60.0, 40.0, 30.0)
#: Rest posture of the torso, rad: upright. The null-space term pulls it back there.
TORSO_REST = (0.0, 0.0, 0.0)
#: The torso's null-space posture spring and damper relative to the arms': firmer, so that
#: it stays upright unless the palms need it.
TORSO_POSTURE_WEIGHT = 8.0
#: Inner face of the hand's collision hull along the hand frame's -y axis, m (both hands).
HAND_INNER_FACE_Y = -0.018
#: Palm centre along the fingers (hand x, left; -x right) and towards the thumb (hand z), m.
#: Thumbs point up in the lateral grasp: the palm centre 1 cm below the wrist axis keeps the
#: forearm (about 3.5 cm in radius) off the table when the parcel is held at mid-height.
PALM_ALONG_FINGERS = 0.06
PALM_TOWARDS_THUMB = -0.01
#: Turn of the palm about its normal on the hand, rad. The wrist yaw axis is the palm normal,
#: so this joint alone keeps the palm's x axis down while the forearm's slope changes (about
#: 0.05 rad per cm of lift) in its narrow range (-0.35..0.44 rad); the turn centres it over
#: the table workspace (at 0.05 rad the start postures sat on the lower limit).
PALM_TWIST = -0.15
#: The hands carry a flat palm box and their fingers stay curled: flat palms, no gripper.
END_EFFECTOR = EndEffector.FLAT_PALM
#: Gap between the hand's hull and the palm box, m.
PALM_CLEARANCE = 0.002
#: Rest posture of an arm, rad: forearm forward, palm facing the robot's midline. The iCub's
#: arm joints are mirrored, so the same values give the mirrored posture of the right arm.
LEFT_REST = (-0.9, 0.35, 0.3, 1.2, 0.0, 0.0, 0.0)
#: Root link frame in the robot frame: turned by pi about z (the root's x points backwards).
_ROOT2ROBOT = quat.from_axis_angle([0.0, 0.0, 1.0], math.pi)


def icub_source() -> Path:
    """Path of the icub-models URDF the model is built from."""
    import icub_models

    return Path(icub_models.get_model_file(ICUB_VARIANT))


def _origin(parent: ET.Element, xyz: tuple[float, ...], rpy: tuple[float, ...] = (0, 0, 0)) -> None:
    ET.SubElement(
        parent,
        "origin",
        xyz=" ".join(f"{v:.9g}" for v in xyz),
        rpy=" ".join(f"{v:.9g}" for v in rpy),
    )


def _set_origin(element: ET.Element, xyz: np.ndarray, rotation: np.ndarray) -> None:
    for old in element.findall("origin"):
        element.remove(old)
    rpy = quat.to_rpy(rotation)
    origin = ET.Element(
        "origin",
        xyz=" ".join(f"{v:.9g}" for v in xyz),
        rpy=" ".join(f"{v:.9g}" for v in rpy),
    )
    element.insert(0, origin)


def palm_link_name(side: str) -> str:
    """The palm link of the ``side`` ("l" or "r") hand."""
    return f"{side}_palm"


def _palm_link(robot: ET.Element, side: str, palm_size: tuple[float, float, float]) -> None:
    """Append a palm box link (:func:`palm_link_name`) on a fixed joint on a hand's inner face."""
    palm = ET.SubElement(robot, "link", name=palm_link_name(side))
    inertial = ET.SubElement(palm, "inertial")
    _origin(inertial, (0.0, 0.0, 0.0))
    ET.SubElement(inertial, "mass", value="0.05")
    ET.SubElement(
        inertial, "inertia", ixx="3e-5", ixy="0", ixz="0", iyy="2e-5", iyz="0", izz="4e-5"
    )
    for tag in ("visual", "collision"):
        element = ET.SubElement(palm, tag)
        _origin(element, (0.0, 0.0, 0.0))
        geometry = ET.SubElement(element, "geometry")
        ET.SubElement(geometry, "box", size=" ".join(f"{v:.6g}" for v in palm_size))
    joint = ET.SubElement(robot, "joint", name=f"{side}_palm_joint", type="fixed")
    ET.SubElement(joint, "parent", link=f"{side}_hand")
    ET.SubElement(joint, "child", link=palm_link_name(side))
    position, rotation = palm2hand(side, palm_size)
    _set_origin(joint, position, rotation)


def palm2hand(side: str, palm_size: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Palm frame in the hand link frame: position (3,) m and orientation (4,).

    The palm's z axis (contact normal) is the hand's -y axis (out of the inner face), its y
    axis runs along the hand's x (the fingers of the left hand; the right hand's point along -x)
    and its x axis away from the thumb, so that in the lateral
    grasp (palm x down) the fingers point forward and the thumbs up.
    """
    fingers = 1.0 if side == "l" else -1.0  # the right hand frame is the mirror, x reversed
    y = HAND_INNER_FACE_Y - PALM_CLEARANCE - palm_size[2] / 2.0
    position = np.array([fingers * PALM_ALONG_FINGERS, y, PALM_TOWARDS_THUMB])
    # Columns: palm x, y, z in the hand frame; y = z x x is the hand's x for both hands.
    matrix = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, -1.0], [-1.0, 0.0, 0.0]])
    twist = quat.from_rotation_vector([0.0, 0.0, -fingers * PALM_TWIST])
    return position, quat.multiply(quat.from_matrix(matrix), twist)


def _arm_link_names(side: str) -> set[str]:
    return {f"{side}_{name}" for name in ARM_LINKS}


def icub_urdf_text(palm_size: tuple[float, float, float], palm_friction: float) -> str:
    """URDF text of the iCub as one body: torso and arms movable, legs and neck fixed.

    Parameters
    ----------
    palm_size : tuple of float
        (3,) palm box extent along the palm frame's x, y, z, m.
    palm_friction : float
        Lateral friction coefficient of the palms.

    Returns
    -------
    str
    """
    source = icub_source()
    package_root = source.parents[3]  # share/iCub/robots/<variant>/model.urdf -> share
    robot = ET.parse(source).getroot()
    for mesh in robot.iter("mesh"):
        filename = mesh.get("filename", "")
        if filename.startswith("package://"):
            mesh.set("filename", str(package_root / filename[len("package://") :]))
    for element in list(robot):
        if element.tag not in ("link", "joint"):
            robot.remove(element)
    # Massless frames go; every kept link has a kept parent in this model.
    kept = {_name(ln) for ln in robot.findall("link") if ln.find("inertial") is not None}
    for link in robot.findall("link"):
        if _name(link) not in kept:
            robot.remove(link)
    moving = {f"{side}_{name}" for side in "lr" for name in ARM_JOINTS} | set(TORSO_JOINTS)
    for joint in robot.findall("joint"):
        if _child(joint) not in kept:
            robot.remove(joint)
            continue
        for dynamics in joint.findall("dynamics"):
            joint.remove(dynamics)
        if _name(joint) in moving:
            # The file's axes are unit to 6 digits; PyBullet's inverse dynamics (the
            # controller's gravity and inertia) warns on every body it builds unless exact.
            for axis in joint.findall("axis"):
                xyz = np.array([float(v) for v in axis.get("xyz", "1 0 0").split()])
                axis.set("xyz", " ".join(repr(float(v)) for v in xyz / np.linalg.norm(xyz)))
            continue
        if joint.get("type") == "fixed":
            continue
        joint.set("type", "fixed")
        for tag in ("axis", "limit"):
            for sub in joint.findall(tag):
                joint.remove(sub)
    return _body_text(robot, palm_size, palm_friction)


def _name(element: ET.Element) -> str:
    return element.get("name", "")


def _child(joint: ET.Element) -> str:
    child = joint.find("child")
    return child.get("link", "") if child is not None else ""


def _parent(joint: ET.Element) -> str:
    parent = joint.find("parent")
    return parent.get("link", "") if parent is not None else ""


def _body_text(
    robot: ET.Element, palm_size: tuple[float, float, float], palm_friction: float
) -> str:
    """URDF text of ``robot`` with a palm on each hand, its joints ordered for PyBullet."""
    out = ET.Element("robot", name="duet_icub")
    links = list(robot.findall("link"))
    joints = list(robot.findall("joint"))
    for side in "lr":
        _palm_link(out, side, palm_size)
    palms = [ln for ln in out.findall("link")]
    palm_joints = [j for j in out.findall("joint")]
    for element in palms + palm_joints:
        out.remove(element)
    links.extend(palms)
    joints.extend(palm_joints)
    # PyBullet numbers links depth first, children in file order: the joints on the way from
    # the root to the palms go last, the left arm's before the right's, so the trunk's links
    # come first, then each arm's shoulder to palm (the FCL mirror takes the links just before
    # a palm as its forearm).
    parent_of = {_child(j): _parent(j) for j in joints}
    rank: dict[str, int] = {}
    for order, side in ((1, "l"), (2, "r")):
        link_name: str | None = palm_link_name(side)
        while link_name is not None:
            rank.setdefault(link_name, order)
            link_name = parent_of.get(link_name)
    joints.sort(key=lambda j: rank.get(_child(j), 0))
    out.extend(links)
    out.extend(joints)
    for side in "lr":
        palm = out.find(f"link[@name='{palm_link_name(side)}']")
        assert palm is not None
        contact = ET.SubElement(palm, "contact")
        ET.SubElement(contact, "lateral_friction", value=f"{palm_friction:.6g}")
    return ET.tostring(out, encoding="unicode")


def icub_model(
    base_position: tuple[float, float, float] = (0.0, 0.0, 0.0),
    base_rpy_deg: tuple[float, float, float] = (0.0, 0.0, 0.0),
    arm_separation: float | None = None,
    mount_height: float = 0.6,
    palm_size: tuple[float, float, float] = (0.05, 0.06, 0.01),
    palm_friction: float = 1.0,
    cache_dir: Path | None = None,
) -> RobotModel:
    """The iCub fixed at its root link (the waist), facing the robot frame's +x.

    Parameters
    ----------
    base_position : tuple of float
        (3,) robot frame origin in the world (floor level, under the waist), m.
    base_rpy_deg : tuple of float
        (3,) robot frame roll, pitch, yaw in the world, degrees.
    arm_separation : float, optional
        Not a free parameter for iCub (the shoulders are 0.24 m apart); accepted so that world
        files keep one robot schema.
    mount_height : float
        Height of the root link (waist) above the robot frame origin, m.
    palm_size : tuple of float
        (3,) palm box extent, m.
    palm_friction : float
        Palm lateral friction coefficient.
    cache_dir : Path, optional
        Where the generated URDF goes.

    Returns
    -------
    RobotModel
    """
    del arm_separation
    if mount_height <= 0.0:
        raise ValueError(f"icub_model: expected mount_height > 0, got {mount_height}")
    if min(palm_size) <= 0.0:
        raise ValueError(f"icub_model: expected positive palm_size, got {palm_size}")
    palm_size = (float(palm_size[0]), float(palm_size[1]), float(palm_size[2]))
    text = icub_urdf_text(palm_size, palm_friction)
    urdf = cached_urdf(text, "icub", cache_dir)
    robot2world = quat.from_rpy(np.radians(base_rpy_deg))
    root2world = quat.multiply(robot2world, _ROOT2ROBOT)
    root_position = np.asarray(base_position, float) + quat.rotate(
        robot2world, [0, 0, mount_height]
    )

    def quat4(rotation: np.ndarray) -> tuple[float, float, float, float]:
        x, y, z, w = (float(v) for v in rotation)
        return (x, y, z, w)

    def vec(v: np.ndarray) -> tuple[float, float, float]:
        return (float(v[0]), float(v[1]), float(v[2]))

    links, joints = _link_and_joint_order(text)
    limits = _joint_limits(text)
    arms = {}
    for arm, side in ((Arm.LEFT, "l"), (Arm.RIGHT, "r")):
        names = [f"{side}_{n}" for n in ARM_JOINTS]
        lower = tuple(limits[n][0] for n in names)
        upper = tuple(limits[n][1] for n in names)
        rest = tuple(
            float(np.clip(q, lo, hi)) for q, lo, hi in zip(LEFT_REST, lower, upper, strict=True)
        )
        arms[arm] = ArmSpec(
            body=0,
            joint_indices=tuple(joints.index(n) for n in names),
            palm_link=links.index(palm_link_name(side)),
            rest_posture=rest,
            lower=lower,
            upper=upper,
            max_torque=MAX_TORQUE,
            palm_size=palm_size,
            end_effector=END_EFFECTOR,
            palm_link_name=palm_link_name(side),
        )
    torso = SharedJointsSpec(
        body=0,
        joint_indices=tuple(joints.index(n) for n in TORSO_JOINTS),
        rest_posture=TORSO_REST,
        lower=tuple(limits[n][0] for n in TORSO_JOINTS),
        upper=tuple(limits[n][1] for n in TORSO_JOINTS),
        max_torque=TORSO_MAX_TORQUE,
        posture_weight=TORSO_POSTURE_WEIGHT,
    )
    position, _ = palm2hand("l", palm_size)
    return RobotModel(
        name="icub",
        bodies=(BodySpec(urdf, vec(root_position), quat4(root2world)),),
        arms=arms,
        palm2flange_position=vec(position),
        # Its arms reach about 0.3 m from shoulders 0.24 m apart: the palms wait closer in.
        rest_palms=(0.08, 0.14, 0.10),
        # The controller's implicit damping scales the static spring by less than one where
        # the inertia is small: on the light iCub arm the default gains squeeze 79 % of
        # stiffness * offset (11.8 N for 15 N asked); less damping brings it to about 89 %
        # (13.4 N), above the grasp's 80 % threshold, and stays stable (tests/worlds/test_icub.py).
        # Its whole body sways in the palms' null space at 1.4 Hz (torso pitch against the
        # shoulders) after a 3 cm step of both palms. With the joint damper at 0.05 and the
        # posture damper at 0.2 the sway decayed over about 6 s at no lag and grew under a
        # 30 ms lag with one tick of latency (torso pitch rate 0.09 to 0.34 rad/s rms over 6 s):
        # the arms then shook the parcel out of the grip. At 0.6 and 1.0 it decays within 2 s
        # from no lag to 30 ms, and the palms settle under a 40 ms lag
        # (tests/worlds/test_torque_loop.py).
        # Pressed to its limit under a 13 ms actuator lag, a wrist's yaw sang at 20 Hz on the
        # 50 N m/rad repulsion (Hard trial 19 of seed 0) and shook the parcel out of the grip;
        # at 15 it rests. Hard, first 60 trials of seed 0: 58 (51 before); Easy, 100 trials:
        # 100, as before; the reach map (below) 0.4 mm worse at 6 of 147 points, up to 1.7 mm
        # better at 46, the same regions within 3 mm.
        # The wrists' ranges are narrow (yaw -20..25 deg): the default joint-limit band
        # (8.6 deg at 200 N m/rad, beyond the wrist motors) pushes back over a third of one.
        # A 1.7 deg band at 50 N m/rad (15 since) cut the palm error holding the parcel at
        # table height from 2.7-6.1 mm to 0.8-2.4 mm over x 0.24-0.32 m, y -0.04-0.04 m, and
        # at x 0.24, y 0.08 from 6.0 to 1.1 mm (bench/reach_map.py, torso fixed).
        # With the torso driven, a palm far to one side brings the other arm's shoulder roll to
        # its limit (the arm reaching across the chest): a posture pull out of a 0.15 rad band
        # at each limit, in the palms' null space, turns the torso to spare it. It cut the
        # palm error at (0.29, 0.12), (0.29, 0.16) and (0.25, 0.12) m at table height from 9.2,
        # 16.1 and 9.8 mm to 1.4, 2.8 and 1.1 mm (bench/reach_map.py).
        gain_overrides={
            "damping_linear": 30.0,
            "damping_angular": 0.5,
            "joint_damping": 0.6,
            "damping_null": 1.0,
            "limit_margin": 0.03,
            "limit_stiffness": 15.0,
            "posture_limit_band": 0.15,
            "posture_limit_weight": 20.0,
        },
        arm_link_names={
            arm: frozenset(_arm_link_names(side) | {palm_link_name(side)})
            for arm, side in ((Arm.LEFT, "l"), (Arm.RIGHT, "r"))
        },
        shoulder_at_first_joint=True,
        shared_joints=torso,
        forearm_link_names={
            arm: frozenset(f"{side}_{name}" for name in FOREARM_LINKS)
            for arm, side in ((Arm.LEFT, "l"), (Arm.RIGHT, "r"))
        },
        # The iCub estimates its arms' joint torques from the force-torque sensors in its
        # upper arms (and the torso's from the rest of its model). Its light arms flail under
        # a 30 ms actuator lag (every joint; the palms 0.1 m off a 3 cm step) unless the loop
        # also feeds the gap back at once: at 0.5 they settle within 4 mm, lag 0 to 30 ms.
        torque_loop=TorqueLoop(proportional=0.5),
    )


def _link_and_joint_order(text: str) -> tuple[list[str], list[str]]:
    """PyBullet's link and joint names by index: joint i has child link i (depth first, in
    file order; checked against PyBullet in tests/worlds/test_icub.py)."""
    robot = ET.fromstring(text)
    children: dict[str, list[ET.Element]] = {}
    for joint in robot.findall("joint"):
        children.setdefault(_parent(joint), []).append(joint)
    child_links = {_child(j) for j in robot.findall("joint")}
    root = next(_name(ln) for ln in robot.findall("link") if _name(ln) not in child_links)
    links: list[str] = []
    joints: list[str] = []

    def visit(link: str) -> None:
        for joint in children.get(link, []):
            links.append(_child(joint))
            joints.append(_name(joint))
            visit(_child(joint))

    visit(root)
    return links, joints


def _joint_limits(text: str) -> dict[str, tuple[float, float]]:
    limits = {}
    for joint in ET.fromstring(text).findall("joint"):
        limit = joint.find("limit")
        if limit is not None:
            limits[joint.get("name", "")] = (
                float(limit.get("lower", 0)),
                float(limit.get("upper", 0)),
            )
    return limits


__all__ = ["icub_model", "icub_source", "icub_urdf_text", "palm2hand", "palm_link_name"]

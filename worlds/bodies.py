"""PyBullet bodies of a scene: the robot's URDFs, the table, objects and obstacles.

Each function creates bodies in the given client from :mod:`worlds.spec` values and returns
their ids; :class:`worlds.scene.Scene` calls them in a fixed order (PyBullet's results depend
on the order bodies are created in).
"""

from __future__ import annotations

import os
import socket
import sys
from collections.abc import Sequence

import pybullet as pb

from skills.vocabulary import Arm
from worlds.robots import RobotModel, robot_model_of
from worlds.spec import ObjectSpec, ObstacleSpec, RobotSpec, Shape, ShapeSpec, TableSpec

TABLE_RGBA = (0.6, 0.45, 0.3, 1.0)
OBJECT_RGBA = (0.8, 0.6, 0.35, 1.0)
OBSTACLE_RGBA = (0.8, 0.2, 0.2, 1.0)


def build_robot(spec: RobotSpec) -> RobotModel:
    """The robot model ``spec`` describes (:func:`worlds.robots.robot_model_of`)."""
    return robot_model_of(spec)


#: Collision filter bits of a body that carries both arms (PyBullet's defaults: 1 for dynamic
#: bodies, 2 for static ones, every other body colliding with every group).
_DYNAMIC, _STATIC, _TRUNK, _LEFT, _RIGHT = 1, 2, 4, 8, 16


def load_robot(client: int, robot: RobotModel) -> tuple[int, ...]:
    """Load the robot's bodies with fixed bases, exclude its collision pairs and put its arms
    and shared joints in their rest postures; returns the body ids in
    :attr:`RobotModel.bodies` order.

    On a body that carries both arms, the two arms' links collide with each other (as two
    bodies' would) and with nothing else of the body."""
    shared_bodies = {spec.body for spec in robot.arms.values()}
    both_arms = len(shared_bodies) == 1
    robot_ids = tuple(
        pb.loadURDF(
            str(body.urdf_path),
            body.base2world_position,
            body.base2world_quaternion,
            useFixedBase=True,
            flags=pb.URDF_USE_INERTIA_FROM_FILE
            | (pb.URDF_USE_SELF_COLLISION if both_arms and index in shared_bodies else 0),
            physicsClientId=client,
        )
        for index, body in enumerate(robot.bodies)
    )
    exclude_collisions(client, robot, robot_ids)
    if both_arms:
        _arms_collide_only_with_each_other(client, robot, robot_ids)
    for joint in robot.driven_joints():
        pb.resetJointState(
            robot_ids[joint.body], joint.joint, joint.rest, 0.0, physicsClientId=client
        )
    return robot_ids


def arm_link_indices(
    client: int, robot: RobotModel, robot_ids: Sequence[int]
) -> dict[Arm, frozenset[int] | None]:
    """Each arm's links on its body (-1 the base): None when the arm has its body to itself.

    On a body that carries both arms, an arm's links are those of
    :attr:`RobotModel.arm_link_names`; the rest of the body (a humanoid's trunk) goes with the
    left arm, as it does in the FCL mirror's groups (:mod:`worlds.collision`).
    """
    out: dict[Arm, frozenset[int] | None] = {}
    for arm in (Arm.LEFT, Arm.RIGHT):
        spec = robot.arms[arm]
        others = [a for a in (Arm.LEFT, Arm.RIGHT) if a != arm and robot.arms[a].body == spec.body]
        if not others:
            out[arm] = None
            continue
        body = robot_ids[spec.body]
        names = _link_names(client, body)
        own = robot.arm_link_names.get(arm, frozenset())
        other_links = frozenset().union(*(robot.arm_link_names.get(a, frozenset()) for a in others))
        if arm is Arm.LEFT:
            out[arm] = frozenset(i for name, i in names.items() if name not in other_links)
        else:
            out[arm] = frozenset(i for name, i in names.items() if name in own)
    return out


def _link_names(client: int, body: int) -> dict[str, int]:
    names = {"base": -1}
    for j in range(pb.getNumJoints(body, physicsClientId=client)):
        names[pb.getJointInfo(body, j, physicsClientId=client)[12].decode()] = j
    return names


def exclude_collisions(client: int, robot: RobotModel, robot_ids: Sequence[int]) -> None:
    """Switch off the robot's :attr:`RobotModel.collision_exclusions` link pairs."""
    if not robot.collision_exclusions:
        return
    indices = [_link_names(client, body) for body in robot_ids]
    for body_a, link_a, body_b, link_b in robot.collision_exclusions:
        pb.setCollisionFilterPair(
            robot_ids[body_a],
            robot_ids[body_b],
            indices[body_a][link_a],
            indices[body_b][link_b],
            enableCollision=0,
            physicsClientId=client,
        )


def _arms_collide_only_with_each_other(
    client: int, robot: RobotModel, robot_ids: Sequence[int]
) -> None:
    """Filter groups on the body that carries both arms: each arm's links collide with the
    other arm's and with other bodies; the trunk's with other bodies only."""
    body = robot_ids[robot.arms[Arm.LEFT].body]
    left = robot.arm_link_names.get(Arm.LEFT, frozenset())
    right = robot.arm_link_names.get(Arm.RIGHT, frozenset())
    everything = _DYNAMIC | _STATIC
    for name, link in _link_names(client, body).items():
        if name in left:
            group, mask = _LEFT, everything | _RIGHT
        elif name in right:
            group, mask = _RIGHT, everything | _LEFT
        else:
            group, mask = _TRUNK, everything
        pb.setCollisionFilterGroupMask(body, link, group, mask, physicsClientId=client)


def create_table(client: int, table: TableSpec) -> int:
    """The static table box, its top surface centred on ``table.position``; its body id."""
    half = (table.size[0] / 2.0, table.size[1] / 2.0, table.size[2] / 2.0)
    col = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=half, physicsClientId=client)
    vis = pb.createVisualShape(
        pb.GEOM_BOX, halfExtents=half, rgbaColor=list(TABLE_RGBA), physicsClientId=client
    )
    body = pb.createMultiBody(
        0.0,
        col,
        vis,
        basePosition=[table.position[0], table.position[1], table.position[2] - half[2]],
        physicsClientId=client,
    )
    pb.changeDynamics(body, -1, lateralFriction=table.friction, physicsClientId=client)
    return int(body)


def create_object(client: int, obj: ObjectSpec) -> int:
    """A movable object at its initial pose, no spinning or rolling friction; its body id."""
    col, vis = shape_ids(client, obj.shape, OBJECT_RGBA)
    body = pb.createMultiBody(
        obj.mass,
        col,
        vis,
        basePosition=obj.position,
        baseOrientation=obj.quaternion,
        physicsClientId=client,
    )
    pb.changeDynamics(
        body,
        -1,
        lateralFriction=obj.friction,
        spinningFriction=0.0,
        rollingFriction=0.0,
        physicsClientId=client,
    )
    return int(body)


def create_obstacle(client: int, obstacle: ObstacleSpec, position: Sequence[float]) -> int:
    """A static obstacle at ``position`` (3,), m (where it waits while inactive); its body id."""
    col, vis = shape_ids(client, obstacle.shape, OBSTACLE_RGBA)
    return int(
        pb.createMultiBody(0.0, col, vis, basePosition=list(position), physicsClientId=client)
    )


def shape_ids(client: int, shape: ShapeSpec, rgba: Sequence[float]) -> tuple[int, int]:
    """Collision and visual shape ids of ``shape``, coloured ``rgba`` (4,)."""
    if shape.is_tray:
        # One body of five boxes: a loose item inside rolls on the floor against the walls.
        boxes = shape.tray_boxes()
        halves = [list(h) for h, _ in boxes]
        centres = [list(c) for _, c in boxes]
        col = pb.createCollisionShapeArray(
            [pb.GEOM_BOX] * len(boxes),
            halfExtents=halves,
            collisionFramePositions=centres,
            physicsClientId=client,
        )
        vis = pb.createVisualShapeArray(
            [pb.GEOM_BOX] * len(boxes),
            halfExtents=halves,
            visualFramePositions=centres,
            rgbaColors=[list(rgba)] * len(boxes),
            physicsClientId=client,
        )
    elif shape.kind == Shape.BOX:
        half = [s / 2.0 for s in shape.size]
        col = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=half, physicsClientId=client)
        vis = pb.createVisualShape(
            pb.GEOM_BOX, halfExtents=half, rgbaColor=list(rgba), physicsClientId=client
        )
    elif shape.kind == Shape.SPHERE:
        col = pb.createCollisionShape(pb.GEOM_SPHERE, radius=shape.radius, physicsClientId=client)
        vis = pb.createVisualShape(
            pb.GEOM_SPHERE, radius=shape.radius, rgbaColor=list(rgba), physicsClientId=client
        )
    elif shape.kind == Shape.CYLINDER:
        col = pb.createCollisionShape(
            pb.GEOM_CYLINDER, radius=shape.radius, height=shape.height, physicsClientId=client
        )
        vis = pb.createVisualShape(
            pb.GEOM_CYLINDER,
            radius=shape.radius,
            length=shape.height,
            rgbaColor=list(rgba),
            physicsClientId=client,
        )
    else:
        scale = [shape.scale] * 3
        col = pb.createCollisionShape(
            pb.GEOM_MESH, fileName=str(shape.mesh_path), meshScale=scale, physicsClientId=client
        )
        vis = pb.createVisualShape(
            pb.GEOM_MESH,
            fileName=str(shape.mesh_path),
            meshScale=scale,
            rgbaColor=list(rgba),
            physicsClientId=client,
        )
    return col, vis


def x_display_reachable(display: str, timeout_s: float = 2.0) -> bool:
    """Whether an X server accepts connections at ``display`` (``:0``, ``host:10.0``).

    Connects to its socket (``/tmp/.X11-unix/X<n>`` for a local display, TCP port 6000 + n
    for a host) and closes it again; no X protocol is spoken.
    """
    host, _, rest = display.rpartition(":")
    number = rest.split(".", 1)[0]
    if not number.isdigit():
        return False
    try:
        if host in ("", "unix"):
            with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as sock:
                sock.settimeout(timeout_s)
                sock.connect(f"/tmp/.X11-unix/X{number}")
        else:
            with socket.create_connection((host, 6000 + int(number)), timeout=timeout_s):
                pass
    except OSError:
        return False
    return True


class NoDisplayError(RuntimeError):
    """PyBullet's window was asked for where there is no display."""


def connect(gui: bool) -> int:
    """A PyBullet client: DIRECT by default, a window (GUI) when asked and a display exists.

    Raises
    ------
    NoDisplayError
        If ``gui`` is asked for and no display is available (``DISPLAY`` unset or refused).
    """
    if not gui:
        return int(pb.connect(pb.DIRECT))
    display = os.environ.get("DISPLAY", "")
    if sys.platform.startswith("linux"):
        if not display:
            raise NoDisplayError(
                "--gui: expected a display (DISPLAY is not set); run without --gui"
            )
        # PyBullet's C code exits the process (status 1) when it cannot reach the X server:
        # ask the server's socket first.
        if not x_display_reachable(display):
            raise NoDisplayError(
                f"--gui: expected a display, but nothing answers at DISPLAY={display!r}; "
                "run without --gui"
            )
    client = int(pb.connect(pb.GUI))
    if client < 0:
        raise NoDisplayError("--gui: PyBullet could not open a window on this display")
    return client


__all__ = [
    "NoDisplayError",
    "arm_link_indices",
    "build_robot",
    "connect",
    "create_object",
    "create_obstacle",
    "create_table",
    "exclude_collisions",
    "load_robot",
    "shape_ids",
]

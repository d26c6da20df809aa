"""Views of a world for the other packages: affordance contexts and robot capabilities.

The affordance reasoner knows nothing of world files; these functions translate the core's
:class:`worlds.spec.WorldSpec` (a validated ``World`` is converted at the entry).
"""

from __future__ import annotations

import math

from affordances import ObjectContext, RobotCapabilities
from affordances.context import Obstacle
from skills.flip import grasp_axis_turn
from worlds.mesh_sides import mesh_centre, squeeze_axes
from worlds.robots import robot_model_of
from worlds.spec import ObjectSpec, ObstacleSpec, RobotModelName, Shape, ShapeSpec, WorldSpec
from worlds.world_file import World, as_world_spec

# Reach of the two palms towards each other and apart, and palm friction, per robot model.
_SPANS_M: dict[RobotModelName, tuple[float, float, float]] = {
    RobotModelName.KUKA_IIWA: (0.10, 0.60, 0.8),
    # Shoulders 0.24 m apart, about 0.3 m from shoulder to palm: the palms meet in front of
    # the chest and spread to about the shoulders' width plus a forearm.
    RobotModelName.ICUB: (0.06, 0.30, 0.8),
}

#: Largest grip turn about the vertical, degrees, per robot model (``max_turn_rad``): the two
#: iiwas placed goals turned 45 degrees either way within 7 mm and 2 degrees, and 40 degrees
#: either side of their natural pose (an 80-degree turn) within 17 mm, the arms near their
#: reach; 45 is the least that reaches every yaw of a box (its faces come every quarter turn).
_MAX_TURN_DEG: dict[RobotModelName, float] = {
    RobotModelName.KUKA_IIWA: 45.0,
    RobotModelName.ICUB: 45.0,
}


def robot_capabilities(world: World | WorldSpec) -> RobotCapabilities:
    """What the world's robot can carry and squeeze and what its arms end in (its model's
    declared end-effectors), for the affordance reasoner."""
    robot = as_world_spec(world).scene.robot
    min_span, max_span, palm_mu = _SPANS_M.get(robot.model, (0.10, 0.60, 0.8))
    return RobotCapabilities(
        payload_per_arm_kg=robot.payload_kg,
        palm_size_m=robot.palm_size,
        max_span_m=max_span,
        min_span_m=min_span,
        squeeze_force_n=robot.squeeze_force_n,
        palm_friction=palm_mu,
        end_effectors=robot_model_of(robot).end_effectors,
        max_turn_rad=math.radians(_MAX_TURN_DEG.get(robot.model, 45.0)),
        base_pose=(
            float(robot.base_position[0]),
            float(robot.base_position[1]),
            math.radians(robot.base_rpy_deg[2]),
        ),
    )


def _dimensions(shape: ShapeSpec) -> tuple[float, ...]:
    """The reasoner's dimensions of a shape (see :class:`affordances.ObjectContext`), m."""
    if shape.kind is Shape.CYLINDER:
        return (shape.radius, shape.height)
    if shape.kind is Shape.SPHERE:
        return (shape.radius,)
    return shape.extents()  # box and mesh: bounding-box extents


def _obstacle(obstacle: ObstacleSpec) -> Obstacle:
    """The obstacle bounded by a sphere about its centre."""
    shape = obstacle.shape
    if shape.kind is Shape.SPHERE:
        return Obstacle(obstacle.name, obstacle.position, shape.radius)
    if shape.kind is Shape.CYLINDER:
        return Obstacle(
            obstacle.name, obstacle.position, math.hypot(shape.radius, shape.height / 2)
        )
    if shape.kind is Shape.MESH:  # about its bounding box's centre, which its file may offset
        x, y, z = (p + c for p, c in zip(obstacle.position, mesh_centre(shape), strict=True))
        return Obstacle.from_box(obstacle.name, (float(x), float(y), float(z)), shape.extents())
    return Obstacle.from_box(obstacle.name, obstacle.position, shape.extents())


def _object_context(
    obj: ObjectSpec, spec: WorldSpec, obstacles: tuple[Obstacle, ...]
) -> ObjectContext:
    moves = spec.moves_of(obj.name)
    return ObjectContext(
        name=obj.name,
        category=obj.category,
        shape=obj.shape.kind,
        dimensions=_dimensions(obj.shape),
        mass_kg=obj.mass,
        material=obj.material,
        friction=obj.friction,
        fragility=obj.fragility,
        state=frozenset(obj.state),
        position=obj.position,
        yaw=obj.yaw,
        obstacles=obstacles,
        goals=tuple(m.goal_position for m in moves),
        goal_yaw=moves[-1].goal_yaw if moves else None,
        goal_yaws=tuple(m.goal_yaw for m in moves),
        goal_grasp_turns=tuple(
            grasp_axis_turn(a, b)
            for a, b in zip(
                (obj.quaternion, *(m.goal_quaternion for m in moves)),
                (m.goal_quaternion for m in moves),
                strict=False,
            )
        ),
        goal_fixtures=tuple(m.fixture or "" for m in moves),
        squeeze_axes=squeeze_axes(obj.shape) if obj.shape.kind is Shape.MESH else (),
    )


def object_contexts(world: World | WorldSpec) -> list[ObjectContext]:
    """One affordance context per object, with the world's obstacles and its task goals."""
    spec = as_world_spec(world)
    obstacles = tuple(_obstacle(o) for o in spec.scene.obstacles)
    return [_object_context(obj, spec, obstacles) for obj in spec.scene.objects]

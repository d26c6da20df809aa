"""Views of a world file for the other packages: affordance contexts and robot capabilities.

The affordance reasoner knows nothing of world files; these functions translate.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

from affordances import ObjectContext, RobotCapabilities, make_object_context
from worlds.world_file import (
    BoxShape,
    CylinderShape,
    MeshShape,
    Robot,
    RobotModelName,
    SphereShape,
    World,
    WorldObject,
)

# Reach of the two palms towards each other and apart, and palm friction, per robot model.
_SPANS_M: dict[RobotModelName, tuple[float, float, float]] = {
    RobotModelName.KUKA_IIWA: (0.10, 0.60, 0.8),
    # Shoulders 0.24 m apart, about 0.3 m from shoulder to palm: the palms meet in front of
    # the chest and spread to about the shoulders' width plus a forearm.
    RobotModelName.ICUB: (0.06, 0.30, 0.8),
}


def robot_capabilities(world: World) -> RobotCapabilities:
    """What the world's robot can carry and squeeze, for the affordance reasoner."""
    robot: Robot = world.robot
    min_span, max_span, palm_mu = _SPANS_M.get(robot.model, (0.10, 0.60, 0.8))
    return RobotCapabilities(
        payload_per_arm_kg=robot.payload_kg,
        palm_size_m=tuple(robot.palm_size),  # type: ignore[arg-type]
        max_span_m=max_span,
        min_span_m=min_span,
        squeeze_force_n=robot.squeeze_force_n,
        palm_friction=palm_mu,
    )


def _shape_and_dimensions(
    obj: WorldObject, resolve: Callable[[str], Path]
) -> tuple[str, tuple[float, ...]]:
    """Shape name and dimensions, m; ``resolve`` turns a file's path into one to open."""
    shape = obj.shape
    if isinstance(shape, BoxShape):
        return "box", tuple(shape.size)
    if isinstance(shape, CylinderShape):
        return "cylinder", (shape.radius, shape.height)
    if isinstance(shape, SphereShape):
        return "sphere", (shape.radius,)
    if isinstance(shape, MeshShape):
        return "mesh", _mesh_extents(shape, resolve)
    raise TypeError(f"unknown shape {shape!r}")


def _mesh_extents(shape: MeshShape, resolve: Callable[[str], Path]) -> tuple[float, ...]:
    import trimesh

    # Relative to the world file's folder, as the scene loads it: not to the working directory.
    mesh = trimesh.load(resolve(shape.file), force="mesh")
    return tuple(float(e) * shape.scale for e in mesh.extents)


def _obstacle_plain(world: World) -> list[dict[str, Any]]:
    out: list[dict[str, Any]] = []
    for ob in world.obstacles:
        kind, dims = _shape_and_dimensions(ob, world.resolve_path)  # type: ignore[arg-type]
        entry: dict[str, Any] = {"name": ob.name, "position": list(ob.position)}
        if kind == "sphere":
            entry["radius"] = dims[0]
        elif kind == "cylinder":
            entry["radius"] = math.hypot(dims[0], dims[1] / 2.0)
        else:
            entry["size"] = list(dims)
        out.append(entry)
    return out


def object_contexts(world: World) -> list[ObjectContext]:
    """One affordance context per object, with the world's obstacles and its task goals."""
    obstacles = _obstacle_plain(world)
    contexts = []
    for obj in world.objects:
        kind, dims = _shape_and_dimensions(obj, world.resolve_path)
        moves = [m for step in world.task if step.object == obj.name for m in step.moves]
        goal_yaw = math.radians(moves[0].goal.rpy_deg[2]) if moves else None
        contexts.append(
            make_object_context(
                name=obj.name,
                category=obj.category,
                shape=kind,
                dimensions=dims,
                mass_kg=obj.mass,
                material=obj.material,
                friction=obj.friction,
                fragility=obj.fragility.value,
                state=[s.value for s in obj.state],
                position=list(obj.pose.position),
                yaw=math.radians(obj.pose.rpy_deg[2]),
                obstacles=obstacles,
                goals=[list(m.goal.position) for m in moves],
                goal_yaw=goal_yaw,
            )
        )
    return contexts

"""FCL shapes of the world's bodies: primitives, meshes as cached convex hulls, posed pairs.

A mesh collides as its convex hull (as PyBullet collides it), computed once per mesh content
with trimesh and read back from ``~/.cache/duet/hulls`` after (:func:`cached_mesh_hull`).
:func:`shape_geometry` gives each shape's FCL geometry with its bounding sphere, which
:class:`worlds.collision.CollisionWorld` prefilters with; :func:`penetration_depth` and
:func:`shape_gap` answer for two shapes at given poses, as the world file's checks ask
(:mod:`worlds.placement`).
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import fcl
import numpy as np
import pybullet as pb
from numpy.typing import ArrayLike, NDArray

from skills import file_cache
from skills import quaternion as quat
from worlds.spec import Shape, ShapeSpec

FloatArray = NDArray[np.float64]


def _convex_from_hull(vertices: FloatArray, faces: NDArray[np.int64]) -> fcl.Convex:
    """FCL's convex shape of a hull's vertices (V, 3) and triangles (F, 3)."""
    flat = np.hstack([np.full((len(faces), 1), 3), faces]).ravel()
    return fcl.Convex(vertices, len(faces), flat)


#: Bump when what :func:`_mesh_hull` computes changes: it names the cached hulls.
HULL_CACHE_VERSION = "1"

_MESH_CACHE: dict[tuple[str, float], tuple[fcl.Convex, FloatArray]] = {}


def _mesh_hull(path: Path, scale: float) -> tuple[FloatArray, NDArray[np.int64]]:
    """The convex hull of a mesh file scaled by ``scale``: vertices (V, 3), m, and triangles
    (F, 3), as trimesh computes it."""
    import trimesh  # here: only a mesh not in the hull cache needs it (a second to import)

    mesh = trimesh.load(path, force="mesh")
    if not isinstance(mesh, trimesh.Trimesh):
        raise ValueError(f"collision: expected a triangle mesh in {path}, got {type(mesh)}")
    mesh = mesh.copy()
    mesh.apply_scale(scale)
    hull = mesh.convex_hull
    return np.asarray(hull.vertices, dtype=float), np.asarray(hull.faces, dtype=np.int64)


def _hull_from_payload(payload: bytes) -> tuple[FloatArray, NDArray[np.int64]] | None:
    """A cached hull's arrays, or None if they are not a hull (then it is computed again)."""
    try:
        with np.load(io.BytesIO(payload), allow_pickle=False) as npz:
            vertices, faces = npz["vertices"], npz["faces"]
    except (ValueError, OSError, KeyError, EOFError):
        return None
    ok = (
        vertices.dtype == np.float64
        and vertices.ndim == 2
        and vertices.shape[1] == 3
        and faces.dtype == np.int64
        and faces.ndim == 2
        and faces.shape[1] == 3
        and len(faces) > 0
        and bool(np.all(np.isfinite(vertices)))
        and int(faces.min()) >= 0
        and int(faces.max()) < len(vertices)
    )
    return (vertices, faces) if ok else None


def cached_mesh_hull(
    path: Path, scale: float, cache_dir: Path | None = None
) -> tuple[FloatArray, NDArray[np.int64]]:
    """:func:`_mesh_hull`, computed once per mesh content and then read from the cache.

    Named by the file's bytes, the scale and the versions of trimesh and scipy (its hull is
    qhull's), so the hull read back is the one computed, bit for bit; a cache that cannot be
    used costs the time of computing it, never the hull.
    """
    try:
        data = path.read_bytes()
    except OSError:
        return _mesh_hull(path, scale)  # trimesh says what is wrong with the file
    key = file_cache.content_key(
        [HULL_CACHE_VERSION, repr(float(scale)), data, *file_cache.versions("trimesh", "scipy")]
    )
    try:
        entry = file_cache.cache_folder("hulls", "cached collision hulls", cache_dir) / (
            f"{path.stem[:40]}_{key}.npz.bin"
        )
    except OSError:
        return _mesh_hull(path, scale)
    payload = file_cache.read_entry(entry)
    hull = _hull_from_payload(payload) if payload is not None else None
    if hull is not None:
        return hull
    vertices, faces = _mesh_hull(path, scale)
    buffer = io.BytesIO()
    np.savez(buffer, vertices=vertices, faces=faces)
    try:
        file_cache.write_entry(entry, buffer.getvalue())
    except OSError:
        pass
    return vertices, faces


def _mesh_geometry(path: Path, scale: float) -> tuple[fcl.Convex, FloatArray]:
    key = (str(path), scale)
    if key not in _MESH_CACHE:
        vertices, faces = cached_mesh_hull(path, scale)
        _MESH_CACHE[key] = (_convex_from_hull(vertices, faces), vertices)
    return _MESH_CACHE[key]


def shape_geometry(shape: ShapeSpec) -> tuple[fcl.CollisionGeometry, FloatArray, float]:
    """FCL geometry, bounding-sphere centre (3,) in the shape frame and radius of a shape."""
    if shape.kind == Shape.BOX:
        geometry: fcl.CollisionGeometry = fcl.Box(*shape.size)
        return geometry, np.zeros(3), 0.5 * float(np.linalg.norm(shape.size))
    if shape.kind == Shape.SPHERE:
        return fcl.Sphere(shape.radius), np.zeros(3), shape.radius
    if shape.kind == Shape.CYLINDER:
        radius = float(np.hypot(shape.radius, shape.height / 2.0))
        return fcl.Cylinder(shape.radius, shape.height), np.zeros(3), radius
    assert shape.mesh_path is not None
    convex, vertices = _mesh_geometry(shape.mesh_path, shape.scale)
    centre = 0.5 * (vertices.min(axis=0) + vertices.max(axis=0))
    return convex, centre, float(np.max(np.linalg.norm(vertices - centre, axis=1)))


def pybullet_geometry(data: Sequence[Any]) -> tuple[fcl.CollisionGeometry, FloatArray, float]:
    """FCL geometry of one ``getCollisionShapeData`` entry (box, sphere, cylinder, mesh)."""
    kind = int(data[2])
    dims = np.asarray(data[3], dtype=float)
    if kind == pb.GEOM_BOX:
        return shape_geometry(ShapeSpec.box(dims))
    if kind == pb.GEOM_SPHERE:
        return shape_geometry(ShapeSpec.sphere(float(dims[0])))
    if kind == pb.GEOM_CYLINDER:
        return shape_geometry(ShapeSpec.cylinder(float(dims[1]), float(dims[0])))
    if kind == pb.GEOM_MESH:
        name = data[4]
        path = Path(name.decode() if isinstance(name, bytes) else str(name))
        return shape_geometry(ShapeSpec(Shape.MESH, mesh_path=path, scale=float(dims[0])))
    raise ValueError(f"collision: expected a box, sphere, cylinder or mesh shape, got type {kind}")


def _posed(shape: ShapeSpec, pose: tuple[ArrayLike, ArrayLike]) -> fcl.CollisionObject:
    position, quaternion = pose
    rotation = quat.to_matrix(np.asarray(quaternion, dtype=float))
    transform = fcl.Transform(rotation, np.asarray(position, dtype=float))
    return fcl.CollisionObject(shape_geometry(shape)[0], transform)


def _overlap(a: fcl.CollisionObject, b: fcl.CollisionObject) -> float | None:
    """How deep two posed objects interpenetrate, m (0 when they only touch); None when apart."""
    request = fcl.CollisionRequest(num_max_contacts=1, enable_contact=True)
    result = fcl.CollisionResult()
    if not fcl.collide(a, b, request, result):
        return None
    return max(float(result.contacts[0].penetration_depth), 0.0) if result.contacts else 0.0


def penetration_depth(
    shape_a: ShapeSpec,
    pose_a: tuple[ArrayLike, ArrayLike],
    shape_b: ShapeSpec,
    pose_b: tuple[ArrayLike, ArrayLike],
) -> float:
    """How deep two shapes at their poses (position (3,), quaternion (4,) scalar-last, world
    frame) interpenetrate, m; 0 when they are apart or only touch."""
    depth = _overlap(_posed(shape_a, pose_a), _posed(shape_b, pose_b))
    return 0.0 if depth is None else depth


def shape_gap(
    shape_a: ShapeSpec,
    pose_a: tuple[ArrayLike, ArrayLike],
    shape_b: ShapeSpec,
    pose_b: tuple[ArrayLike, ArrayLike],
) -> float:
    """Signed gap between two shapes at their poses (as :func:`penetration_depth`), m: their
    distance when apart, 0 when they touch, minus the penetration depth when they overlap."""
    a, b = _posed(shape_a, pose_a), _posed(shape_b, pose_b)
    depth = _overlap(a, b)
    if depth is not None:
        return -depth
    return max(float(fcl.distance(a, b, fcl.DistanceRequest())), 0.0)


__all__ = [
    "HULL_CACHE_VERSION",
    "cached_mesh_hull",
    "penetration_depth",
    "pybullet_geometry",
    "shape_gap",
    "shape_geometry",
]

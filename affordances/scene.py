"""Stage 3: scene checks through a collision-query port.

The reasoner asks a :class:`SceneQuery` how close obstacles come to the carried object's
predicted path and to the arms' predicted links. ``worlds`` will implement the port with
FCL; :class:`GeometricSceneQuery` is a pure-numpy stand-in that treats obstacles as spheres,
the path as a polyline and each arm as a segment from its shoulder to its palm.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from affordances.actions import DEFAULT_SPACE, SkillSelection
from affordances.config import ReasonerConfig
from affordances.context import ObjectContext, Obstacle, Vector3, check_positive, check_vector3
from affordances.object_geometry import bounding_radius
from affordances.physics import GraspOption
from skills.vocabulary import Action, AffordanceElement, Arm

FloatArray = NDArray[np.float64]

#: Shoulder positions in {W}, metres, of a humanoid torso at the origin facing +x.
DEFAULT_SHOULDERS: Mapping[Arm, Vector3] = MappingProxyType(
    {Arm.LEFT: (0.0, 0.2, 0.4), Arm.RIGHT: (0.0, -0.2, 0.4)}
)


class SceneQuery(Protocol):
    """Collision queries the reasoner needs; implemented by ``worlds`` with FCL."""

    def path_clearance(
        self, waypoints: FloatArray, object_radius: float, obstacles: Sequence[Obstacle]
    ) -> FloatArray:
        """Distance from the object swept along a path to each obstacle.

        Parameters
        ----------
        waypoints : ndarray, shape (n, 3)
            Object centre in {W}, metres; the path joins them with straight lines.
        object_radius : float
            Radius of the sphere bounding the object, metres.
        obstacles : sequence of Obstacle
            Obstacles to check, ``m`` of them.

        Returns
        -------
        ndarray, shape (m,)
            Smallest surface-to-surface distance per obstacle, metres; negative if they overlap.
        """
        ...

    def link_clearance(
        self, palm_paths: Mapping[Arm, FloatArray], obstacles: Sequence[Obstacle]
    ) -> dict[Arm, FloatArray]:
        """Distance from each arm's predicted links to each obstacle.

        Parameters
        ----------
        palm_paths : mapping of Arm to ndarray, shape (n, 3)
            Predicted palm centres in {W}, metres, for the arms in use.
        obstacles : sequence of Obstacle
            Obstacles to check, ``m`` of them.

        Returns
        -------
        dict of Arm to ndarray, shape (m,)
            Smallest distance from the arm's links to each obstacle's surface, metres.
        """
        ...


def segment_distances(points: FloatArray, starts: FloatArray, ends: FloatArray) -> FloatArray:
    """Distance from each point to each segment.

    Parameters
    ----------
    points : ndarray, shape (m, 3)
        Query points.
    starts, ends : ndarray, shape (k, 3)
        Segment end points; a zero-length segment is a point.

    Returns
    -------
    ndarray, shape (m, k)
        Euclidean distances, same unit as the inputs.
    """
    direction = ends - starts  # (k, 3)
    length_sq = np.einsum("kd,kd->k", direction, direction)
    rel = points[:, None, :] - starts[None, :, :]  # (m, k, 3)
    safe = np.where(length_sq > 0.0, length_sq, 1.0)
    t = np.clip(np.einsum("mkd,kd->mk", rel, direction) / safe, 0.0, 1.0)
    t = np.where(length_sq > 0.0, t, 0.0)
    closest = starts[None, :, :] + t[..., None] * direction[None, :, :]
    return np.asarray(np.linalg.norm(points[:, None, :] - closest, axis=-1), dtype=np.float64)


def sample_polyline(waypoints: FloatArray, samples_per_segment: int) -> FloatArray:
    """Points along a polyline, both ends included.

    Parameters
    ----------
    waypoints : ndarray, shape (n, 3)
        Vertices of the polyline.
    samples_per_segment : int
        Points per segment, counting its start and not its end.

    Returns
    -------
    ndarray, shape (samples_per_segment * (n - 1) + 1, 3)
        The sampled points.
    """
    if len(waypoints) == 1:
        return np.array(waypoints, dtype=np.float64)
    s = np.arange(samples_per_segment) / samples_per_segment  # (s,)
    starts, ends = waypoints[:-1], waypoints[1:]
    inner = starts[:, None, :] + s[None, :, None] * (ends - starts)[:, None, :]
    return np.vstack([inner.reshape(-1, 3), waypoints[-1:]])


def _obstacle_arrays(obstacles: Sequence[Obstacle]) -> tuple[FloatArray, FloatArray]:
    centres = np.array([o.position for o in obstacles], dtype=np.float64).reshape(-1, 3)
    radii = np.array([o.radius for o in obstacles], dtype=np.float64)
    return centres, radii


@dataclass(frozen=True)
class GeometricSceneQuery:
    """Sphere obstacles, polyline paths and shoulder-to-palm segments as arm links.

    Attributes
    ----------
    shoulders : mapping of Arm to tuple of float, shape (3,)
        Shoulder positions in {W}, metres.
    link_radius_m : float
        Radius of the capsule around each arm segment, metres.
    samples_per_segment : int
        Palm positions sampled per path segment to predict the arm segments.
    hands : mapping of Arm to (ndarray (K, 3), ndarray (K,))
        Bounding spheres of what is welded to each palm (a hand standing out of the grip):
        centres in the palm frame and radii, metres. The palm frame of the lateral grasp has
        x down and z along the push into the object (:meth:`skills.dual_arm.GraspGeometry
        .lateral`), the other palm being across the object; the spheres ride along the palm's
        path. None for an arm: nothing welded.
    """

    shoulders: Mapping[Arm, Vector3] = field(default_factory=lambda: dict(DEFAULT_SHOULDERS))
    link_radius_m: float = 0.04
    samples_per_segment: int = 8
    hands: Mapping[Arm, tuple[FloatArray, FloatArray]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        owner = "GeometricSceneQuery"
        shoulders = {
            Arm(arm): check_vector3(pos, owner, f"shoulders[{arm!s}]")
            for arm, pos in self.shoulders.items()
        }
        object.__setattr__(self, "shoulders", MappingProxyType(shoulders))
        object.__setattr__(
            self, "link_radius_m", check_positive(self.link_radius_m, owner, "link_radius_m")
        )
        if self.samples_per_segment < 1:
            raise ValueError(
                f"{owner}.samples_per_segment: expected >= 1, got {self.samples_per_segment!r}"
            )

    def path_clearance(
        self, waypoints: FloatArray, object_radius: float, obstacles: Sequence[Obstacle]
    ) -> FloatArray:
        """Distance from the object swept along the polyline to each sphere obstacle, metres."""
        if not obstacles:
            return np.zeros(0)
        points = np.asarray(waypoints, dtype=np.float64).reshape(-1, 3)
        centres, radii = _obstacle_arrays(obstacles)
        starts = points[:-1] if len(points) > 1 else points
        ends = points[1:] if len(points) > 1 else points
        nearest = segment_distances(centres, starts, ends).min(axis=1)
        return np.asarray(nearest - radii - object_radius, dtype=np.float64)

    def link_clearance(
        self, palm_paths: Mapping[Arm, FloatArray], obstacles: Sequence[Obstacle]
    ) -> dict[Arm, FloatArray]:
        """Distance from each arm's shoulder-to-palm segments along the path, metres."""
        centres, radii = _obstacle_arrays(obstacles)
        result: dict[Arm, FloatArray] = {}
        for arm, path in palm_paths.items():
            if not obstacles:
                result[arm] = np.zeros(0)
                continue
            palms = sample_polyline(
                np.asarray(path, dtype=np.float64).reshape(-1, 3), self.samples_per_segment
            )
            shoulder = np.broadcast_to(
                np.asarray(self.shoulders[arm], dtype=np.float64), palms.shape
            )
            nearest = segment_distances(centres, shoulder, palms).min(axis=1)
            gap = np.asarray(nearest - radii - self.link_radius_m, dtype=np.float64)
            hand = self._hand_clearance(arm, palm_paths, palms, centres, radii)
            result[arm] = gap if hand is None else np.minimum(gap, hand)
        return result

    def _hand_clearance(
        self,
        arm: Arm,
        palm_paths: Mapping[Arm, FloatArray],
        palms: FloatArray,
        centres: FloatArray,
        radii: FloatArray,
    ) -> FloatArray | None:
        """Clearance (m) of ``arm``'s hand spheres carried along its sampled ``palms`` from each
        obstacle, or None (nothing welded, or no other palm to say which way it faces)."""
        local, hand_radii = self.hands.get(arm, (np.zeros((0, 3)), np.zeros(0)))
        others = [a for a in palm_paths if a != arm]
        if len(local) == 0 or not others:
            return None
        start = np.asarray(palm_paths[arm], dtype=np.float64).reshape(-1, 3)[0]
        across = np.asarray(palm_paths[others[0]], dtype=np.float64).reshape(-1, 3)[0] - start
        inward = np.array([across[0], across[1], 0.0])
        if np.linalg.norm(inward) < 1e-9:
            return None
        z = inward / np.linalg.norm(inward)
        x = np.array([0.0, 0.0, -1.0])
        frame = np.column_stack((x, np.cross(z, x), z))  # palm axes in {W}
        spheres = palms[:, None, :] + (np.asarray(local) @ frame.T)[None]  # (S, K, 3)
        d = np.linalg.norm(spheres[None] - centres[:, None, None, :], axis=-1)  # (m, S, K)
        gaps = d - np.asarray(hand_radii)[None, None, :] - radii[:, None, None]
        return np.asarray(gaps.min(axis=(1, 2)), dtype=np.float64)


@dataclass(frozen=True)
class SceneFindings:
    """What stage 3 adds to one grasp.

    Attributes
    ----------
    skills : tuple of SkillSelection
        ``avoid_obstacle`` and/or ``avoid_links`` when obstacles come near.
    elements : frozenset of AffordanceElement
        ``obstacle_near_path`` / ``obstacle_near_links`` for the rules.
    because : tuple of str
        Which obstacle came how close.
    """

    skills: tuple[SkillSelection, ...]
    elements: frozenset[AffordanceElement]
    because: tuple[str, ...]


def object_path(context: ObjectContext) -> FloatArray:
    """The object's predicted path: its position, then each goal, shape (n, 3), {W}, metres."""
    return np.array((context.position, *context.goals), dtype=np.float64)


def check_scene(
    context: ObjectContext, option: GraspOption, scene: SceneQuery, config: ReasonerConfig
) -> SceneFindings:
    """Ask the scene port how close obstacles come to the object's path and to the arms.

    Parameters
    ----------
    context : ObjectContext
        The object, its obstacles and goals.
    option : GraspOption
        The grasp, which fixes the arms and the palms' start positions.
    scene : SceneQuery
        The collision-query port.
    config : ReasonerConfig
        Margins for the path and the links.

    Returns
    -------
    SceneFindings
        Added skills, elements and reasons.
    """
    obstacles = context.obstacles
    if not obstacles:
        return SceneFindings((), frozenset(), ())
    path = object_path(context)
    skills: list[SkillSelection] = []
    elements: set[AffordanceElement] = set()
    because: list[str] = []

    lifts = [np.array([0.0, 0.0, h]) for h in np.linspace(0.0, config.carry_lift_m, 3)]
    path_gap = np.min(
        [scene.path_clearance(path + up, bounding_radius(context), obstacles) for up in lifts],
        axis=0,
    )
    near = [i for i in range(len(obstacles)) if path_gap[i] < config.path_margin_m]
    if near:
        names = tuple(obstacles[i].name for i in near)
        clearance = float(min(path_gap[i] for i in near))
        skills.append(
            SkillSelection(
                Action.AVOID_OBSTACLE,
                DEFAULT_SPACE[Action.AVOID_OBSTACLE],
                1.0,
                {"obstacles": names, "clearance_m": clearance},
            )
        )
        elements.add(AffordanceElement.OBSTACLE_NEAR_PATH)
        for i in near:
            because.append(
                f"scene: {obstacles[i].name} {path_gap[i]:.3g} m from the object's path "
                f"(margin {config.path_margin_m:.3g} m): avoid obstacle"
            )

    offsets = path - path[0]
    palm_paths = {
        arm: np.asarray(palm, dtype=np.float64) + offsets
        for arm, palm in zip(option.arms, option.palms, strict=True)
    }
    swept = [
        scene.link_clearance({arm: p + up for arm, p in palm_paths.items()}, obstacles)
        for up in lifts
    ]
    link_gap = {arm: np.min([g[arm] for g in swept], axis=0) for arm in swept[0]}
    near_arms = tuple(
        arm for arm in Arm if arm in link_gap and bool(np.any(link_gap[arm] < config.link_margin_m))
    )
    if near_arms:
        near_links = [
            i
            for i in range(len(obstacles))
            if any(link_gap[arm][i] < config.link_margin_m for arm in near_arms)
        ]
        clearance = float(min(link_gap[arm].min() for arm in near_arms))
        skills.append(
            SkillSelection(
                Action.AVOID_LINKS,
                DEFAULT_SPACE[Action.AVOID_LINKS],
                1.0,
                {
                    "arms": tuple(a.value for a in near_arms),
                    "obstacles": tuple(obstacles[i].name for i in near_links),
                    "clearance_m": clearance,
                },
            )
        )
        elements.add(AffordanceElement.OBSTACLE_NEAR_LINKS)
        for arm in near_arms:
            for i in near_links:
                if link_gap[arm][i] < config.link_margin_m:
                    because.append(
                        f"scene: {obstacles[i].name} {link_gap[arm][i]:.3g} m from the "
                        f"{arm.value} arm (margin {config.link_margin_m:.3g} m): avoid links"
                    )
    return SceneFindings(tuple(skills), frozenset(elements), tuple(because))

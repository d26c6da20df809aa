"""Choosing a clear way for the empty palms: predict each candidate route, check it, take the first
that keeps clear of the obstacles.

Approach and Retreat move the palms through via-points (:class:`ViaPointMotion`) near an
object that stands among obstacles. Each offers a small ordered set of routes, its usual one
first; the route's motion is rolled out open loop (the DMPs are deterministic) and the palms'
path, with the arm links carried along, is checked through
:meth:`planner.port.ObstacleScene.check_palm_path`. The first route clear by the margin is
taken, so a palm with nothing near its path moves exactly as it always did.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from py_trees.ports import PortInformation

from planner.leaves.palm_motion import (
    PalmPath,
    ViaPointLeaf,
    ViaPointMotion,
    predict_palm_path,
)
from planner.port import ObstacleInfo, ObstacleScene, PathCheck, Pose
from skills.pose_dmp import PoseState
from skills.vocabulary import ARMS, Arm

#: How far beyond an obstacle's bounding sphere a detour's via-point puts the palm, m: about a
#: wrist-to-palm length, since the links behind the palm are what sweep past it.
DETOUR_CLEARANCE_M = 0.15


def margin_port() -> PortInformation:
    """The clearance an empty palms' route must keep from the obstacles and the resting
    objects, m."""
    return PortInformation(
        float,
        required=False,
        default_value=0.01,
        description="clearance from the obstacles and the resting objects the palms' "
        "predicted path must keep, m (else another way is taken)",
    )


@dataclass(frozen=True)
class PalmRoute:
    """One candidate way for both palms.

    Attributes
    ----------
    name : str
        What the route does, in words (for the leaf's feedback).
    waypoints : mapping Arm -> sequence of Pose
        Via-points then the final pose per palm, world frame.
    """

    name: str
    waypoints: Mapping[Arm, Sequence[Pose]]


@dataclass(frozen=True)
class RouteChoice:
    """The route a leaf takes and why.

    Attributes
    ----------
    route : PalmRoute
    check : PathCheck
        Its check at the margin.
    clear : bool
        Clear by the margin.
    contact_free : bool
        Clear at least of contact (always, when ``clear``).
    note : str
        Empty for the first route taken clear; else which routes were refused and why.
    ends_in_contact : str
        When no route is clear of contact and every one ends touching an obstacle (its last
        pose's palms or arm links, :attr:`planner.port.PathCheck.end_clear`), or with an arm
        link on one of the other objects (``around``, :attr:`planner.port.PathCheck.end_objects`):
        which, in words. Empty otherwise.
    """

    route: PalmRoute
    check: PathCheck
    clear: bool
    contact_free: bool
    note: str
    ends_in_contact: str = ""


def detour(route: PalmRoute, path: PalmPath, obstacles: Sequence[ObstacleInfo]) -> PalmRoute:
    """``route`` with a via-point that takes each palm around the obstacle its path comes
    nearest: where the predicted path passes closest to that obstacle's bounding sphere, the
    palm is sent out horizontally, away from the obstacle's centre, to
    :data:`DETOUR_CLEARANCE_M` beyond the sphere, before heading on to the via-point it was
    heading for there. A palm already that far from every obstacle keeps its route.
    """
    if not obstacles:
        return route
    centres = np.array([o.position for o in obstacles])  # (K, 3)
    radii = np.array([o.radius for o in obstacles])
    out: dict[Arm, list[Pose]] = {}
    for a, arm in enumerate(ARMS):
        p = path.positions[:, a]  # (N, 3)
        gaps = np.linalg.norm(p[:, None] - centres[None], axis=-1) - radii[None]  # (N, K)
        step, k = np.unravel_index(int(np.argmin(gaps)), gaps.shape)
        waypoints = list(route.waypoints[arm])
        reach = radii[k] + DETOUR_CLEARANCE_M
        away = p[step] - centres[k]
        away[2] = 0.0
        across = float(np.linalg.norm(away))
        if gaps[step, k] >= DETOUR_CLEARANCE_M or across >= reach:
            out[arm] = waypoints
            continue
        if across < 1e-6:
            # Straight above or below the centre: out sideways, to the arm's own side (the
            # whole reach: before, a unit sideways vector was taken as 1 m across already).
            unit = np.array([0.0, 1.0 if arm is Arm.LEFT else -1.0, 0.0])
            across = 0.0
        else:
            unit = away / across
        via = p[step] + (reach - across) * unit
        heading = int(min(path.segments[step, a], len(waypoints) - 1))
        waypoints.insert(heading, Pose(via, waypoints[heading].orientation))
        out[arm] = waypoints
    return PalmRoute(f"{route.name}, around the nearest obstacle", out)


def choose_route(
    scene: ObstacleScene,
    starts: Mapping[Arm, PoseState],
    routes: Sequence[PalmRoute],
    segment_tau: float,
    dt: float,
    margin_m: float,
    detour_of: int | None = 0,
    detour_at: int | None = None,
    around: Sequence[ObstacleInfo] = (),
    object_margin_m: float | None = None,
) -> RouteChoice:
    """The first of ``routes`` whose predicted path is clear by ``margin_m``.

    The routes are tried in order, with (if ``detour_of`` names one) that route taken around
    the obstacle, or object of ``around``, its path comes nearest (:func:`detour`) tried at
    ``detour_at``. When none is clear, the one clear of contact with the largest predicted
    distance; when none is even that, the usual one, unless every route ends touching an
    obstacle or with an arm link on an object of ``around`` (``RouteChoice.ends_in_contact``).

    Parameters
    ----------
    scene : ObstacleScene
        The world's obstacles and collision queries.
    starts : mapping Arm -> PoseState
        Where each palm starts.
    routes : sequence of PalmRoute
        Candidates, the usual one first.
    segment_tau, dt : float
        The motion's segment duration scale and control step, s.
    margin_m : float
        Clearance asked, m.
    detour_of : int or None
        Index of the route to also try around the nearest obstacle.
    detour_at : int, optional
        Where in the order to try that detour (after ``detour_of``); default last.
    around : sequence of ObstacleInfo
        Other objects, where they lie, that the detour may go around too, and that the end
        may not put an arm link on.
    object_margin_m : float, optional
        Clearance asked from the objects where they rest, m; ``margin_m`` when None.
    """
    if not routes:
        raise ValueError("choose_route: expected at least one route, got none")
    tried: list[tuple[PalmRoute, PalmPath, PathCheck]] = []
    candidates = list(routes)
    obstacles = (*scene.obstacles(), *around)
    k = 0
    while k < len(candidates):
        route = candidates[k]
        path = predict_palm_path(starts, route.waypoints, segment_tau, dt)
        check = scene.check_palm_path(
            path.positions, path.orientations, margin_m, object_margin_m=object_margin_m
        )
        if check.clear:
            return RouteChoice(route, check, True, True, _refusals(tried))
        tried.append((route, path, check))
        if detour_of is not None and k == detour_of and obstacles:
            at = len(routes) if detour_at is None else max(detour_at, k + 1)
            candidates.insert(at, detour(route, path, obstacles))
        k += 1
    contact = [scene.check_palm_path(p.positions, p.orientations, 0.0) for _, p, _ in tried]
    if not any(c.clear for c in contact):
        # The prediction carries the forearms rigidly and asks them for extra clearance the
        # further the palms go: over a long way it doubts every route alike, and then it is
        # no ground for leaving the usual one, unless the usual one is sure to touch (a palm,
        # or a link on an object that rests) and another only doubted.
        doubted = [i for i, c in enumerate(contact) if c.doubtful]
        i = 0 if contact[0].doubtful or not doubted else doubted[0]
        route, _, check = tried[i]
        # Each way ends touching (a leaf's routes share their end): no other way helps.
        on = set.intersection(*({o.name for o in around} & set(c.end_objects) for c in contact))
        end = (
            "every way ends with a palm or an arm link on an obstacle"
            if not any(c.end_clear for c in contact)
            else f"every way ends with an arm link on {', '.join(sorted(on))}"
            if on
            else ""
        )
        return RouteChoice(route, check, False, False, _refusals(tried), end)
    best = max(range(len(tried)), key=lambda i: (contact[i].clear, tried[i][2].min_distance_m))
    route, _, check = tried[best]
    return RouteChoice(route, check, False, True, _refusals(tried))


def _refusals(tried: Sequence[tuple[PalmRoute, PalmPath, PathCheck]]) -> str:
    return "; ".join(f"{route.name}: {check.detail}" for route, _, check in tried)


def take_clear_route(
    leaf: ViaPointLeaf,
    scene: ObstacleScene,
    starts: Mapping[Arm, PoseState],
    routes: Sequence[PalmRoute],
    segment_tau: float,
    margin_m: float,
    detour_of: int | None = 0,
    detour_at: int | None = None,
    around: Sequence[ObstacleInfo] = (),
    object_margin_m: float | None = None,
) -> None:
    """Plan ``leaf``'s motion along the route :func:`choose_route` picks; the leaf's feedback
    says which and why when it is not the usual one, or when no route is clear.

    A route that is not even clear of contact is still taken when only its way is doubted;
    one whose end itself touches (:attr:`RouteChoice.ends_in_contact`) is refused: the leaf
    gets no motion and fails with the reason (``leaf.refusal``), its palms where they are."""
    choice = choose_route(
        scene,
        starts,
        routes,
        segment_tau,
        leaf.control_dt,
        margin_m,
        detour_of,
        detour_at,
        around,
        object_margin_m,
    )
    leaf.route_note = ""
    leaf.refusal = None
    if choice.ends_in_contact:
        leaf.motion = None
        leaf.refusal = f"no way clear of contact: {choice.ends_in_contact}; refused {choice.note}"
        return
    leaf.motion = ViaPointMotion(starts, choice.route.waypoints, segment_tau)
    if choice.clear:
        if choice.note:
            leaf.route_note = f"by {choice.route.name}; refused {choice.note}"
    elif choice.contact_free:
        leaf.route_note = (
            f"no way clear by {margin_m:g} m: by {choice.route.name}, the most clearance "
            f"(palms {choice.check.min_distance_m * 1000:.0f} mm from the nearest obstacle); "
            f"{choice.note}"
        )
    else:
        leaf.route_note = (
            f"no way predicted clear, by {choice.route.name} (every way predicted to touch "
            f"somewhere along it); refused {choice.note}"
        )

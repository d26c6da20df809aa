"""Benchmark the PyBullet scene: control-loop real-time factor and FCL trajectory checks.

Usage: ``python bench/bench_sim.py [--json] [--seconds S] [--world FILE]``

Figures:
- ``realtime_factor``: simulated s / wall s, default world, 240 Hz physics, both palms under
  impedance torque control holding the parcel 10 cm above the table, commands re-sent at the
  world's control rate (the law re-linearised at that rate).
- ``realtime_factor_exact``: the same with the law re-linearised every physics step.
- ``physics_us_per_step``: wall time inside stepSimulation, for scale.
- ``fcl_check_ms``: median time to check a 1000-waypoint dual-arm trajectory (two palms and the
  held parcel) passing 2 cm above the world's obstacles (every waypoint reaches FCL).
With ``--json`` the last line is a JSON object of these figures.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
import pybullet as pb

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from skills.vocabulary import Arm  # noqa: E402
from worlds.collision import CollisionWorld  # noqa: E402
from worlds.control import PalmCommand  # noqa: E402
from worlds.palm_poses import LATERAL_PALM_QUATERNIONS, lateral_grasp_palm_poses  # noqa: E402
from worlds.scene import Scene  # noqa: E402
from worlds.world_file import BoxShape, load_world  # noqa: E402

SQUEEZE = 0.015


def _command_palms(
    scene: Scene, centre: np.ndarray, half_span: float, gap: float, squeeze: float
) -> None:
    thickness = scene.spec.robot.palm_size[2]
    for arm, (position, quaternion) in lateral_grasp_palm_poses(
        centre, half_span, thickness, gap
    ).items():
        scene.set_palm_command(arm, PalmCommand(position, quaternion, squeeze_offset=squeeze))


def _ramp(
    scene: Scene,
    centre_from: np.ndarray,
    centre_to: np.ndarray,
    gap_from: float,
    gap_to: float,
    squeeze: float,
    duration: float,
    half_span: float,
) -> None:
    per_command = scene.spec.physics_hz // scene.spec.control_hz
    steps = round(duration * scene.spec.physics_hz)
    for k in range(0, steps, per_command):
        s = min((k + per_command) / steps, 1.0)
        s = s**3 * (10.0 - 15.0 * s + 6.0 * s**2)
        _command_palms(
            scene,
            centre_from + (centre_to - centre_from) * s,
            half_span,
            gap_from + (gap_to - gap_from) * s,
            squeeze,
        )
        scene.step(per_command)


def _box_size(shape: object) -> np.ndarray:
    if not isinstance(shape, BoxShape):
        raise ValueError(f"bench_sim: expected a box-shaped first object, got {shape!r}")
    return np.asarray(shape.size, dtype=float)


def grasped_scene(world_file: Path, refresh_every: int | None) -> tuple[Scene, np.ndarray, float]:
    """Default world with the parcel squeezed and lifted 10 cm; returns scene, centre, half span."""
    world = load_world(world_file)
    scene = Scene.from_world(world, refresh_every=refresh_every)
    obj = world.objects[0]
    centre = np.asarray(obj.pose.position, dtype=float)
    half_span = float(_box_size(obj.shape)[1]) / 2.0
    thickness = scene.spec.robot.palm_size[2]
    scene.place_palms(lateral_grasp_palm_poses(centre, half_span, thickness, gap=0.08))
    scene.step(48)
    _ramp(scene, centre, centre, 0.08, 0.0, 0.0, 1.0, half_span)
    _ramp(scene, centre, centre, 0.0, 0.0, SQUEEZE, 0.5, half_span)
    up = centre + np.array([0.0, 0.0, 0.1])
    _ramp(scene, centre, up, 0.0, 0.0, SQUEEZE, 1.0, half_span)
    return scene, up, half_span


def hold_factor(world_file: Path, seconds: float, refresh_every: int | None) -> dict[str, float]:
    """Real-time factor of holding the parcel in the air for ``seconds``, and the slip."""
    scene, up, half_span = grasped_scene(world_file, refresh_every)
    with scene:
        name = scene.spec.objects[0].name
        start_offset = _object_in_palms(scene, name)
        per_command = scene.spec.physics_hz // scene.spec.control_hz
        steps = round(seconds * scene.spec.physics_hz)
        apply = scene.controller.apply
        step = pb.stepSimulation
        client = scene.client
        clock = time.perf_counter
        physics = 0.0
        t0 = clock()
        for _ in range(0, steps, per_command):
            _command_palms(scene, up, half_span, 0.0, SQUEEZE)
            for _ in range(per_command):
                apply()
                t1 = clock()
                step(physicsClientId=client)
                physics += clock() - t1
        wall = clock() - t0
        scene.step_count += steps
        slip = float(np.linalg.norm(_object_in_palms(scene, name) - start_offset))
        force = min(scene.palm_contact_force(arm, name) for arm in (Arm.LEFT, Arm.RIGHT))
    return {
        "factor": seconds / wall,
        "us_per_step": wall / steps * 1e6,
        "physics_us_per_step": physics / steps * 1e6,
        "slip_m": slip,
        "min_squeeze_n": float(force),
    }


def _object_in_palms(scene: Scene, name: str) -> np.ndarray:
    position, _ = scene.object_pose(name)
    palms = [scene.palm_state(arm).position for arm in (Arm.LEFT, Arm.RIGHT)]
    return position - 0.5 * (palms[0] + palms[1])


def fcl_figures(world_file: Path, repeats: int = 15) -> dict[str, float]:
    """Median times of a 1000-waypoint trajectory check, a sync and per-link distances.

    The held object is carried along y at x = 0.6 m with its bottom 2 cm above the highest
    obstacle top, all obstacles active: every waypoint passes the bounding-sphere prefilter and
    goes to FCL, and none collides, so no early exit shortens the check (a worst case).
    """
    world = load_world(world_file)
    with Scene.from_world(world) as scene:
        scene.set_active_obstacles([o.name for o in world.obstacles])
        collision = CollisionWorld(scene)
        obj = world.objects[0]
        size = _box_size(obj.shape)
        tops = [
            o.position[2] + (o.shape.radius if hasattr(o.shape, "radius") else 0.0)
            for o in world.obstacles
        ]
        height = max(tops, default=0.7) + 0.02 + size[2] / 2.0
        n = 1000
        y = np.linspace(-0.3, 0.3, n)
        centre = np.stack([np.full(n, 0.6), y, np.full(n, height)], axis=1)
        offset = np.array([0.0, size[1] / 2.0 + scene.spec.robot.palm_size[2] / 2.0, 0.0])
        palms = np.stack([centre + offset, centre - offset], axis=1)
        quaternions = np.broadcast_to(
            np.array([LATERAL_PALM_QUATERNIONS[Arm.LEFT], LATERAL_PALM_QUATERNIONS[Arm.RIGHT]]),
            (n, 2, 4),
        )
        object_q = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
        times, sync_times, link_times = [], [], []
        result = None
        for _ in range(repeats):
            t0 = time.perf_counter()
            result = collision.check_trajectory(palms, quaternions, obj.name, centre, object_q)
            times.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            collision.sync()
            sync_times.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            collision.link_distances(Arm.LEFT)
            collision.link_distances(Arm.RIGHT)
            link_times.append(time.perf_counter() - t0)
        assert result is not None
    return {
        "fcl_check_ms": float(np.median(times) * 1e3),
        "fcl_colliding_waypoints": int(result.collides.sum()),
        "fcl_sync_ms": float(np.median(sync_times) * 1e3),
        "fcl_link_distances_ms": float(np.median(link_times) * 1e3),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="end with one JSON line")
    parser.add_argument("--seconds", type=float, default=10.0, help="simulated hold time, s")
    parser.add_argument(
        "--world", type=Path, default=ROOT / "worlds" / "parcel_pick_place.yaml", help="world file"
    )
    args = parser.parse_args(argv)
    control = hold_factor(args.world, args.seconds, refresh_every=None)
    exact = hold_factor(args.world, min(args.seconds, 4.0), refresh_every=1)
    fcl_out = fcl_figures(args.world)
    figures = {
        "realtime_factor": round(control["factor"], 2),
        "realtime_factor_exact": round(exact["factor"], 2),
        "us_per_step": round(control["us_per_step"], 1),
        "physics_us_per_step": round(control["physics_us_per_step"], 1),
        "hold_slip_mm": round(control["slip_m"] * 1e3, 3),
        "hold_min_squeeze_n": round(control["min_squeeze_n"], 2),
        "fcl_check_ms": round(fcl_out["fcl_check_ms"], 2),
        "fcl_colliding_waypoints": fcl_out["fcl_colliding_waypoints"],
        "fcl_sync_ms": round(fcl_out["fcl_sync_ms"], 3),
        "fcl_link_distances_ms": round(fcl_out["fcl_link_distances_ms"], 3),
    }
    print(
        f"hold parcel {args.seconds} s, 240 Hz, both arms impedance: "
        f"{figures['realtime_factor']}x real time ({figures['us_per_step']} us/step, of which "
        f"physics {figures['physics_us_per_step']} us); law re-linearised every step: "
        f"{figures['realtime_factor_exact']}x"
    )
    print(
        f"parcel slip in the palms over the hold: {figures['hold_slip_mm']} mm, "
        f"min squeeze {figures['hold_min_squeeze_n']} N"
    )
    print(
        f"FCL: 1000-waypoint trajectory check {figures['fcl_check_ms']} ms "
        f"({figures['fcl_colliding_waypoints']} colliding), sync {figures['fcl_sync_ms']} ms, "
        f"per-link distances both arms {figures['fcl_link_distances_ms']} ms"
    )
    if args.json:
        print(json.dumps(figures))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

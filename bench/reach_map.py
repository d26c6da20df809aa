"""Two-palm reach map: how well a world's robot reaches and holds the lateral grasp over a grid.

The palms start on the +-y faces of the world's object where it rests (the episode's own
start-posture solve, :meth:`worlds.scene.Scene.place_palms`); for each object centre of a grid
(x, y at a few heights above the table) the impedance controller (the model's gains, a
humanoid's torso included) then carries them there along a minimum-jerk path in 1.5 s and
holds them 0.5 s; the figure is the larger palm position error, mm. It shows where a world's
trial regions (its ``trials`` section) can lie; under the tables, per height, the largest
rectangle of grid points (x rows by a y range symmetric about the centre line) all within
3 mm. With ``--json`` the last line is ``{"grid": [[x, y, z, error_mm], ...], "within_3mm":
{z: [[x_min, x_max], [y_min, y_max]] or null}}``.

    python bench/reach_map.py worlds/icub_parcel_pick_place.yaml
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from skills.vocabulary import Arm
from worlds.control import PalmCommand
from worlds.scene import Scene, lateral_grasp_palm_poses
from worlds.world_file import World, load_world


def palm_error(world: World, centre: np.ndarray, move_s: float = 1.5, hold_s: float = 0.5) -> float:
    """Larger palm position error (m) after carrying the grasp from the object's rest pose to
    ``centre`` (3,) in ``move_s`` and holding it there for ``hold_s``."""
    obj = world.objects[0]
    half_span = float(obj.shape.size[1]) / 2.0  # type: ignore[union-attr]
    thickness = float(world.robot.palm_size[2])
    start = np.asarray(obj.pose.position, dtype=float)
    with Scene.from_world(world) as scene:
        scene.set_active_obstacles(())
        # No object between the palms: the map is the arms' and torso's, not the grip's.
        scene.place_palms(lateral_grasp_palm_poses(start, half_span, thickness))
        per_command = scene.spec.physics_hz // scene.spec.control_hz
        steps = round(move_s * scene.spec.physics_hz)
        for k in range(0, steps, per_command):
            s = min(1.0, (k + per_command) / steps)
            blend = s**3 * (10.0 - 15.0 * s + 6.0 * s * s)  # minimum jerk
            poses = lateral_grasp_palm_poses(start + blend * (centre - start), half_span, thickness)
            for arm, (p, q) in poses.items():
                scene.set_palm_command(arm, PalmCommand(p, q))
            scene.step(per_command)
        scene.step(round(hold_s * scene.spec.physics_hz))
        return max(
            float(np.linalg.norm(scene.palm_state(arm).position - poses[arm][0]))
            for arm in (Arm.LEFT, Arm.RIGHT)
        )


def within_rectangle(
    grid: list[list[float]], z: float, tolerance_mm: float = 3.0
) -> tuple[tuple[float, float], tuple[float, float]] | None:
    """The largest rectangle of grid points at height ``z`` all within ``tolerance_mm``: a run
    of consecutive x rows by ``|y| <= Y``; ((x_min, x_max), (-Y, Y)), m, or None if none."""
    at = [g for g in grid if g[2] == z]
    xs = sorted({g[0] for g in at})
    ys = sorted({abs(g[1]) for g in at})
    error = {(g[0], g[1]): g[3] for g in at}
    best: tuple[float, tuple[tuple[float, float], tuple[float, float]]] | None = None
    for half in ys:
        ok = [
            all(e <= tolerance_mm for (x0, y), e in error.items() if x0 == x and abs(y) <= half)
            for x in xs
        ]
        start = None
        for i, good in enumerate([*ok, False]):
            if good and start is None:
                start = i
            elif not good and start is not None:
                area = (xs[i - 1] - xs[start] + 1e-9) * (2.0 * half + 1e-9)
                if best is None or area > best[0]:
                    best = (area, ((xs[start], xs[i - 1]), (-half, half)))
                start = None
    return None if best is None else best[1]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("world", type=Path, help="world file")
    parser.add_argument("--dx", type=float, default=0.04, help="grid step along x, m")
    parser.add_argument("--dy", type=float, default=0.04, help="grid step along y, m")
    parser.add_argument("--nx", type=int, default=3, help="grid points each side along x")
    parser.add_argument("--ny", type=int, default=3, help="grid points each side along y")
    parser.add_argument(
        "--lifts", type=float, nargs="+", default=[0.0, 0.06, 0.12], help="heights above rest, m"
    )
    parser.add_argument("--json", action="store_true", help="print a JSON summary last")
    args = parser.parse_args()
    world = load_world(args.world)
    rest = np.asarray(world.objects[0].pose.position, dtype=float)
    xs = rest[0] + args.dx * np.arange(-args.nx, args.nx + 1)
    ys = args.dy * np.arange(-args.ny, args.ny + 1)
    grid: list[list[float]] = []
    for lift in args.lifts:
        z = rest[2] + lift
        print(f"palm error, mm, with the object's centre at z = {z:.3f} m (lifted {lift:.2f})")
        print("   x \\ y " + " ".join(f"{y:7.2f}" for y in ys))
        for x in xs:
            row = []
            for y in ys:
                error = palm_error(world, np.array([x, y, z]))
                grid.append([round(float(x), 4), round(float(y), 4), round(z, 4), error * 1e3])
                row.append(f"{error * 1e3:7.1f}")
            print(f"{x:8.2f} " + " ".join(row), flush=True)
    within = {}
    for lift in args.lifts:
        z = round(float(rest[2] + lift), 4)
        within[z] = within_rectangle(grid, z)
        print(f"within 3 mm at z = {z:.3f} m: x, y ranges {within[z]}")
    if args.json:
        print(json.dumps({"grid": grid, "within_3mm": within}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

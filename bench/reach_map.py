"""Two-palm reach map: how well a world's robot reaches and holds the lateral grasp over a grid.

For each object centre of a grid (x, y at a few heights above the table; in the robot's frame,
x ahead of its base and y to its left: the world's for a robot at the origin facing +x) and
each grip yaw (from the palms' natural pose, along the robot's y axis),
the object stands on the table there, turned by the grip yaw, and the palms are placed on its
turned +-y faces by the episode's own start-posture solve
(:meth:`worlds.scene.Scene.place_palms`: a humanoid's torso included, both palms solved
together), then held for 0.5 s by the impedance controller (the model's gains); the figure is
the larger palm position error, mm. It shows where a world's trial regions (its ``trials``
section) can lie, and how far a turned grip holds there (``--grip-yaws 0 45 -45``); under the
tables, per height and grip, the largest rectangle of grid points (x rows by a y range
symmetric about the centre line) all within 3 mm. With ``--json`` the last line is
``{"grid": [[x, y, z, grip_yaw_deg, error_mm], ...], "within_3mm": {"z grip": [[x_min,
x_max], [y_min, y_max]] or null}}``.

    python bench/reach_map.py worlds/icub_parcel_pick_place.yaml
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # before bench/, whose worlds/ folder would shadow the package
    sys.path.insert(0, str(ROOT))

from skills.vocabulary import Arm  # noqa: E402
from worlds.palm_poses import lateral_grasp_palm_poses  # noqa: E402
from worlds.scene import Scene  # noqa: E402
from worlds.world_file import World, load_world, world_from_data  # noqa: E402


def palm_error(
    world: World, centre: np.ndarray, hold_s: float = 0.5, grip_yaw_deg: float = 0.0
) -> float:
    """Larger palm position error (m) after holding the grasp at ``centre`` (the object's
    centre, m, world frame) for ``hold_s``, the grip turned by ``grip_yaw_deg`` about z from
    its natural pose (palms along the robot's y axis, as the robot is turned)."""
    grip_yaw_deg += float(world.robot.base.rpy_deg[2])
    obj = world.objects[0]
    half_span = float(obj.shape.size[1]) / 2.0  # type: ignore[union-attr]
    # The object where the palms hold it (its start pose would stand in their way elsewhere),
    # on the table and turned with the grip.
    data = world.model_dump(mode="json")
    data["objects"][0]["pose"] = {
        "position": [float(centre[0]), float(centre[1]), float(obj.pose.position[2])],
        "rpy_deg": [0.0, 0.0, grip_yaw_deg],
    }
    with Scene.from_world(world_from_data(data, world.source)) as scene:
        scene.set_active_obstacles(())
        poses = lateral_grasp_palm_poses(
            centre,
            half_span,
            float(world.robot.palm_size[2]),
            grip_yaw=math.radians(grip_yaw_deg),
        )
        scene.place_palms(poses)
        scene.step(round(hold_s * scene.spec.physics_hz))
        return max(
            float(np.linalg.norm(scene.palm_state(arm).position - poses[arm][0]))
            for arm in (Arm.LEFT, Arm.RIGHT)
        )


def within_rectangle(
    cells: list[list[float]], tolerance_mm: float = 3.0
) -> tuple[tuple[float, float], tuple[float, float]] | None:
    """The largest rectangle of ``cells`` ([x, y, ..., error_mm], one height and grip) all
    within ``tolerance_mm``: a run of consecutive x rows by ``|y| <= Y``; ((x_min, x_max),
    (-Y, Y)), m, or None if none."""
    xs = sorted({c[0] for c in cells})
    ys = sorted({abs(c[1]) for c in cells})
    error = {(c[0], c[1]): c[-1] for c in cells}
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
    parser.add_argument(
        "--grip-yaws", type=float, nargs="+", default=[0.0], help="grip turns about z, degrees"
    )
    parser.add_argument("--json", action="store_true", help="print a JSON summary last")
    args = parser.parse_args()
    world = load_world(args.world)
    rest = np.asarray(world.objects[0].pose.position, dtype=float)
    # The grid in the robot's frame (x forward from its base, y to its left): the object's
    # rest distance ahead of the robot, either side of its centre line.
    heading = math.radians(world.robot.base.rpy_deg[2])
    base = np.asarray(world.robot.base.position, dtype=float)
    forward = np.array([math.cos(heading), math.sin(heading), 0.0])
    left = np.array([-math.sin(heading), math.cos(heading), 0.0])
    ahead = float((rest - base) @ forward)
    xs = ahead + args.dx * np.arange(-args.nx, args.nx + 1)
    ys = args.dy * np.arange(-args.ny, args.ny + 1)
    grid: list[list[float]] = []
    for grip in args.grip_yaws:
        for lift in args.lifts:
            z = rest[2] + lift
            print(
                f"palm error, mm, with the object's centre at z = {z:.3f} m (lifted {lift:.2f}), "
                f"the grip turned {grip:g} deg"
            )
            print("   x \\ y " + " ".join(f"{y:7.2f}" for y in ys))
            for x in xs:
                row = []
                for y in ys:
                    at = base + x * forward + y * left
                    at[2] = z
                    error = palm_error(world, at, grip_yaw_deg=grip)
                    cell = [round(float(x), 4), round(float(y), 4), round(z, 4), grip, error * 1e3]
                    grid.append(cell)
                    row.append(f"{error * 1e3:7.1f}")
                print(f"{x:8.2f} " + " ".join(row), flush=True)
    within = {}
    for grip in args.grip_yaws:
        for lift in args.lifts:
            z = round(float(rest[2] + lift), 4)
            found = within_rectangle([c for c in grid if c[2] == z and c[3] == grip])
            within[f"{z} {grip:g}"] = found
            print(f"within 3 mm at z = {z:.3f} m, grip {grip:g} deg: x, y ranges {found}")
    if args.json:
        print(json.dumps({"grid": grid, "within_3mm": within}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

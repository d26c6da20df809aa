"""The palms' static stiffness as the impedance law applies it, against the gains' stated one.

Usage: ``python bench/bench_static_stiffness.py [WORLD.yaml ...] [--json]``

For each world (default: the two shipped pick-and-place worlds) the robot is loaded, holds its
start pose for a second, and each palm's translational stiffness against a load that holds it
still is read from the law (``DualArmImpedanceController.static_palm_stiffness``). Then 5 N is
pushed up on each palm (PyBullet's external force, every physics step, 3 s) and its rise
measured: ``measured_z_n_per_m`` is 5 N over that rise. The law's implicit damping scales the
spring's torques by ``G = M (M + dt D)^-1``, which assumes the joints free to accelerate; a
load that holds the palm still meets only that share, so the stiffness a held parcel's weight
meets is below ``stated_n_per_m``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

# isort: off
from duet_robot.blas import pin_blas_kernel  # noqa: E402

pin_blas_kernel()
import numpy as np  # noqa: E402
import pybullet as pb  # noqa: E402

from skills.vocabulary import Arm  # noqa: E402
from worlds.scene import Scene  # noqa: E402
from worlds.world_file import load_world  # noqa: E402

# isort: on

WORLDS = ("worlds/parcel_pick_place.yaml", "worlds/icub_parcel_pick_place.yaml")
PUSH_N = 5.0


def measure(path: Path) -> dict[str, Any]:
    """The figures of one world: per palm, stated, law and measured stiffness, N/m."""
    world = load_world(path)
    out: dict[str, Any] = {"world": world.name}
    with Scene.from_world(world) as scene:
        hz = scene.spec.physics_hz
        scene.step(hz)
        controller = scene.controller
        law = controller.static_palm_stiffness()
        start = {arm: scene.palm_state(arm).position for arm in Arm}
        for _ in range(3 * hz):
            for arm in Arm:
                spec = scene.robot.arms[arm]
                body = scene.robot_ids[spec.body]
                at = pb.getLinkState(body, spec.palm_link, physicsClientId=scene.client)[0]
                pb.applyExternalForce(
                    body,
                    spec.palm_link,
                    [0.0, 0.0, PUSH_N],
                    at,
                    pb.WORLD_FRAME,
                    physicsClientId=scene.client,
                )
            scene.step(1)
        for arm in Arm:
            rise = float(scene.palm_state(arm).position[2] - start[arm][2])
            out[arm.value] = {
                "stated_n_per_m": float(controller.gains(arm).stiffness_linear),
                "law_xyz_n_per_m": [round(float(v), 1) for v in np.diag(law[arm])],
                "measured_z_n_per_m": round(PUSH_N / rise, 1),
            }
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("worlds", nargs="*", default=[str(ROOT / w) for w in WORLDS])
    parser.add_argument("--json", action="store_true", help="one JSON object per world")
    args = parser.parse_args()
    for name in args.worlds:
        figures = measure(Path(name))
        if args.json:
            print(json.dumps(figures))
            continue
        for arm in Arm:
            f = figures[arm.value]
            print(
                f"{figures['world']}, {arm.value} palm: stated {f['stated_n_per_m']:g} N/m; "
                f"against a held load (x, y, z) {f['law_xyz_n_per_m']} N/m by the law, "
                f"{f['measured_z_n_per_m']} N/m up measured ({PUSH_N:g} N pushed)"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

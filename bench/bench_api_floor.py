"""How fast the whole loop could be: the PyBullet calls it cannot do without, timed in real trials.

Usage: ``python bench/bench_api_floor.py [--n N] [--seed S] [--json]``

Runs ``N`` trials of the default world in this process, as ``app.py trials`` draws them (after
one more, trial ``N``, to warm up). After every physics step the safety watch sees, it makes
again, and times, the PyBullet calls that step needed at the least, with no Python around them
but the loops that make them:

- the control law: each robot body's joint states read and torques written (zeros: torque
  control adds them to the next step's, so the write changes nothing), and, whenever the law
  re-linearised, its inverse dynamics, mass matrix, palm Jacobians and palm poses;
- the judge: the contact queries of every physics step (the table's, each obstacle present's,
  the arms' against each other);
- each control step's read of the links' and objects' poses for the clearance watch.

The leaves' own reads (palm states, contact forces, object poses) are left out: the floor is
a lower bound on what these calls cost. ``api_floor_over_physics`` is the loop's speed over
its physics' speed if all else cost nothing: the issue's target (0.5) is out of reach where it
is below or near 0.5. Figures: ``physics_s`` (inside stepSimulation), ``api_floor_s``,
``api_floor_over_physics`` = physics / (physics + floor), and the trials' own
``whole_over_physics``, all from the same trials.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

# isort: off
from duet_robot.blas import pin_blas_kernel  # noqa: E402

pin_blas_kernel()  # as app.py does, before anything loads numpy (pybullet does)
import pybullet as pb  # noqa: E402
import worlds.control as control  # noqa: E402
import worlds.safety_monitor as safety_monitor  # noqa: E402
from experiment.trials import campaign_of, run_trial  # noqa: E402
from worlds.world_file import load_world  # noqa: E402

# isort: on

DEFAULT = ROOT / "worlds" / "parcel_pick_place.yaml"


class _Floor:
    """The replayed calls' wall time, s, and the re-linearisations seen since the last step."""

    def __init__(self) -> None:
        self.seconds = 0.0
        self.relinearised = 0


def _replay_step(scene: Any, floor: _Floor) -> None:
    """The calls one physics step needed, made again and timed."""
    c = scene.client
    law = scene.controller
    began = time.perf_counter()
    joint_positions = []
    for body, joints in zip(law._bodies, law._body_joints, strict=True):
        states = pb.getJointStates(body, joints, physicsClientId=c)
        joint_positions.append([s[0] for s in states])
        # Torque control adds to the next step's torques: a write of zeros costs what the
        # torques' write does and changes nothing.
        pb.setJointMotorControlArray(
            body, joints, pb.TORQUE_CONTROL, forces=[0.0] * len(joints), physicsClientId=c
        )
    for _ in range(floor.relinearised):
        for g, body in enumerate(law._bodies):
            # The joints as they stand: these calls pose PyBullet's model of the body.
            q = joint_positions[g]
            zeros = [0.0] * len(q)
            pb.calculateInverseDynamics(body, q, zeros, zeros, physicsClientId=c)
            pb.calculateMassMatrix(body, q, physicsClientId=c)
            for i, spec in enumerate(law._specs):
                if law._arm_body[i] == body:
                    pb.calculateJacobian(
                        body, spec.palm_link, [0.0, 0.0, 0.0], q, zeros, zeros, physicsClientId=c
                    )
                    pb.getLinkState(
                        body, spec.palm_link, computeForwardKinematics=1, physicsClientId=c
                    )
    floor.relinearised = 0
    for name in scene.active_obstacles:
        pb.getContactPoints(bodyA=scene.obstacle_ids[name], physicsClientId=c)
    pb.getContactPoints(bodyA=scene.table_id, physicsClientId=c)
    bodies = list(dict.fromkeys(scene.robot_ids))
    if len(bodies) > 1:
        pb.getContactPoints(bodyA=bodies[0], bodyB=bodies[1], physicsClientId=c)
    else:
        pb.getContactPoints(bodyA=bodies[0], bodyB=bodies[0], physicsClientId=c)
    floor.seconds += time.perf_counter() - began


def _replay_sync(scene: Any, collision: Any, floor: _Floor) -> None:
    """The clearance watch's read of every pose, once a control step."""
    c = scene.client
    began = time.perf_counter()
    for body, _, moving, _, _, _ in collision._link_tracks:
        pb.getLinkStates(body, moving, computeForwardKinematics=1, physicsClientId=c)
        pb.getBasePositionAndOrientation(body, physicsClientId=c)
    for body in scene.object_ids.values():
        pb.getBasePositionAndOrientation(body, physicsClientId=c)
    floor.seconds += time.perf_counter() - began


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=4, help="trials (default: 4)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", action="store_true", help="print a JSON summary last")
    args = parser.parse_args()
    floor = _Floor()
    relinearise = control.DualArmImpedanceController._relinearise

    def counted(self: Any) -> None:
        floor.relinearised += 1
        relinearise(self)

    watch = safety_monitor.SafetyMonitor
    after_physics_step, after_control_step = watch.after_physics_step, watch.after_control_step

    def physics_step_seen(self: Any) -> None:
        after_physics_step(self)
        _replay_step(self.scene, floor)

    def control_step_seen(self: Any) -> None:
        _replay_sync(self.scene, self.collision, floor)
        after_control_step(self)

    control.DualArmImpedanceController._relinearise = counted  # type: ignore[method-assign]
    watch.after_physics_step = physics_step_seen  # type: ignore[method-assign]
    watch.after_control_step = control_step_seen  # type: ignore[method-assign]
    world = load_world(DEFAULT)
    payload = {
        "world": world.model_dump(mode="json"),
        "source": str(world.source or ""),
        "tree": "",
        "key": campaign_of(world, args.seed, None),
        "leaves": [],
        "backend": "local",
    }
    run_trial((payload, args.seed, args.n))  # a warm-up: kernels loaded, caches filled
    floor.seconds, floor.relinearised = 0.0, 0
    records = [run_trial((payload, args.seed, t)) for t in range(args.n)]
    record = ROOT / "bench" / "results" / "trials_seed0_n1000.jsonl"
    recorded: dict[int, Any] = {}
    if args.seed == 0 and record.exists():
        with open(record, encoding="utf-8") as f:
            recorded = {r["trial"]: r for r in map(json.loads, f)}
    # The calls made again change nothing: the trials place as the recorded campaign did.
    same = sum(
        r["placement_error_m"] == recorded[r["trial"]]["placement_error_m"]
        for r in records
        if r["trial"] in recorded
    )
    failed = [r["failure"] for r in records if r["failure"].startswith("error")]
    if failed:
        raise SystemExit(f"a trial crashed: {failed[0]}")
    physics = sum(r["physics_wall_s"] for r in records)
    wall = sum(r["wall_time_s"] for r in records) - floor.seconds
    figures = {
        "trials": args.n,
        "physics_s": round(physics, 3),
        "api_floor_s": round(floor.seconds, 3),
        "api_floor_over_physics": round(physics / (physics + floor.seconds), 3),
        "whole_over_physics": round(physics / wall, 3),
        "successes": sum(r["success"] for r in records),
        "placed_as_recorded": same if recorded else None,
    }
    print(
        f"{args.n} trials: physics {figures['physics_s']} s, the calls the loop cannot do "
        f"without {figures['api_floor_s']} s: with nothing else, the loop would run at "
        f"{figures['api_floor_over_physics']:.2f} of the physics' speed (it runs at "
        f"{figures['whole_over_physics']:.2f})"
    )
    if args.json:
        print(json.dumps(figures))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

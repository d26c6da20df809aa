"""Composition step: eq. (5) with two learnt skills, steering, an 8-point field and grasp x2.

``step_us`` is one closed-loop step of the composer, compiled (the packed terms run in one
call into :mod:`skills.interpreter`), with the sphere query answered in its kernel;
``callback_step_us`` is the same step with the query behind a plain Python callable, as an
FCL query is; ``rollout_step_us`` is a step of an open-loop rollout of the rest of the move
(150 steps) in one compiled call; ``reference_step_us`` is the same step from every term's
numpy reference (what the tests compare against), and ``max_diff`` the largest difference
between the two, states and commands, over a step and the rollout. ``compile_s`` is a fresh
process's first step (numba compiles), ``cached_s`` the next fresh process's (it loads the
kernels from the disk cache). With ``--json`` the last line is the JSON of the figures.
Targets: <= 15 us a step, within 1e-9 of the reference, the first compile cached on disk. For
scale, movement_primitives' dual-arm step with pose coupling takes 1.5-1.7 ms.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from skills import quaternion as quat
from skills.composer import DualArmComposer, PalmCommands, grasped_state, reference_step
from skills.couplings.distance_queries import DistanceQuery, SphereObstacles
from skills.couplings.forcing import LearntForcing
from skills.couplings.grasp import GraspMaintenance
from skills.couplings.potential import PotentialFieldAvoidance
from skills.couplings.steering import ObstacleSteering
from skills.couplings.term import CouplingTerm
from skills.default_library import build_default_library
from skills.dual_arm import GraspGeometry
from skills.types import Array
from skills.vocabulary import ARMS, Action

OBSTACLE = np.array([0.62, -0.08, 0.82])
RADIUS = 0.04
#: Arm-link points in the object frame, m.
LINKS_OBJECT = np.array(
    [
        [-0.3, 0.25, 0.2],
        [-0.2, 0.2, 0.15],
        [-0.1, 0.18, 0.1],
        [0.0, 0.16, 0.05],
        [-0.3, -0.25, 0.2],
        [-0.2, -0.2, 0.15],
        [-0.1, -0.18, 0.1],
        [0.0, -0.16, 0.05],
    ]
)


#: The obstacle, as a distance query (the stand-in for FCL).
SPHERE = SphereObstacles(OBSTACLE[None], [RADIUS])


def python_query(points: Array) -> tuple[Array, Array]:
    """The same query behind a plain callable: the compiled step must call it from Python."""
    return SPHERE(points)


def median_time(fn: Callable[[], object], repeats: int, inner: int) -> float:
    """Median seconds per call over ``repeats`` batches of ``inner`` calls."""
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(inner):
            fn()
        times.append((time.perf_counter() - t0) / inner)
    return float(np.median(times))


def composer(query: DistanceQuery = SPHERE) -> DualArmComposer:
    lib = build_default_library()
    g = GraspGeometry.lateral(0.30, 0.02)
    state = grasped_state(
        [0.65, 0.0, 0.675],
        quat.IDENTITY,
        (g.left_position, g.left_orientation),
        (g.right_position, g.right_orientation),
    )
    steer = lib.first(Action.AVOID_OBSTACLE).params
    absolute: list[tuple[CouplingTerm, float]] = [
        (LearntForcing(lib.first(Action.TRANSPORT).pose_model()), 1.0),
        (LearntForcing(lib.first(Action.ROTATE_Z).pose_model()), 1.0),
        (
            ObstacleSteering(
                float(steer["gamma"]), float(steer["beta"]), float(steer["k"]), object_radius=0.1
            ).with_obstacles(OBSTACLE[None], [RADIUS]),
            1.0,
        ),
        (PotentialFieldAvoidance(query, LINKS_OBJECT, gain=0.4), 1.0),
    ]
    relative = {
        arm: [
            (
                GraspMaintenance(
                    g.position(arm), g.orientation(arm), 0.015, inward_normal_object=g.normal(arm)
                ),
                1.0,
            )
        ]
        for arm in ARMS
    }
    goal_q = quat.from_axis_angle([0.0, 0.0, 1.0], 0.4)
    c = DualArmComposer.start(state, [0.6, -0.15, 0.675], goal_q, 2.5, absolute, relative)
    for _ in range(40):  # mid-move, moving towards the obstacle
        c.step(1.0 / 60.0)
    return c


def difference(a: DualArmComposer, b_state: object, ca: PalmCommands, cb: PalmCommands) -> float:
    """Largest absolute difference between a composer's state and commands and the reference's."""
    pairs = [
        (x, y)
        for sa, sb in zip(
            (a.state.object, a.state.left, a.state.right),
            (b_state.object, b_state.left, b_state.right),  # type: ignore[attr-defined]
            strict=True,
        )
        for x, y in zip(sa[:6], sb[:6], strict=True)
    ]
    pairs += [(getattr(ca, f), getattr(cb, f)) for f in ("positions", "twists", "object_twist")]
    return max(float(np.abs(x - y).max()) for x, y in pairs)


FIRST_STEP = """
import sys, time
sys.path.insert(0, {root!r})
t0 = time.perf_counter()
from bench.bench_compose import composer
composer().step(1 / 60)
print(time.perf_counter() - t0)
"""


def fresh_first_steps(cache: Path) -> tuple[float, float]:
    """A fresh process's first step with an empty kernel cache, then the next one's (s)."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    root = str(Path(__file__).resolve().parents[1])
    code = FIRST_STEP.format(root=root)
    times = []
    for _ in range(2):
        out = subprocess.run(
            [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
        )
        times.append(float(out.stdout.split()[-1]))
    return times[0], times[1]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print a JSON summary last")
    args = parser.parse_args()
    fit_s = median_time(build_default_library, repeats=5, inner=1)
    with tempfile.TemporaryDirectory() as cache:
        compile_s, cached_s = fresh_first_steps(Path(cache))
    c = composer()
    callback = composer(python_query)
    state = c.state
    dt = 1.0 / 60.0
    step_s = median_time(lambda: c.step(dt, state), repeats=15, inner=300)
    callback_s = median_time(lambda: callback.step(dt, state), repeats=15, inner=300)
    c.state = state
    reference_s = median_time(lambda: reference_step(c, dt, state), repeats=15, inner=100)
    diffs = []
    for twin in (c, callback):
        twin.state = state
        want, want_cmd = reference_step(twin, dt)
        diffs.append(difference(twin, want, twin.step(dt), want_cmd))
    steps = 150  # the rest of the move, open loop, in one call
    c.state = state
    path = c.rollout(steps, dt).values
    c.state = state
    for i in range(steps):
        want, _ = reference_step(c, dt)
        c.state = want
        diffs.append(float(np.abs(path[i, :57] - c.state.values()[:57]).max()))

    def rollout() -> None:
        c.state = state
        c.rollout(steps, dt)

    rollout_s = median_time(rollout, repeats=15, inner=10) / steps
    points = state.object.position + quat.rotate(state.object.orientation, LINKS_OBJECT)
    query_s = median_time(lambda: SPHERE(points), repeats=15, inner=300)
    figures = {
        "step_us": round(step_s * 1e6, 1),
        "callback_step_us": round(callback_s * 1e6, 1),
        "rollout_step_us": round(rollout_s * 1e6, 2),
        "reference_step_us": round(reference_s * 1e6, 1),
        "max_diff": max(diffs),
        "compile_s": round(compile_s, 2),
        "cached_s": round(cached_s, 2),
        "query_us": round(query_s * 1e6, 1),
        "fit_ms": round(fit_s * 1e3, 1),
    }
    print(
        f"composition step (2 learnt skills, steering, 8-point field, grasp x2, eq. 5), "
        f"compiled: {figures['step_us']} us (target <= 15); with the query called from "
        f"Python: {figures['callback_step_us']} us"
    )
    print(
        f"  open-loop rollout of {steps} steps in one call: {figures['rollout_step_us']} us a "
        f"step; the numpy reference: {figures['reference_step_us']} us a step"
    )
    print(
        f"  largest difference from the reference {figures['max_diff']:.1e} (<= 1e-9); a fresh "
        f"process's first step {figures['compile_s']} s compiling, {figures['cached_s']} s "
        "from the disk cache"
    )
    print(f"  the numpy sphere query on 8 points alone: {figures['query_us']} us")
    print(f"learning the default skills from their demonstrations: {figures['fit_ms']} ms")
    if args.json:
        print(json.dumps(figures))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Composition benchmark: one dual-arm composition step, and learning the default skills.

The step composes two absolute skills (the learnt pick-and-place and rotation), obstacle
steering, potential-field avoidance over 8 link points and grasp maintenance on both palms,
and yields both palms' poses and twists (the paper's eq. 5), closed loop from a measured
state. It includes the field's distance query to the obstacle, a sphere
(:class:`skills.couplings.SphereObstacles`, numpy; ``query_us`` times it alone).

``step_us`` is the float (numpy) path. ``compiled_step_us`` is the same composition compiled
with numba (``DualArmComposer.start(..., compiled=True)``), which evaluates the sphere query
inside its kernel; ``compiled_callback_step_us`` is the compiled step with the same query
behind a plain Python callable, as an FCL query would be; ``compiled_rollout_step_us`` is a
step of an open-loop rollout of the rest of the move (150 steps) in one compiled call
(``DualArmComposer.rollout``). All must match the float path within 1e-9
(``compiled_max_diff``: the largest difference in the states and commands).
``compile_s`` is the compiled step's first call: numba compiles, or loads its on-disk cache.
The compiled figures are None without numba. With ``--json`` the last line is the JSON of
these figures and ``fit_ms``; medians of repeats. Targets: step <= 50 us with numpy,
<= 10 us compiled. For scale, movement_primitives' dual-arm step with pose coupling takes
1.5-1.7 ms.
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Callable
from functools import partial

import numpy as np
from skills.compiled import available

from skills import quaternion as quat
from skills.composer import DualArmComposer, PalmCommands, grasped_state
from skills.coupling import CouplingTerm
from skills.couplings.grasp import GraspMaintenance
from skills.couplings.potential import DistanceQuery, PotentialFieldAvoidance, SphereObstacles
from skills.couplings.steering import ObstacleSteering
from skills.default_library import build_default_library
from skills.dual_arm import ARMS, GraspGeometry
from skills.labels import Action
from skills.pose_dmp import LearntForcing
from skills.types import Array

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


def composer(compiled: bool = False, query: DistanceQuery = SPHERE) -> DualArmComposer:
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
    c = DualArmComposer.start(
        state, [0.6, -0.15, 0.675], goal_q, 2.5, absolute, relative, compiled=compiled
    )
    for _ in range(40):  # mid-move, moving towards the obstacle
        c.step(1.0 / 60.0)
    return c


def difference(a: DualArmComposer, b: DualArmComposer, ca: PalmCommands, cb: PalmCommands) -> float:
    """Largest absolute difference between two composers' states and commands."""
    pairs = [
        (x, y)
        for sa, sb in zip(
            (a.state.object, a.state.left, a.state.right),
            (b.state.object, b.state.left, b.state.right),
            strict=True,
        )
        for x, y in zip(sa[:6], sb[:6], strict=True)
    ]
    pairs += [(getattr(ca, f), getattr(cb, f)) for f in ("positions", "twists", "object_twist")]
    return max(float(np.abs(x - y).max()) for x, y in pairs)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print a JSON summary last")
    args = parser.parse_args()
    fit_s = median_time(build_default_library, repeats=5, inner=1)
    c = composer()
    state = c.state
    dt = 1.0 / 60.0

    def step() -> None:
        c.step(dt, state)  # closed loop from the same measured state each time

    step_s = median_time(step, repeats=15, inner=300)
    points = state.object.position + quat.rotate(state.object.orientation, LINKS_OBJECT)
    query_s = median_time(lambda: SPHERE(points), repeats=15, inner=300)
    figures: dict[str, float | None] = {
        "step_us": round(step_s * 1e6, 1),
        "compiled_step_us": None,
        "compiled_callback_step_us": None,
        "compiled_rollout_step_us": None,
        "compiled_max_diff": None,
        "compile_s": None,
        "query_us": round(query_s * 1e6, 1),
        "fit_ms": round(fit_s * 1e3, 1),
    }
    print(
        f"composition step (2 learnt skills, steering, 8-point field, grasp x2, eq. 5): "
        f"{figures['step_us']} us with numpy (target <= 50)"
    )
    if available():
        t0 = time.perf_counter()
        fast = composer(compiled=True)  # its first step compiles, or loads numba's cache
        figures["compile_s"] = round(time.perf_counter() - t0, 2)
        callback = composer(compiled=True, query=python_query)
        diffs = []
        for twin, key in ((fast, "compiled_step_us"), (callback, "compiled_callback_step_us")):
            twin.state = state
            diffs.append(difference(c, twin, c.step(dt, state), twin.step(dt, state)))
            figures[key] = round(
                median_time(partial(twin.step, dt, state), repeats=15, inner=300) * 1e6, 1
            )
        steps = 150  # the rest of the move, open loop, in one call
        start = fast.state
        want = c.rollout(steps, dt).values
        fast.state = start
        diffs.append(float(np.abs(fast.rollout(steps, dt).values - want).max()))

        def rollout() -> None:
            fast.state = start
            fast.rollout(steps, dt)

        figures["compiled_rollout_step_us"] = round(
            median_time(rollout, repeats=15, inner=10) / steps * 1e6, 2
        )
        figures["compiled_max_diff"] = max(diffs)
        print(
            f"  compiled (numba): {figures['compiled_step_us']} us (stretch target <= 10); "
            f"with the query called from Python: {figures['compiled_callback_step_us']} us"
        )
        print(
            f"  compiled open-loop rollout of {steps} steps in one call: "
            f"{figures['compiled_rollout_step_us']} us a step"
        )
        print(
            f"  largest difference from numpy {figures['compiled_max_diff']:.1e} (<= 1e-9); "
            f"first call {figures['compile_s']} s"
        )
    else:
        print("  compiled: numba is not installed (pip install -e '.[fast]')")
    print(f"  the numpy sphere query on 8 points alone: {figures['query_us']} us")
    print(f"learning the 5 default skills from their demonstrations: {figures['fit_ms']} ms")
    if args.json:
        print(json.dumps(figures))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

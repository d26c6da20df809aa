"""DMP core benchmark: fit, closed-loop step and open-loop rollout of a pose DMP.

Prints one line per figure; with ``--json`` the last line is a JSON object with
``fit_ms``, ``step_us`` (:meth:`PoseDMP.step`, compiled), ``reference_step_us`` (the pure
:func:`pose_step`, numpy) and ``rollout_ms`` (medians of repeats). Targets: fit <= 5 ms,
step <= 20 us, rollout <= 20 ms. For scale, movement_primitives 0.9.1 took 140 ms, 130-145 us
and 79 ms on a machine of this size.
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Callable

import numpy as np

from skills import quaternion as quat
from skills.demonstration import Demonstration
from skills.pose_dmp import PoseDMP, PoseState, PoseTarget, fit_pose, pose_rollout, pose_step


class ConstantPush:
    """A minimal coupling term: a constant acceleration (what the step figure includes)."""

    def __init__(self) -> None:
        self.lin = np.array([0.0, 0.0, 0.1])
        self.ang = np.zeros(3)

    def acceleration(self, state: PoseState, target: PoseTarget) -> tuple[np.ndarray, np.ndarray]:
        return self.lin, self.ang


def demo(n: int = 1000) -> Demonstration:
    t = np.linspace(0.0, 2.0, n)
    u = t / 2.0
    s = 10 * u**3 - 15 * u**4 + 6 * u**5
    y = np.stack((0.4 * s, 0.2 * np.sin(np.pi * s), 0.15 * np.sin(np.pi * u) ** 2), axis=1)
    q = quat.from_axis_angle(np.array([0.2, 0.3, 1.0]), 1.2 * s)
    return Demonstration.create(t, y, q)


def median_time(fn: Callable[[], object], repeats: int, inner: int = 1) -> float:
    """Median seconds per call over ``repeats`` batches of ``inner`` calls."""
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(inner):
            fn()
        times.append((time.perf_counter() - t0) / inner)
    return float(np.median(times))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--json", action="store_true", help="print a JSON summary last")
    args = parser.parse_args()
    d = demo()
    fit_s = median_time(lambda: fit_pose(d), repeats=30)
    model = fit_pose(d)
    target = model.target(d.positions[0], d.orientations[0], d.positions[-1], d.orientations[-1])
    state = PoseState.at_rest(d.positions[0], d.orientations[0])
    state = pose_step(state, model, target, 0.002)
    couplings = [ConstantPush()]
    dmp = PoseDMP(model, target, state, list(couplings))
    step_s = median_time(lambda: dmp.step(0.002, state), 15, 2000)
    reference_s = median_time(lambda: pose_step(state, model, target, 0.002, couplings), 15, 500)
    rollout_s = median_time(lambda: pose_rollout(model, target, state, 0.002, 1000), 15)
    figures = {
        "fit_ms": round(fit_s * 1e3, 3),
        "step_us": round(step_s * 1e6, 2),
        "reference_step_us": round(reference_s * 1e6, 2),
        "rollout_ms": round(rollout_s * 1e3, 3),
    }
    print(f"fit pose DMP, 1000 samples, 50 RBF/dim: {figures['fit_ms']} ms (target <= 5)")
    print(f"closed-loop pose step, one coupling:    {figures['step_us']} us (target <= 20)")
    print(f"  the same step from the numpy reference: {figures['reference_step_us']} us")
    print(f"open-loop rollout, 1000 steps:          {figures['rollout_ms']} ms (target <= 20)")
    if args.json:
        print(json.dumps(figures))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Which actuator fault drops a Hard trial: rerun Hard trials with one kind of fault alone.

Each trial is rerun bit for bit from (world, seed, trial index) as ``app.py trials --hard``
draws it, its pushes kept, with: every fault (as drawn), none, the torque bias alone, the
torque scale alone, and the lag and latency alone. Prints one line per run.

Usage::

    python bench/hard_fault_ablation.py worlds/parcel_pick_place.yaml --trials 2 3 11
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # before bench/, whose worlds/ folder would shadow the package
    sys.path.insert(0, str(ROOT))

# isort: off
from duet_robot.blas import pin_blas_kernel  # noqa: E402

pin_blas_kernel()  # as app.py does: one BLAS kernel on every x86-64 host
from experiment.episode import run_episode  # noqa: E402
from experiment.hard import draw_hard, with_pushes  # noqa: E402
from experiment.layout import draw_trial  # noqa: E402
from worlds.actuators import ActuatorFaults  # noqa: E402
from worlds.truth import PhysicalTruth  # noqa: E402
from worlds.world_file import load_world  # noqa: E402

# isort: on


def only(faults: ActuatorFaults, kind: str) -> ActuatorFaults | None:
    """``faults`` with every kind but ``kind`` removed (``all``: as drawn; ``none``: None)."""
    if kind == "all":
        return faults
    if kind == "none":
        return None
    n = len(faults.torque_scale)
    ideal = replace(
        faults, torque_scale=(1.0,) * n, torque_bias_nm=(0.0,) * n, lag_s=0.0, latency_ticks=0
    )
    if kind == "bias":
        return replace(ideal, torque_bias_nm=faults.torque_bias_nm)
    if kind == "scale":
        return replace(ideal, torque_scale=faults.torque_scale)
    return replace(ideal, lag_s=faults.lag_s, latency_ticks=faults.latency_ticks)  # "lag"


KINDS = ("all", "none", "bias", "scale", "lag")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("world")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--trials", type=int, nargs="+", default=[0])
    parser.add_argument("--kinds", nargs="+", choices=KINDS, default=list(KINDS))
    args = parser.parse_args()
    base = load_world(args.world)
    for trial in args.trials:
        world, _ = draw_trial(base, args.seed, trial)
        hard = draw_hard(world, args.seed, trial)
        pushed = with_pushes(world, hard.pushes)
        for kind in args.kinds:
            truth: PhysicalTruth = hard.truth
            if truth.actuators is not None:
                truth = replace(truth, actuators=only(truth.actuators, kind))
            s = run_episode(pushed, None, out=None, animation=False, truth=truth).summary()
            verdict = "success" if s["success"] else s["failure"]
            print(
                f"trial {trial:4d}  faults {kind:<5}  {verdict:<40.40}  "
                f"slip {s.get('slip_mm')} mm  dropped {s.get('dropped')}",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())

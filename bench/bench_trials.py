"""Trial-campaign benchmark: 10 trials of the default world, as ``app.py trials`` runs them.

Prints success, wall seconds per trial (campaign wall time over trials, with all workers),
trials per hour, the real-time factor of the whole task (simulated over wall seconds, per
worker: tree, control, checks and judge) and, measured in the same trials, the real-time
factor of the physics engine's steps alone (``physics_only_realtime_factor``: the same scene
and the same physics steps with their contacts, without control, tree or checks). The
issue's targets: ``realtime_factor`` at least half of the physics-only one, and at least 15.
With ``--json`` the last line is ``{"trials", "successes", "wall_s_per_trial",
"trials_per_hour", "realtime_factor", "physics_only_realtime_factor",
"whole_over_physics", "worker_time_split_s", "without_tree_over_physics"}``: the split is
the trials' wall time in the physics steps, the control law before each step, the safety
watch (contacts every physics step, clearances every control step) and the tree with its
leaves; the last figure is the loop's speed over its physics' with a tree that cost nothing.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # before bench/, whose worlds/ folder would shadow the package
    sys.path.insert(0, str(ROOT))

# isort: off
from duet_robot.blas import pin_blas_kernel  # noqa: E402

pin_blas_kernel()  # as app.py does: one BLAS kernel on every x86-64 host
from experiment.summary import split_line  # noqa: E402
from experiment.trials import run_campaign, summarise  # noqa: E402
from worlds.world_file import load_world  # noqa: E402

# isort: on

DEFAULT = ROOT / "worlds" / "parcel_pick_place.yaml"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=10, help="trials (default: 10)")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--json", action="store_true", help="print a JSON summary last")
    args = parser.parse_args()
    world = load_world(DEFAULT)
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        records = run_campaign(world, args.n, 12345, Path(tmp), args.workers)
        wall = time.perf_counter() - t0
    s = summarise(records)
    figures = {
        "trials": s["trials"],
        "successes": s["successes"],
        "wall_s_per_trial": round(wall / max(s["trials"], 1), 2),
        "trials_per_hour": round(3600.0 * s["trials"] / wall, 1),
        "realtime_factor": s["realtime_factor"],
        "physics_only_realtime_factor": s["physics_only_realtime_factor"],
        "whole_over_physics": round(s["realtime_factor"] / s["physics_only_realtime_factor"], 3),
        "worker_time_split_s": s["worker_time_split"],
    }
    split = s["worker_time_split"]
    # The loop with a tree that cost nothing: physics, the control law and the safety watch.
    below_tree = split["physics"] + split["control"] + split["watch"]
    figures["without_tree_over_physics"] = round(split["physics"] / below_tree, 3)
    print(
        f"{figures['successes']} of {figures['trials']} trials succeeded "
        f"with {args.workers} workers"
    )
    print(f"wall time per trial: {figures['wall_s_per_trial']} s")
    print(f"trials per hour: {figures['trials_per_hour']}")
    print(
        f"real-time factor per worker: {figures['realtime_factor']} (whole task), "
        f"{figures['physics_only_realtime_factor']} (physics steps alone): "
        f"{figures['whole_over_physics']:.2f} of the physics' speed"
    )
    print(split_line(s).strip())
    print(
        f"without the tree and leaves the loop would run at "
        f"{figures['without_tree_over_physics']:.2f} of the physics' speed"
    )
    if args.json:
        print(json.dumps(figures))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

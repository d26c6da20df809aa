"""Trial-campaign benchmark: 10 trials of the default world, as ``app.py trials`` runs them.

Prints success, wall seconds per trial (campaign wall time over trials, with all workers) and
the real-time factor (simulated over wall seconds, per worker). With ``--json`` the last line
is ``{"trials", "successes", "wall_s_per_trial", "realtime_factor"}``.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

from experiment.trials import run_campaign, summarise
from worlds.world_file import load_world

DEFAULT = Path(__file__).resolve().parents[1] / "worlds" / "parcel_pick_place.yaml"


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
        "realtime_factor": s["realtime_factor"],
    }
    print(
        f"{figures['successes']} of {figures['trials']} trials succeeded "
        f"with {args.workers} workers"
    )
    print(f"wall time per trial: {figures['wall_s_per_trial']} s")
    print(f"real-time factor per worker: {figures['realtime_factor']}")
    if args.json:
        print(json.dumps(figures))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

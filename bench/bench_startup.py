"""Start-up benchmark: how soon ``app.py run`` ticks its tree, and how long its figure takes.

Each repetition runs ``app.py run WORLD --out TMP --no-animation`` in a fresh interpreter (the
default world unless ``--world``), as a user would, and reads the time of three moments from
it, counted from just before the parent started the process:

- ``import_s``: the run's modules imported (``app`` and :mod:`experiment.episode`);
- ``first_tick_s``: the end of the tree's first tick (the world loaded and checked, the
  skill library and the tree built, the scene up, the first leaf's first step computed);
- ``figure_s``: the trajectory figure written (``trajectories.png``: the moves traced,
  drawn and saved, imports included), as the run spends it after its verdict.

``first_tick_cpu_s`` is the CPU time the process used until its first tick: on a machine
shared with other work it says what the wall times would be on an idle one. Figures are
medians over ``--repeats`` (3). The issue's targets: ``first_tick_s`` at most 2, ``figure_s``
at most 1. With ``--json`` the last line is ``{"import_s", "first_tick_s",
"first_tick_cpu_s", "figure_s", "repeats"}``.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEFAULT = ROOT / "worlds" / "parcel_pick_place.yaml"

#: Runs ``app.main`` as ``app.py run`` does, timing it from inside (monotonic clock: the
#: parent's and the child's readings compare).
CHILD = """
import json, os, sys, time
import app
import experiment.episode as episode
import experiment.move_recorder as move_recorder
import planner.runner as runner
moments = {"import": time.monotonic()}
first_tick = runner.tick_tree
def tick_tree(tree):
    first_tick(tree)
    if "first_tick" not in moments:
        moments["first_tick"] = time.monotonic()
        cpu = os.times()
        moments["first_tick_cpu"] = cpu.user + cpu.system
runner.tick_tree = tick_tree
traces, figure = move_recorder.MoveRecorder.traces, episode.trajectory_figure
def timed_traces(self, library):
    moments["figure_start"] = time.monotonic()
    return traces(self, library)
def timed_figure(*args, **kwargs):
    path = figure(*args, **kwargs)
    moments["figure_end"] = time.monotonic()
    return path
move_recorder.MoveRecorder.traces, episode.trajectory_figure = timed_traces, timed_figure
code = app.main(["run", sys.argv[1], "--out", sys.argv[2], "--no-animation"])
print(json.dumps(moments))
sys.exit(code)
"""


def one_run(world: Path, out: Path) -> dict[str, float]:
    """The moments of one fresh ``app.py run``, s from just before its process started."""
    start = time.monotonic()
    done = subprocess.run(
        [sys.executable, "-c", CHILD, str(world), str(out)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=False,
    )
    if done.returncode not in (0, 1):  # 1: the task failed, still a run to time
        raise SystemExit(f"app.py run exited {done.returncode}:\n{done.stderr[-2000:]}")
    lines = done.stdout.strip().splitlines()
    if not lines:
        raise SystemExit(f"app.py run printed nothing to time:\n{done.stderr[-2000:]}")
    moments = json.loads(lines[-1])
    return {
        "import_s": moments["import"] - start,
        "first_tick_s": moments["first_tick"] - start,
        "first_tick_cpu_s": moments["first_tick_cpu"],
        "figure_s": moments["figure_end"] - moments["figure_start"],
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--world", type=Path, default=DEFAULT, help="world file (default world)")
    parser.add_argument("--repeats", type=int, default=3, help="fresh runs (default: 3)")
    parser.add_argument("--json", action="store_true", help="print a JSON summary last")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        runs = [one_run(args.world, Path(tmp) / f"run{i}") for i in range(args.repeats)]
    figures: dict[str, float | int] = {
        key: round(statistics.median(r[key] for r in runs), 3) for key in runs[0]
    }
    figures["repeats"] = args.repeats
    print(f"modules imported: {figures['import_s']} s after the process started")
    print(
        f"first tick: {figures['first_tick_s']} s after it started "
        f"({figures['first_tick_cpu_s']} s of CPU)"
    )
    print(f"trajectory figure: {figures['figure_s']} s to trace, draw and write")
    if args.json:
        print(json.dumps(figures))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

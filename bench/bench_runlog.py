"""The run log's cost per tick: the default tree against the in-memory world, the log's
post-tick work (status changes, blackboard writes, the file) timed around each call.

Run from the project folder as ``python -m bench.bench_runlog [--json]`` (so the folder's own
packages are imported). ``per_tick_us`` is the mean wall time of
:meth:`planner.runlog.RunLog.record_tick` per tick, ``share_of_tick`` its share of the whole
run (tree and log; the fake world costs next to nothing, so in PyBullet the share is smaller).
With ``--json`` the last line is the JSON of the figures.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np
import py_trees

from planner.default_tree import default_tree
from planner.port import ObstacleInfo
from planner.runlog import RunLog
from planner.runner import run_tree
from planner.testing.fake_world import FakeObject, FakeWorld
from planner.testing.fixtures import paper_moves
from skills.default_library import build_default_library


def measure() -> dict[str, float]:
    """One run of the default three-move task with the log attached; the log's figures."""
    library = build_default_library()
    py_trees.blackboard.Blackboard.clear()
    world = FakeWorld(
        objects=[FakeObject("parcel", np.array([0.20, 0.30, 0.15]))],
        obstacles=[
            ObstacleInfo("ball_right", np.array([0.625, -0.075, 0.81]), 0.04),
            ObstacleInfo("ball_left", np.array([0.74, 0.0, 0.80]), 0.04),
        ],
        moves=paper_moves(),
    )
    root = default_tree()
    spent = [0.0]
    with tempfile.TemporaryDirectory() as folder:
        log = RunLog(Path(folder) / "run.jsonl", clock=world.time)
        record = log.record_tick

        def timed(node: py_trees.behaviour.Behaviour) -> None:
            start = time.perf_counter()
            record(node)
            spent[0] += time.perf_counter() - start

        log.record_tick = timed  # type: ignore[method-assign]
        with log:
            result = run_tree(
                root, world, library, 1.0 / 60.0, 120.0, {"/object": "parcel"},
                attach=(log.attach,),
            )  # fmt: skip
    return {
        "ticks": result.ticks,
        "nodes": sum(1 for _ in root.iterate()),
        "per_tick_us": round(1e6 * spent[0] / result.ticks, 1),
        "share_of_tick": round(spent[0] / result.wall_time, 3),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print the figures as JSON last")
    args = parser.parse_args()
    figures = measure()
    print(
        f"run log: {figures['per_tick_us']} us a tick over {figures['ticks']} ticks of a "
        f"{figures['nodes']}-node tree ({100 * figures['share_of_tick']:.0f} % of the run)"
    )
    if args.json:
        print(json.dumps(figures))


if __name__ == "__main__":
    main()

"""The paper's experiment: many trials of three pick-and-place moves with new obstacles.

Each trial draws, from ``numpy.random.default_rng([seed, trial])``:

- the parcel's start on the table, near the robot's centre line;
- three goals, in the centre, right (-y) and left (+y) regions of the workspace;
- for at least two of the three moves a sphere, either *on the line*: above the straight path
  between the move's start and goal, under the demonstrated lift, or *ahead*: in front (+x) of
  the carry at the lifted parcel's height. Every sphere clears the parcel at its move's start
  and goal (by 2 cm at least) and stays 5 cm off the vertical line of each palm there (where
  the forearm rises), so only the carry can meet it: a sphere the robot would have to be in at
  the start or the goal is not a test of avoidance.

Trials are judged as :func:`worlds.episode.judge` says (2 cm and 10 degrees per placement,
never dropped, no robot link or parcel touching an obstacle, arms never touching). Results
are appended to ``results.jsonl`` one line per trial as they finish, so an interrupted
campaign resumes where it stopped.
"""

from __future__ import annotations

import json
import math
import os
from collections import Counter
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from worlds.world_file import _CONTEXT_BASE_DIR, World

#: Regions of the goals, (x range, y range) of the parcel's centre, m.
REGIONS: dict[str, tuple[tuple[float, float], tuple[float, float]]] = {
    "centre": ((0.58, 0.68), (-0.03, 0.03)),
    "right": ((0.55, 0.65), (-0.18, -0.12)),
    "left": ((0.55, 0.65), (0.12, 0.18)),
}
START = ((0.50, 0.60), (-0.04, 0.04))
CLEARANCE_M = 0.02
#: Horizontal clearance of a sphere from each palm at its move's start and goal, m.
FOREARM_CLEARANCE_M = 0.05


@dataclass(frozen=True)
class Sphere:
    """An obstacle drawn for one move."""

    name: str
    centre: tuple[float, float, float]
    radius: float
    kind: str  # "line" or "ahead"


def _box_gap(centre: np.ndarray, half: np.ndarray, point: np.ndarray) -> float:
    """Distance from a point to an axis-aligned box's surface (0 inside)."""
    d = np.maximum(np.abs(point - centre) - half, 0.0)
    return float(np.linalg.norm(d))


def draw_trial(base: World, seed: int, trial: int) -> tuple[World, list[str]]:
    """A variant of ``base`` for one trial and the kinds of obstacle per move.

    The base world gives the robot, table, object and simulation settings; this draws the
    object's start, the three goals and the obstacles.
    """
    rng = np.random.default_rng([seed, trial])
    obj = base.objects[0]
    size = np.asarray(getattr(obj.shape, "size", (0.2, 0.3, 0.15)), dtype=float)
    half = size / 2.0
    z = base.table.position[2] + half[2]
    start = np.array([rng.uniform(*START[0]), rng.uniform(*START[1]), z])
    goals = [
        np.array([rng.uniform(*REGIONS[r][0]), rng.uniform(*REGIONS[r][1]), z])
        for r in ("centre", "right", "left")
    ]
    with_obstacle = [True, True, True]
    with_obstacle[int(rng.integers(3))] = bool(rng.random() < 0.5)  # at least two of three
    spheres: list[Sphere | None] = []
    kinds: list[str] = []
    prev = start
    for i, goal in enumerate(goals):
        if not with_obstacle[i]:
            spheres.append(None)
            kinds.append("none")
            prev = goal
            continue
        sphere = _draw_sphere(rng, f"ball_{i + 1}", prev, goal, half)
        spheres.append(sphere)
        kinds.append(sphere.kind)
        prev = goal
    data = base.model_dump(mode="json")
    data["objects"][0]["pose"]["position"] = start.tolist()
    data["obstacles"] = [
        {
            "name": s.name,
            "shape": {"type": "sphere", "radius": s.radius},
            "position": list(s.centre),
        }
        for s in spheres
        if s is not None
    ]
    data["task"] = [
        {
            "object": obj.name,
            "moves": [
                {
                    "goal": {"position": g.tolist(), "rpy_deg": [0.0, 0.0, 0.0]},
                    "obstacles": [] if s is None else [s.name],
                }
                for g, s in zip(goals, spheres, strict=True)
            ],
        }
    ]
    data["name"] = f"{base.name}_trial_{trial}"
    return validate_like(data, base.source), kinds


def validate_like(data: dict[str, Any], source: Path | None) -> World:
    """Validate world data as if it were read from ``source`` (relative paths resolve there)."""
    context: dict[str, Any] = {}
    if source is not None:
        context = {_CONTEXT_BASE_DIR: source.parent, "source": source}
    return World.model_validate(data, context=context)


def _draw_sphere(
    rng: np.random.Generator, name: str, start: np.ndarray, goal: np.ndarray, half: np.ndarray
) -> Sphere:
    """A sphere on the line or ahead of the carry, clear of the box at start and goal."""
    top = start[2] + half[2]
    for _ in range(200):  # rejection sampling; a handful of draws suffice in practice
        radius = float(rng.uniform(0.03, 0.05))
        if rng.random() < 0.5:
            kind = "line"
            t = float(rng.uniform(0.35, 0.65))
            xy = start[:2] + t * (goal[:2] - start[:2])
            centre = np.array([*xy, top + float(rng.uniform(0.03, 0.06)) + radius])
        else:
            kind = "ahead"
            mid = 0.5 * (start + goal)
            front = max(start[0], goal[0]) + half[0]
            centre = np.array(
                [
                    front + radius + float(rng.uniform(0.0, 0.04)),
                    mid[1],
                    top + float(rng.uniform(-0.02, 0.06)),
                ]
            )
        gaps = [_box_gap(p, half, centre) - radius for p in (start, goal)]
        # Each forearm rises from its palm: keep the sphere off the palms' vertical lines at
        # the move's start and goal, or the arm would have to be inside it there.
        palms = [
            p + np.array([0.0, side * (half[1] + 0.01), 0.0])
            for p in (start, goal)
            for side in (1.0, -1.0)
        ]
        off_palms = min(float(np.linalg.norm(centre[:2] - q[:2])) for q in palms) - radius
        if min(gaps) >= CLEARANCE_M and off_palms >= FOREARM_CLEARANCE_M:
            return Sphere(
                name, (float(centre[0]), float(centre[1]), float(centre[2])), radius, kind
            )
    raise RuntimeError(f"{name}: could not place a sphere clear of the start and goal")


def run_trial(job: tuple[dict[str, Any], int, int]) -> dict[str, Any]:
    """Run one trial in this process; returns its JSON-ready record (never raises)."""
    from worlds.episode import run_episode

    base_data, seed, trial = job
    source = Path(base_data["source"]) if base_data["source"] else None
    base = validate_like(base_data["world"], source)
    try:
        world, kinds = draw_trial(base, seed, trial)
        report = run_episode(world, out=None, animation=False)
        record = report.summary()
        record.pop("outputs", None)
        failure = record["failure"] or ""
    except Exception as err:  # a trial that crashes is a failed trial with its reason
        record = {"success": False, "sim_time_s": 0.0, "wall_time_s": 0.0}
        kinds = []
        failure = f"error: {type(err).__name__}: {err}"
    record.update({"trial": trial, "seed": seed, "obstacles": kinds, "failure": failure})
    return record


def reason_of(failure: str) -> str:
    """A failure's category for the summary table."""
    if not failure:
        return "success"
    if failure.startswith("obstacle contact"):
        touching = failure.split(": ", 1)[1] if ": " in failure else ""
        parts = {p.split(" ~ ")[0] for p in touching.split(", ") if p}
        return "obstacle contact: " + "/".join(sorted(parts))
    return failure.split(":")[0].split(" placed")[0]


def read_results(path: Path) -> dict[int, dict[str, Any]]:
    """Records already in ``results.jsonl`` by trial number (a torn last line is ignored)."""
    done: dict[int, dict[str, Any]] = {}
    if not path.exists():
        return done
    for line in path.read_text(encoding="utf-8").splitlines():
        try:
            rec = json.loads(line)
            done[int(rec["trial"])] = rec
        except (json.JSONDecodeError, KeyError, TypeError, ValueError):
            continue
    return done


def run_campaign(
    base: World,
    n: int,
    seed: int,
    out: Path,
    workers: int = 1,
    on_result: Callable[[dict[str, Any], int, int], None] | None = None,
) -> list[dict[str, Any]]:
    """Run trials ``0..n-1`` not yet in ``out/results.jsonl``; append each as it finishes.

    Parameters
    ----------
    base : World
    n : int
        Number of trials.
    seed : int
        Campaign seed: trial ``i`` draws from ``default_rng([seed, i])``.
    out : Path
        Folder of ``results.jsonl``.
    workers : int
        Worker processes (each runs its own PyBullet).
    on_result : callable (record, finished, total), optional
        Progress callback, in the parent process.

    Returns
    -------
    list of dict
        The records of trials ``0..n-1`` for this seed, in trial order.
    """
    out.mkdir(parents=True, exist_ok=True)
    results = out / "results.jsonl"
    done = {t: r for t, r in read_results(results).items() if r.get("seed") == seed}
    pending = [t for t in range(n) if t not in done]
    payload = {"world": base.model_dump(mode="json"), "source": str(base.source or "")}
    jobs = [(payload, seed, t) for t in pending]
    finished = n - len(pending)
    with open(results, "a", encoding="utf-8") as fh:

        def keep(rec: dict[str, Any]) -> None:
            nonlocal finished
            fh.write(json.dumps(rec) + "\n")
            fh.flush()
            os.fsync(fh.fileno())
            done[int(rec["trial"])] = rec
            finished += 1
            if on_result is not None:
                on_result(rec, finished, n)

        if workers <= 1:
            for job in jobs:
                keep(run_trial(job))
        else:
            import multiprocessing as mp

            ctx = mp.get_context("fork")
            with ctx.Pool(workers) as pool:
                for rec in pool.imap_unordered(run_trial, jobs):
                    keep(rec)
    return [done[t] for t in range(n) if t in done]


def summarise(records: Iterable[dict[str, Any]]) -> dict[str, Any]:
    """Counts of successes and failure reasons, mean times."""
    recs = list(records)
    reasons = Counter(reason_of(r.get("failure", "")) for r in recs)
    successes = reasons.pop("success", 0)
    sim = sum(float(r.get("sim_time_s") or 0.0) for r in recs)
    wall = sum(float(r.get("wall_time_s") or 0.0) for r in recs)
    dists = [r["min_obstacle_distance_m"] for r in recs if r.get("min_obstacle_distance_m")]
    return {
        "trials": len(recs),
        "successes": successes,
        "failure_reasons": dict(sorted(reasons.items(), key=lambda kv: (-kv[1], kv[0]))),
        "obstacle_contacts": sum(1 for r in recs if r.get("obstacle_contacts")),
        "min_obstacle_distance_m": min(dists) if dists else None,
        "sim_time_s": round(sim, 2),
        "wall_time_s": round(wall, 2),
        "realtime_factor": round(sim / wall, 2) if wall > 0 else math.nan,
    }

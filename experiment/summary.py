"""A campaign's summary from its records: outcomes, Wilson intervals, splits by condition,
the grip metrics' median and worst.

Pure Python over JSON records (no PyBullet), so that ``app.py report`` reads campaigns fast.
"""

from __future__ import annotations

import math
import statistics
from collections import Counter
from collections.abc import Iterable, Sequence
from typing import Any

from duet_robot.text import printable
from experiment.judge import CLOSEST_VS_CONTACTS, STANDING_SUFFIX
from experiment.metrics import METRIC_LABELS

#: The normal quantile of a two-sided 95 % interval.
Z_95 = 1.959963984540054


def wilson_interval(successes: int, trials: int, z: float = Z_95) -> tuple[float, float]:
    """Wilson score interval of a success rate, as fractions in [0, 1].

    Raises
    ------
    ValueError
        If ``trials`` < 1 or ``successes`` is outside ``0..trials``.
    """
    if trials < 1 or not 0 <= successes <= trials:
        raise ValueError(
            f"wilson_interval: expected 0 <= successes <= trials and trials >= 1, "
            f"got {successes} of {trials}"
        )
    p = successes / trials
    z2 = z * z
    centre = (p + z2 / (2 * trials)) / (1 + z2 / trials)
    half = z * math.sqrt(p * (1 - p) / trials + z2 / (4 * trials * trials)) / (1 + z2 / trials)
    return max(0.0, centre - half), min(1.0, centre + half)


def reason_of(failure: str) -> str:
    """A failure's category for the summary table."""
    if not failure:
        return "success"
    if failure.startswith("obstacle contact"):
        touching = failure.split(": ", 1)[1] if ": " in failure else ""
        parts = {p.split(" ~ ")[0] for p in touching.split(", ") if p}
        return "obstacle contact: " + "/".join(sorted(parts))
    if failure.endswith("after it was placed"):  # "<object> moved 4.0 cm, 16.9 deg after ..."
        return failure.split(" moved ")[0] + " moved after it was placed"
    if failure.endswith(STANDING_SUFFIX):  # "<object> moved 12.0 cm, 3.1 deg from where ..."
        return failure.split(" moved ")[0] + " moved " + STANDING_SUFFIX
    head = failure.split(":")[0]
    # "parcel move 1 placed 2.3 cm, ..." is its move's; "not placed: ..." stays itself.
    return head if head == "not placed" else head.split(" placed")[0]


def composition_label(composition: dict[str, float]) -> str:
    """A placed move's composition in words: the pick-and-place weight and avoidance gain."""
    weight = composition.get("transport_weight", math.nan)
    gain = composition.get("avoid_gain", math.nan)
    avoid = "no avoidance" if gain == 0.0 else f"avoidance x{gain:g}"
    return f"pick-and-place x{weight:g}, {avoid}"


def conditions(record: dict[str, Any]) -> dict[str, str]:
    """The conditions a trial ran under, by axis: ``obstacles`` (how many spheres of each
    kind, e.g. "1 ahead + 2 line") and ``mode`` where the record names one."""
    out: dict[str, str] = {}
    kinds = record.get("obstacles")
    if isinstance(kinds, list) and kinds:
        counts = Counter(str(k) for k in kinds if k != "none")
        out["obstacles"] = " + ".join(f"{n} {k}" for k, n in sorted(counts.items())) or "none"
    mode = record.get("mode")
    if isinstance(mode, str) and mode:
        out["mode"] = mode
    return out


def _rate(successes: int, trials: int) -> dict[str, Any]:
    lo, hi = wilson_interval(successes, trials)
    return {
        "trials": trials,
        "successes": successes,
        "success_interval_95": [round(lo, 4), round(hi, 4)],
    }


def metric_values(records: Iterable[dict[str, Any]], name: str) -> list[float]:
    """The values of grip metric ``name`` over records; a record without one (older campaigns,
    crashed trials, nothing held) is left out."""
    values = (r.get(name) for r in records)
    return [
        float(v)
        for v in values
        if isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
    ]


def metric_summary(records: Iterable[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """Per grip metric (:data:`experiment.metrics.METRIC_LABELS`), its ``median`` and worst
    (``max``) over the records that carry it, and how many do (``trials``); None when none."""
    recs = list(records)
    out = {}
    for name in METRIC_LABELS:
        values = metric_values(recs, name)
        out[name] = {
            "median": round(statistics.median(values), 6) if values else None,
            "max": max(values) if values else None,
            "trials": len(values),
        }
    return out


#: Fewest trials of a campaign before a kind of sphere never drawn is worth a warning: each
#: listed kind stands on a move in about two trials of five, so ten without one is a chance
#: of under 1 %.
UNDRAWN_AFTER_TRIALS = 10


def undrawn_kinds(listed: Sequence[Sequence[str]], records: Iterable[dict[str, Any]]) -> list[str]:
    """One line per kind of sphere a move's region lists (``listed[i]``: move i's
    ``obstacles``) that none of ``records`` drew on that move, once there are
    :data:`UNDRAWN_AFTER_TRIALS` records: a kind that cannot be placed in the world's layout
    is redrawn away, and the campaign would report only the others without a word."""
    recs = [r for r in records if isinstance(r.get("obstacles"), list)]
    if len(recs) < UNDRAWN_AFTER_TRIALS:
        return []
    lines = []
    for i, kinds in enumerate(listed):
        drawn = Counter(str(r["obstacles"][i]) for r in recs if len(r["obstacles"]) > i)
        for kind in kinds:
            if not drawn.get(kind):
                lines.append(
                    f"warning: move {i + 1}'s '{kind}' sphere (trials: its region's obstacles) "
                    f"was drawn in none of {len(recs)} trials: it finds no place in this "
                    "world's layout, and these results hold without it"
                )
    return lines


def summarise(records: Iterable[dict[str, Any]]) -> dict[str, Any]:
    """Counts of successes and failure reasons with a Wilson 95 % interval, the same split by
    condition (:func:`conditions`), the grip metrics (:func:`metric_summary`), mean times."""
    recs = list(records)
    reasons = Counter(reason_of(r.get("failure", "") or "") for r in recs)
    successes = reasons.pop("success", 0)
    sim = sum(float(r.get("sim_time_s") or 0.0) for r in recs)
    wall = sum(float(r.get("wall_time_s") or 0.0) for r in recs)
    physics = sum(float(r.get("physics_wall_s") or 0.0) for r in recs)
    dists = [
        r["min_obstacle_distance_m"] for r in recs if r.get("min_obstacle_distance_m") is not None
    ]
    forearm = [
        r["min_forearm_distance_m"] for r in recs if r.get("min_forearm_distance_m") is not None
    ]
    carried = Counter(
        composition_label(c) for r in recs for c in r.get("compositions") or () if c is not None
    )
    split: dict[str, dict[str, list[int]]] = {}
    for r in recs:
        for axis, value in conditions(r).items():
            tally = split.setdefault(axis, {}).setdefault(value, [0, 0])
            tally[0] += int(bool(r.get("success")))
            tally[1] += 1
    interval = wilson_interval(successes, len(recs)) if recs else (math.nan, math.nan)
    return {
        "trials": len(recs),
        "successes": successes,
        "success_interval_95": [round(interval[0], 4), round(interval[1], 4)],
        "failure_reasons": dict(sorted(reasons.items(), key=lambda kv: (-kv[1], kv[0]))),
        "by_condition": {
            axis: {value: _rate(ok, n) for value, (ok, n) in sorted(values.items())}
            for axis, values in sorted(split.items())
        },
        "compositions": dict(sorted(carried.items(), key=lambda kv: (-kv[1], kv[0]))),
        # A negative clearance is a contact PyBullet may not report (a fixed base in a sphere).
        "obstacle_contacts": sum(
            1
            for r in recs
            if r.get("obstacle_contacts") or (r.get("min_obstacle_distance_m") or 0.0) < 0.0
        ),
        "min_obstacle_distance_m": min(dists) if dists else None,
        # The forearms apart (their contacts count among the arms' above too).
        "forearm_contacts": sum(1 for r in recs if r.get("forearm_contacts")),
        "min_forearm_distance_m": min(forearm) if forearm else None,
        # An arm's wrist or forearm on the table (records made before it was watched: none).
        "table_contacts": (
            sum(1 for r in recs if r.get("table_contacts"))
            if any("table_contacts" in r for r in recs)
            else None
        ),
        "metrics": metric_summary(recs),
        "sim_time_s": round(sim, 2),
        "wall_time_s": round(wall, 2),
        "realtime_factor": round(sim / wall, 2) if wall > 0 else math.nan,
        # The physics engine's steps alone, in the same trials (records that lack it: nan).
        "physics_only_realtime_factor": round(sim / physics, 2) if physics > 0 else math.nan,
        "worker_time_split": worker_time_split(recs),
    }


#: The parts of a trial's loop :func:`worker_time_split` names, in the order it gives them.
LOOP_PARTS = ("physics", "control", "watch", "tree")


def worker_time_split(records: Iterable[dict[str, Any]]) -> dict[str, float] | None:
    """Where the loops of ``records`` spent their wall time, s, summed over the records that
    measured it (records made before it was: None): ``physics`` (PyBullet's steps),
    ``control`` (the torques computed and sent before each step), ``watch`` (contacts every
    physics step, clearances every control step) and ``tree`` (the rest: the tree's ticks,
    its leaves' planning and checks, the run's recording)."""
    timed = [r for r in records if r.get("control_wall_s") is not None]
    if not timed:
        return None
    parts = {
        "physics": sum(float(r.get("physics_wall_s") or 0.0) for r in timed),
        "control": sum(float(r["control_wall_s"]) for r in timed),
        "watch": sum(float(r.get("watch_wall_s") or 0.0) for r in timed),
    }
    whole = sum(float(r.get("wall_time_s") or 0.0) for r in timed)
    parts["tree"] = max(0.0, whole - sum(parts.values()))
    return {name: round(parts[name], 2) for name in LOOP_PARTS}


def split_line(summary: dict[str, Any]) -> str | None:
    """The printed line of :func:`summarise`'s ``worker_time_split`` (None: not measured)."""
    split = summary.get("worker_time_split")
    whole = sum(split.values()) if split else 0.0
    if not split or whole <= 0.0:
        return None
    labels = {
        "physics": "physics",
        "control": "control law",
        "watch": "safety watch",
        "tree": "tree and leaves",
    }
    shares = ", ".join(f"{labels[k]} {100.0 * split[k] / whole:.0f} %" for k in LOOP_PARTS)
    return f"  worker time: {shares}"


def _bounds(successes: int, trials: int, rounded: list[float]) -> tuple[float, float]:
    """The Wilson bounds of a count as printed: from the counts (the summary's are rounded
    to 4 places), the summary's own for no trials."""
    if trials < 1:
        return rounded[0], rounded[1]
    return wilson_interval(successes, trials)


def summary_lines(summary: dict[str, Any]) -> list[str]:
    """The outcome table of :func:`summarise`'s summary, then its grip metrics (those some
    trial measured), as printed lines."""
    # The bounds from the counts, not from the summary's rounded ones: rounded twice, 1 of 1's
    # 20.655 % lower bound printed 20.6.
    lo, hi = _bounds(summary["successes"], summary["trials"], summary["success_interval_95"])
    lines = [f"  {'outcome':<44} trials"]
    lines.append(
        f"  {'success':<44} {summary['successes']} of {summary['trials']} "
        f"(Wilson 95 %: {100 * lo:.1f}-{100 * hi:.1f} %)"
    )
    for reason, count in summary["failure_reasons"].items():
        lines.append(f"  {printable(reason)[:44]:<44} {count}")
    for axis, values in summary["by_condition"].items():
        lines.append(f"  {'by ' + axis:<44} successes")
        for value, rate in values.items():
            a, b = _bounds(rate["successes"], rate["trials"], rate["success_interval_95"])
            lines.append(
                f"  {'  ' + printable(value)[:42]:<44} {rate['successes']} of {rate['trials']} "
                f"({100 * a:.1f}-{100 * b:.1f} %)"
            )
    measured = {k: m for k, m in summary.get("metrics", {}).items() if m["trials"]}
    if measured:
        lines.append(f"  {'grip, over the trials that measured it':<44} {'median':>9} {'worst':>9}")
        for name, m in measured.items():
            label = METRIC_LABELS.get(name, name)
            lines.append(
                f"  {'  ' + label:<44} {m['median']:>9.4g} {m['max']:>9.4g}"
                + ("" if m["trials"] == summary["trials"] else f"  ({m['trials']} trials)")
            )
    return lines


def contact_lines(summary: dict[str, Any]) -> list[str]:
    """The obstacle contacts and closest approaches of :func:`summarise`'s summary, the
    forearms' apart (campaigns recorded before the forearms were measured: no forearm line)."""
    dist = summary["min_obstacle_distance_m"]
    lines = [
        f"  trials with any obstacle contact: {summary['obstacle_contacts']}; closest approach "
        f"{'n/a' if dist is None else f'{dist * 1000:.1f} mm'}"
    ]
    if summary["obstacle_contacts"] and dist is not None and dist > 0.0:
        lines.append(f"    (the closest approach is {CLOSEST_VS_CONTACTS})")
    if "forearm_contacts" in summary:
        forearm = summary["min_forearm_distance_m"]
        lines.append(
            f"  of which by a forearm: {summary['forearm_contacts']}; forearms' closest approach "
            f"{'n/a' if forearm is None else f'{forearm * 1000:.1f} mm'}"
        )
    if summary.get("table_contacts") is not None:
        lines.append(
            f"  trials with an arm's link other than its hand on the table: "
            f"{summary['table_contacts']}"
        )
    return lines


def campaign_lines(summary: dict[str, Any]) -> list[str]:
    """A campaign as ``app.py trials`` prints it under its verdict: :func:`summary_lines`, the
    compositions its moves were placed with, :func:`contact_lines`, the simulated time over
    the worker time, and :func:`split_line`."""
    lines = summary_lines(summary)
    lines.append(f"  {'moves placed with':<44} moves")
    lines += [f"  {label[:44]:<44} {count}" for label, count in summary["compositions"].items()]
    lines += contact_lines(summary)
    lines.append(
        f"  simulated {summary['sim_time_s']:.0f} s in {summary['wall_time_s']:.0f} s of "
        + (
            f"worker time ({summary['realtime_factor']}x real time per worker)"
            if math.isfinite(summary["realtime_factor"])
            else "worker time"
        )
    )
    split = split_line(summary)
    if split is not None:
        lines.append(split)
    return lines

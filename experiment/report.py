"""``app.py report``: a campaign's outcomes from its ``results.jsonl``, as a table and a picture.

Reads records only (no PyBullet, no world file): any results file, old records included.
The picture (``report.png``) shows where trials failed over the start and goal regions, the
failure reasons, and each trial's closest approach to an obstacle.
"""

from __future__ import annotations

import json
import math
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from experiment.records import KEY_FIELDS, RUN_FIELDS, group_of
from experiment.results import ResultsFileError, read_results
from experiment.summary import reason_of, summarise

#: The closest-approach histogram's series: outcome, colour, label.
_OUTCOMES = ((True, "0.6", "success"), (False, "red", "failed"))


@dataclass(frozen=True)
class Campaign:
    """One campaign's records in a results file (a trial run twice counts once, the last),
    and its key (:data:`experiment.records.KEY_FIELDS`: world and tree with their hashes,
    seed, settings) where its records have one."""

    label: str
    records: list[dict[str, Any]]
    key: dict[str, Any] | None = None


@dataclass(frozen=True)
class CampaignFile:
    """The campaigns of a results file and how many of its lines were not records (and why,
    :meth:`experiment.results.Results.skipped_text`)."""

    path: Path
    campaigns: list[Campaign]
    skipped: int
    skipped_text: str = ""
    #: Trials recorded twice in one campaign by records that disagree (beyond where and how
    #: fast they ran), as "<campaign>: trial K"; the last of each counts.
    conflicts: list[str] = field(default_factory=list)


def results_path(out: Path) -> Path:
    """``out/results.jsonl``, or ``out`` itself when it is a results file.

    Raises
    ------
    ResultsFileError
        If neither exists.
    """
    if out.is_dir():
        path = out / "results.jsonl"
        if not path.exists():
            raise ResultsFileError(f"{out}: expected a campaign folder with results.jsonl in it")
        return path
    if not out.exists():
        raise ResultsFileError(f"{out}: no such campaign folder or results file")
    return out


def read_campaigns(out: Path) -> CampaignFile:
    """Every campaign in ``out``'s results, in the order they first appear.

    Raises
    ------
    ResultsFileError
        If there is no results file, it cannot be read, or it holds no trial record.
    """
    path = results_path(out)
    read = read_results(path)
    if not read.records:
        raise ResultsFileError(
            f"{path}: expected trial records (JSON lines with trial, seed, success), found none"
            + (f"; {read.skipped_text()}" if read.skipped else "")
        )
    groups: dict[tuple[str, ...], dict[int, dict[str, Any]]] = {}
    disagreeing: dict[tuple[str, ...], list[int]] = {}
    for rec in read.records:
        group = group_of(rec)
        by_trial = groups.setdefault(group, {})
        before = by_trial.get(rec["trial"])
        if before is not None and _outcome(before) != _outcome(rec):
            disagreeing.setdefault(group, []).append(int(rec["trial"]))
        by_trial[rec["trial"]] = rec
    firsts = [next(iter(by_trial.values())) for by_trial in groups.values()]
    labels = [_label(first) for first in firsts]
    campaigns = []
    for first, label, by_trial in zip(firsts, labels, groups.values(), strict=True):
        if labels.count(label) > 1:  # a world copied under its name, edited: say which
            label += _told_apart(first)
        key = {f: first[f] for f in KEY_FIELDS if f in first} or None
        campaigns.append(Campaign(label, [by_trial[t] for t in sorted(by_trial)], key))
    conflicts = [
        f"{label}: trial {t}"
        for (group, trials), label in zip(groups.items(), labels, strict=True)
        for t in sorted(set(disagreeing.get(group, ())))
    ]
    return CampaignFile(
        path, campaigns, read.skipped, read.skipped_text() if read.skipped else "", conflicts
    )


def _outcome(record: dict[str, Any]) -> dict[str, Any]:
    """A record but for where and how fast it ran (:data:`experiment.records.RUN_FIELDS`)."""
    return {k: v for k, v in record.items() if k not in RUN_FIELDS}


def _label(first: dict[str, Any]) -> str:
    world = first.get("world") or "(world not recorded)"
    tree = first.get("tree") or "default tree"
    label = f"{world}, {tree}, seed {first.get('seed')}"
    return label + (", Hard" if first.get("mode") == "hard" else "")


def _told_apart(first: dict[str, Any]) -> str:
    """What tells a campaign from another of the same label: its world's and tree's hashes
    (their first 8 hex digits) and its settings."""
    parts = [f"world {str(first.get('world_sha256', ''))[:8] or '?'}"]
    if first.get("tree_sha256"):
        parts.append(f"tree {str(first['tree_sha256'])[:8]}")
    settings = first.get("settings")
    if settings:
        parts.append(json.dumps(settings, sort_keys=True, separators=(",", ":"))[:60])
    return f" ({', '.join(parts)})"


def report_figure(campaign: Campaign, path: Path) -> None:
    """Write the picture of one campaign to ``path`` (PNG), titled with its label (two
    campaigns of one folder, two worlds say, are two pictures: one would mix their boxes)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    from matplotlib.ticker import MaxNLocator

    records = campaign.records
    fig, (where, why, near) = plt.subplots(1, 3, figsize=(15, 4.8))
    fig.suptitle(f"{campaign.label}: {len(records)} trial{'s' * (len(records) != 1)}", fontsize=10)
    placed = [r for r in records if isinstance(r.get("start"), list)]
    # Colour says the outcome, the marker what was drawn: a start (circle), a goal (triangle).
    for ok, colour, label in ((True, "0.6", "success"), (False, "red", "failed")):
        rows = [r for r in placed if bool(r.get("success")) == ok]
        if not rows:
            continue
        where.scatter(
            [r["start"][1] for r in rows],
            [r["start"][0] for r in rows],
            c=colour,
            marker="o",
            s=18,
            label=f"start, {label}",
        )
        if ok:
            goals = [g for r in rows for g in r.get("goals") or () if len(g) >= 2]
            others: list[list[float]] = []
        else:  # the goal each failed at, filled; its other goals (reached, or never tried) open
            split = [_failed_goal(r) for r in rows]
            goals = [g for at, _ in split for g in at]
            others = [g for _, rest in split for g in rest]
        where.scatter(
            [g[1] for g in goals],
            [g[0] for g in goals],
            c=colour,
            marker="^",
            s=20,
            alpha=0.5 if ok else 1.0,
            label=f"goals, {label}" if ok else "goal failed at",
            edgecolors="none",
        )
        if others:
            where.scatter(
                [g[1] for g in others],
                [g[0] for g in others],
                marker="^",
                s=20,
                facecolors="none",
                edgecolors=colour,
                linewidths=0.8,
                label="other goals of failed trials",
            )
    if placed:
        where.invert_xaxis()  # +y to the robot's left, drawn on the left
        where.set_aspect("equal", adjustable="datalim")
        where.legend(fontsize=7, loc="best")
    else:
        where.text(
            0.5, 0.5, "no positions in these records", ha="center", transform=where.transAxes
        )
    where.set(title="where trials failed (top view)", xlabel="y (m)", ylabel="x (m)")
    reasons = Counter(reason_of(r.get("failure", "") or "") for r in records)
    reasons.pop("success", None)
    if reasons:
        names = sorted(reasons, key=lambda k: (reasons[k], k))
        why.barh([n[:40] for n in names], [reasons[n] for n in names], color="tab:red")
        why.tick_params(axis="y", labelsize=7)
        why.xaxis.set_major_locator(MaxNLocator(integer=True))  # trials are counted whole
    else:
        why.text(0.5, 0.5, "no failures", ha="center", transform=why.transAxes)
        why.set_xticks([])
        why.set_yticks([])
    why.set(title="failure reasons", xlabel="trials")
    dist = [
        (1000.0 * float(r["min_obstacle_distance_m"]), bool(r.get("success")))
        for r in records
        if isinstance(r.get("min_obstacle_distance_m"), int | float)
        and math.isfinite(r["min_obstacle_distance_m"])
    ]
    if dist:
        # One set of bins for both, stacked: binned alone, a few failures a fraction of a
        # millimetre apart drew bars too thin to see.
        edges = np.histogram_bin_edges([d for d, _ in dist], bins=30)
        series = [([d for d, s in dist if s == ok], c, label) for ok, c, label in _OUTCOMES]
        shown = [(v, c, label) for v, c, label in series if v]
        near.hist(
            [v for v, _, _ in shown],
            bins=edges,
            stacked=True,
            color=[c for _, c, _ in shown],
            label=[label for _, _, label in shown],
        )
        near.axvline(0.0, color="k", lw=0.8)
        near.yaxis.set_major_locator(MaxNLocator(integer=True))  # trials are counted whole
        near.legend(fontsize=7)
    else:
        near.text(0.5, 0.5, "no distances recorded", ha="center", transform=near.transAxes)
    near.set(title="closest approach per trial", xlabel="mm (below 0: overlap)", ylabel="trials")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def _failed_goal(record: dict[str, Any]) -> tuple[list[list[float]], list[list[float]]]:
    """A failed trial's goals: ([the one it failed at], the others). That is the first goal
    not placed (``placement_error_m`` null), or its last when every one was placed (an
    object knocked away after); every goal when the record does not say."""
    goals = [g for g in record.get("goals") or () if len(g) >= 2]
    placed = record.get("placement_error_m")
    if not isinstance(placed, list) or len(placed) != len(goals) or not goals:
        return goals, []
    at = next((k for k, e in enumerate(placed) if e is None), len(goals) - 1)
    return [goals[at]], goals[:at] + goals[at + 1 :]


def report_summaries(campaigns: list[Campaign]) -> list[dict[str, Any]]:
    """:func:`experiment.summary.summarise` of each campaign, with its label, its key
    (``"key"``: world and tree with their hashes, seed, settings; None for old records) and
    the code its records were made by (``"code"``: :func:`code_versions`)."""
    return [
        {
            "campaign": c.label,
            "key": c.key,
            "code": code_versions(c.records),
            **summarise(c.records),
        }
        for c in campaigns
    ]


def code_versions(records: list[dict[str, Any]]) -> dict[str, int]:
    """How many records each version of the code made: by ``code_sha256`` (records made
    before records named their code: ``"unrecorded"``), most first."""
    counts = Counter(str(r.get("code_sha256") or "unrecorded") for r in records)
    return dict(counts.most_common())


def code_line(summary: dict[str, Any]) -> str | None:
    """The report's line for a campaign whose records more than one version of the code
    made (a campaign resumed after an update), else None."""
    code = summary.get("code") or {}
    if len(code) < 2:
        return None
    parts = ", ".join(f"{h[:8] if h != 'unrecorded' else h}: {n}" for h, n in code.items())
    return (
        f"  made by {len(code)} versions of the code (code_sha256 {parts}): its outcome mixes them"
    )

"""The command line's experiment commands: ``run`` (one episode), ``trials`` (a campaign) and
``report`` (a campaign's table and picture). ``app.py`` parses the options; each command takes
its ``argparse.Namespace`` and returns the exit code (0 success, 1 task failure, 2 bad input).

The heavy imports (PyBullet, the tree) are made inside each command, so that ``app.py`` starts
fast whatever it runs.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

from duet_robot.text import printable, with_notes
from experiment.cli_inputs import (
    EXIT_BAD_INPUT,
    EXIT_FAILURE,
    EXIT_OK,
    load_world_or_exit,
    out_folder_or_exit,
    preflight_or_exit,
    register_leaves_or_none,
)


def run_command(args: argparse.Namespace) -> int:
    """Run a world's task in PyBullet, show progress, judge it and write what it shows."""

    world = load_world_or_exit(args.world)
    if register_leaves_or_none(args) is None:
        return EXIT_BAD_INPUT
    if args.groot is not None:
        from planner.groot_publisher import groot_problem

        problem = groot_problem(args.groot)
        if problem:
            print(problem, file=sys.stderr)
            return EXIT_BAD_INPUT
    preflight_or_exit(world, args.world, args.tree, args.main_tree)
    if args.seed is not None:
        world = world.model_copy(update={"sim": world.sim.model_copy(update={"seed": args.seed})})
    out = out_folder_or_exit(Path(args.out))

    report = _episode_or_none(
        world,
        Path(args.tree) if args.tree else None,
        out=out,
        animation=not args.no_animation,
        progress=_progress,
        gui=args.gui,
        main_tree=args.main_tree,
        groot_port=args.groot,
    )
    if report is None:
        return EXIT_BAD_INPUT
    return _verdict(report, world.name, out, args.json)


def _episode_or_none(world: Any, tree: Path | None, out: Path, **options: Any) -> Any:
    """:func:`experiment.episode.run_episode` into ``out``; None, once the bad input that
    stopped it is printed (a tree, a library, no display, a Groot2 port, an output the run
    cannot write: a folder named like it)."""
    from experiment.episode import run_episode
    from planner.groot_publisher import GrootUnavailableError
    from planner.loader import TreeFileError
    from skills.library import LibraryFileError
    from worlds.scene import NoDisplayError

    try:
        return run_episode(world, tree, out=out, **options)
    except (TreeFileError, LibraryFileError, NoDisplayError, GrootUnavailableError) as err:
        print(with_notes(err), file=sys.stderr)
    except OSError as err:
        print(f"--out {out}: {with_notes(err)}", file=sys.stderr)
    return None


def _progress(t: float, leaf: str, feedback: str) -> None:
    """A run's progress line on stderr: the simulated time, the leaf and its feedback."""
    name = printable(leaf.split(".")[-1])
    print(f"[{t:7.2f} s] {name:<18} {printable(feedback)}", file=sys.stderr, flush=True)


def _verdict(
    report: Any, name: str, out: Path, as_json: bool, record: dict[str, Any] | None = None
) -> int:
    """Print a run's summary (and JSON, with ``record``'s fields: a trial's as its campaign
    records them), what it replaced or could not write; its exit code."""
    for line in report.lines(name):
        print(line)
    if report.killed_run_outputs is not None:
        print(
            f"a run killed in {out} before this one left outputs: kept in "
            f"{report.killed_run_outputs}"
        )
    if report.replaced_outputs:
        print(f"replaced the earlier run's {', '.join(report.replaced_outputs)} in {out}")
    for problem in report.output_errors:
        print(f"not written: {problem}", file=sys.stderr)
    if as_json:
        print(strict_json({**report.summary(), **(record or {})}))
    if report.output_errors:
        # The verdict is out; an output the run could not write (a full disk, a read-only
        # file) is still an input/output error the caller must see.
        return EXIT_BAD_INPUT
    return EXIT_OK if report.success else EXIT_FAILURE


def _one_trial(args: argparse.Namespace, world: Any, tree: Path | None, out: Path) -> int:
    """``trials --trial K``: trial K of the campaign alone, drawn and run as the campaign runs
    it, with what ``run`` writes (figure, run log, Groot2 replay) and the drawn world as
    ``trial_K.yaml`` in ``out``; no ``results.jsonl``."""
    from experiment.trials import TrialNotDrawn, campaign_of, layout_of, tree_misfit, trial_world
    from planner.atomic_file import atomic_open
    from worlds.world_file import dump_world

    try:
        drawn, kinds, hard = trial_world(world, args.seed, args.trial, args.hard)
    except TrialNotDrawn as err:
        print(f"trial {args.trial}: {err}", file=sys.stderr)
        return EXIT_FAILURE
    path = out / f"trial_{args.trial}.yaml"
    mode = " --hard" if args.hard else ""
    header = [
        f"# Trial {args.trial} of seed {args.seed} of {args.world}: app.py trials "
        f"{args.world} --seed {args.seed}{mode} --trial {args.trial}",
        "# Its paths are absolute; app.py run reads it from anywhere.",
    ]
    if hard is not None:
        header.append(
            "# Hard mode: the physics this trial ran (masses, frictions, table, actuators) "
            "differs from this file; --trial runs it, app.py run on this file does not."
        )
    try:
        with atomic_open(path) as handle:
            handle.write("\n".join(header) + "\n" + dump_world(_absolute_paths(drawn)))
    except OSError as err:
        print(f"--out {out}: {path}: cannot write it: {err.strerror or err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    print(f"drawn world: {path}")
    misfit = tree_misfit(drawn, tree, args.main_tree)
    if misfit:
        print(f"trial {args.trial}: {misfit}", file=sys.stderr)
        return EXIT_FAILURE
    report = _episode_or_none(
        drawn,
        tree,
        out,
        animation=False,
        progress=_progress,
        main_tree=args.main_tree,
        truth=None if hard is None else hard.truth,
    )
    if report is None:
        return EXIT_BAD_INPUT
    # The campaign's record of trial K, so that the two compare field by field (wall-clock
    # fields and where it ran aside).
    record: dict[str, Any] = {
        "trial": args.trial,
        **campaign_of(world, args.seed, tree, args.leaves, args.main_tree, args.hard),
        "obstacles": kinds,
        **layout_of(drawn),
    }
    if hard is not None:
        record.update({"mode": "hard", "hard": hard.summary()})
    return _verdict(report, drawn.name, out, args.json, record)


def _absolute_paths(world: Any) -> Any:
    """``world`` with the files it names (its tree, skill library and mesh shapes) given by
    absolute path, so that a copy of it written elsewhere still finds them."""
    from worlds.world_file import world_from_data
    from worlds.world_schema import DEFAULT_SKILL_LIBRARY

    data = world.model_dump(mode="json")
    if data.get("tree"):
        data["tree"] = str(world.resolve_path(data["tree"]))
    if data["skills"]["library"] != DEFAULT_SKILL_LIBRARY:
        data["skills"]["library"] = str(world.resolve_path(data["skills"]["library"]))
    for obj in data["objects"]:
        if obj["shape"]["type"] == "mesh":
            obj["shape"]["file"] = str(world.resolve_path(obj["shape"]["file"]))
    return world_from_data(data, world.source)


def trials_command(args: argparse.Namespace) -> int:
    """The paper's experiment: N trials of three moves with new obstacles, judged, resumable."""
    from experiment.progress import Progress
    from experiment.results import ResultsFileError
    from experiment.summary import campaign_lines, undrawn_kinds
    from experiment.trials import campaign_of, campaign_results, reason_of, run_campaign, summarise

    world = load_world_or_exit(args.world)
    for option, value, most in (("--n", args.n, 1_000_000), ("--workers", args.workers, 1024)):
        if not 1 <= value <= most:
            print(f"{option}: expected a whole number 1..{most}, got {value}", file=sys.stderr)
            return EXIT_BAD_INPUT
    if args.trial is not None and not 0 <= args.trial < 1_000_000:
        print(f"--trial: expected a trial number 0..999999, got {args.trial}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.address and args.backend != "ray":
        print("--address: expected only with --backend ray", file=sys.stderr)
        return EXIT_BAD_INPUT
    if register_leaves_or_none(args) is None:
        return EXIT_BAD_INPUT
    # one message now, not one per trial
    preflight_or_exit(world, args.world, args.tree, args.main_tree)
    from experiment.layout import TrialLayoutError, check_trial_layout

    try:
        check_trial_layout(world, args.seed, args.world)
    except TrialLayoutError as err:
        print(err, file=sys.stderr)
        return EXIT_BAD_INPUT
    tree = Path(args.tree) if args.tree else None
    if tree is not None:
        from planner.loader import TreeFileError, load_tree
        from planner.tree_dataflow import RUN_WRITES

        try:
            load_tree(tree, main_tree_id=args.main_tree, run_keys=RUN_WRITES)
        except TreeFileError as err:
            print(err, file=sys.stderr)
            return EXIT_BAD_INPUT
    out = out_folder_or_exit(Path(args.out))
    if args.trial is not None:
        return _one_trial(args, world, tree, out)
    try:
        key = campaign_of(world, args.seed, tree, args.leaves, args.main_tree, args.hard)
        earlier = campaign_results(out / "results.jsonl", key).values()
    except ResultsFileError as err:
        print(err, file=sys.stderr)
        return EXIT_BAD_INPUT
    # Only this campaign's trials 0..n-1 count: a longer one's records stay in the file.
    within = [r for r in earlier if int(r.get("trial", -1)) < args.n]
    tally = {"ok": sum(1 for r in within if r.get("success"))}
    done = len(within)
    if done:
        left = args.n - done
        print(
            f"resuming: {done} of {args.n} trials already in {out / 'results.jsonl'}, "
            + (f"{left} to run" if left else "none left to run"),
            file=sys.stderr,
        )

    bar = Progress(sys.stderr)

    def progress(rec: dict[str, Any], finished: int, total: int) -> None:
        tally["ok"] += int(bool(rec.get("success")))
        what = "ok" if rec.get("success") else reason_of(rec.get("failure", ""))
        bar.update(
            finished,
            total,
            f"successes {tally['ok']}  (trial {rec['trial']}: {printable(what)})",
        )

    def notice(text: str) -> None:
        print(text, file=sys.stderr)

    try:
        records = run_campaign(
            world,
            args.n,
            args.seed,
            out,
            args.workers,
            progress,
            tree,
            on_notice=notice,
            leaves=args.leaves,
            backend=args.backend,
            address=args.address,
            main_tree=args.main_tree,
            hard=args.hard,
        )
    except ImportError as err:  # --backend ray without Ray installed
        bar.close()
        print(f"--backend ray: {err}; install it with pip install -e '.[cluster]'", file=sys.stderr)
        return EXIT_BAD_INPUT
    except RuntimeError as err:  # Ray gave up on a trial
        bar.close()
        print(printable(err), file=sys.stderr)
        return EXIT_BAD_INPUT
    except ResultsFileError as err:  # a folder that is not one, or another campaign in it
        bar.close()
        print(err, file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        bar.close()
        print(
            f"interrupted: finished trials are in {out / 'results.jsonl'}; "
            "run the same command again to resume",
            file=sys.stderr,
        )
        return 130
    bar.close()
    summary = summarise(records)
    # Only the paper's experiment (its three goal regions, Easy) compares with its 16 of 20:
    # Hard trials and a world's own moves (the task suite) are other experiments.
    mode = "Hard trials" if args.hard else "trials"
    paper = " (the paper: 16 of 20)" if not (args.hard or world.trials.moves) else ""
    print(
        f"{summary['successes']} of {summary['trials']} {mode} succeeded{paper}; "
        f"results in {out / 'results.jsonl'}"
    )
    for line in campaign_lines(summary):
        print(line)
    listed = [region.obstacles for region in world.trials.goal_regions()]
    for line in undrawn_kinds(listed, records):
        print(line, file=sys.stderr)
    if args.json:
        print(strict_json(summary))
    return EXIT_OK if summary["successes"] == summary["trials"] else EXIT_FAILURE


def report_command(args: argparse.Namespace) -> int:
    """A campaign's outcome table with Wilson 95 % intervals, and its picture."""
    from experiment.report import code_line, read_campaigns, report_figure, report_summaries
    from experiment.results import ResultsFileError
    from experiment.summary import campaign_lines

    out = Path(args.out)
    try:
        found = read_campaigns(out)
    except ResultsFileError as err:
        print(err, file=sys.stderr)
        return EXIT_BAD_INPUT
    if found.skipped:
        print(f"warning: {found.path}: {found.skipped_text}", file=sys.stderr)
    for conflict in found.conflicts:
        print(
            f"warning: {found.path}: {printable(conflict)} is recorded more than once, and the "
            "records disagree (merged from two runs?): the last one counts",
            file=sys.stderr,
        )
    summaries = report_summaries(found.campaigns)
    stem = out / "report" if out.is_dir() else out.with_name(f"{out.stem}_report")
    several = len(found.campaigns) > 1
    # The pictures of this report alone: an earlier report's, of other campaigns, would stay
    # beside them and be taken for this one's.
    for old in stem.parent.glob(f"{stem.name}*.png"):
        ours = old.name == f"{stem.name}.png" or old.stem[len(stem.name) + 1 :].isdigit()
        if ours and (old.is_symlink() or old.is_file()):  # a folder: "not written" below
            old.unlink(missing_ok=True)
    unwritten = False
    for k, (campaign, summary) in enumerate(zip(found.campaigns, summaries, strict=True), 1):
        count = summary["trials"]
        print(f"{printable(summary['campaign'])}: {count} trial{'s' * (count != 1)}")
        for line in campaign_lines(summary):  # as `app.py trials` prints it
            print(line)
        mixed = code_line(summary)
        if mixed is not None:
            print(mixed)
        # One picture per campaign: report.png, or report_1.png, report_2.png ... in order.
        figure = stem.with_name(f"{stem.name}_{k}.png" if several else f"{stem.name}.png")
        try:
            report_figure(campaign, figure)
        except OSError as err:
            print(f"not written: {figure}: {err.strerror or err}", file=sys.stderr)
            unwritten = True
        else:  # stdout's own errors (a reader gone: `| head`) are not the picture's
            print(f"  picture: {figure}")
    if args.json:
        print(
            strict_json(
                {"results": str(found.path), "skipped_lines": found.skipped, "campaigns": summaries}
            )
        )
    return EXIT_BAD_INPUT if unwritten else EXIT_OK


def strict_json(value: Any) -> str:
    """``value`` as JSON that strict parsers read: a NaN or infinity (a speed of no wall
    time, say) is null."""

    def clean(x: Any) -> Any:
        if isinstance(x, float) and not math.isfinite(x):
            return None
        if isinstance(x, dict):
            return {k: clean(v) for k, v in x.items()}
        if isinstance(x, list | tuple):
            return [clean(v) for v in x]
        return x

    return json.dumps(clean(value), allow_nan=False)


__all__ = ["report_command", "run_command", "trials_command"]

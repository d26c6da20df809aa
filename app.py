"""Duet command line: learn, compose and run dual-arm skills.

Run ``python app.py --help`` for the commands. Exit codes: 0 success, 1 task failure,
2 bad input (a message names the file, the field and what was expected; no traceback).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

# isort: off
from duet_robot.blas import pin_blas_kernel

pin_blas_kernel()  # before numpy loads OpenBLAS: one BLAS kernel on every x86-64 host
import numpy as np  # noqa: E402

# isort: on

from experiment.campaign_commands import report_command, run_command, trials_command  # noqa: E402
from experiment.cli_inputs import (  # noqa: E402
    EXIT_BAD_INPUT,
    EXIT_FAILURE,
    EXIT_OK,
    load_world_or_exit,
    out_folder_or_exit,
    register_leaves_or_none,
)


def _demo_command(args: argparse.Namespace) -> int:
    """Learn a pose DMP from a synthetic pick-and-place demo and generalise it; plot both."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from skills import quaternion as quat
    from skills.demonstration import Demonstration
    from skills.pose_dmp import PoseState, fit_pose, pose_rollout
    from skills.scaling import Scaling

    t = np.linspace(0.0, 2.0, 1000)
    u = t / 2.0
    s = 10 * u**3 - 15 * u**4 + 6 * u**5
    start = np.array([0.55, 0.15, 0.675])
    positions = start + np.stack(
        (0.05 * np.sin(np.pi * s), -0.3 * s, 0.12 * np.sin(np.pi * u) ** 2), axis=1
    )
    orientations = quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), 0.5 * s)
    demo = Demonstration.create(t, positions, orientations, name="synthetic pick-and-place")
    model = fit_pose(demo, position_scaling=Scaling.ROTATION_Z)
    dt = 0.005
    goals = [
        (np.array([0.65, 0.15, 0.675]), np.array([0.45, -0.1, 0.675])),
        (np.array([0.5, -0.15, 0.675]), np.array([0.7, 0.15, 0.675])),
        (np.array([0.6, 0.0, 0.675]), np.array([0.6, -0.2, 0.675])),
    ]
    rollouts = []
    for y0, g in goals:
        target = model.target(y0, quat.IDENTITY, g, quat.from_axis_angle([0, 0, 1], 0.3))
        rollouts.append(pose_rollout(model, target, PoseState.at_rest(y0), dt, int(3 * 2.0 / dt)))
    out = out_folder_or_exit(Path(args.out))
    fig, (top, side) = plt.subplots(1, 2, figsize=(11, 4.5))
    top.plot(positions[:, 1], positions[:, 0], color="green", lw=2.5, label="demonstration")
    side.plot(positions[:, 1], positions[:, 2], color="green", lw=2.5)
    for i, tr in enumerate(rollouts):
        label = "DMP, new start and goal" if i == 0 else None
        top.plot(tr.positions[:, 1], tr.positions[:, 0], color="tab:blue", label=label)
        side.plot(tr.positions[:, 1], tr.positions[:, 2], color="tab:blue")
        top.plot(*goals[i][1][[1, 0]], "k+", ms=10)
    top.set(xlabel="y (m)", ylabel="x (m)", title="top view", aspect="equal")
    top.invert_xaxis()
    side.set(xlabel="y (m)", ylabel="z (m)", title="side view", aspect="equal")
    side.invert_xaxis()
    top.legend(loc="best")
    fig.suptitle("Pose DMP learnt from one demonstration, generalised to new starts and goals")
    fig.tight_layout()
    path = out / "dmp_demo.png"
    from planner.atomic_file import atomic_path

    try:
        with atomic_path(path) as temporary:
            fig.savefig(temporary, dpi=120)
    except OSError as err:
        print(f"{path}: cannot write it: {err.strerror or err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    finally:
        plt.close(fig)
    errs = [
        float(np.linalg.norm(tr.positions[-1] - g))
        for tr, (_, g) in zip(rollouts, goals, strict=True)
    ]
    summary = {"plot": str(path), "final_position_errors_m": errs}
    print(f"wrote {path}; final position errors (m): {', '.join(f'{e:.2e}' for e in errs)}")
    if args.json:
        print(json.dumps(summary))
    return EXIT_OK


def _validate_command(args: argparse.Namespace) -> int:
    """Check world files (YAML or JSON) and what they ask of the robot, optionally with the
    tree to run them (``--tree``), and behaviour trees (XML), one line each when fine; exit 2
    if any has a problem. ``--nodes`` adds stub nodes from TreeNodesModel files."""
    if register_leaves_or_none(args) is None:
        return EXIT_BAD_INPUT
    trees = [f for f in args.files if f.lower().endswith(".xml")]
    if args.tree and trees:
        print(
            f"--tree: expected a world file to check the tree against, got the tree {trees[0]}",
            file=sys.stderr,
        )
        return EXIT_BAD_INPUT
    registry: dict[str, Any] | None = None
    if args.nodes:
        from py_trees.ports import get_ports_registry

        from planner.model_stubs import model_stub_classes
        from planner.tree_problems import TreeFileError

        registry = dict(get_ports_registry())
        for model in args.nodes:
            try:
                registry.update(model_stub_classes(model))  # the model's nodes win
            except TreeFileError as err:
                print(err, file=sys.stderr)
                return EXIT_BAD_INPUT
    from planner.tree_dataflow import RUN_WRITES
    from planner.validate import tree_cli_validate

    codes = []
    for path in args.files:
        if path.lower().endswith(".xml"):
            codes.append(
                tree_cli_validate(
                    path,
                    registry,
                    main_tree_id=args.main_tree,
                    # a tree for another robot (--nodes) runs under its own host's keys
                    run_keys=None if args.nodes else RUN_WRITES,
                )
            )
        else:
            from experiment.preflight import validate_cli  # the world's checks need PyBullet

            codes.append(validate_cli(path, args.tree, args.main_tree))
    return EXIT_BAD_INPUT if EXIT_BAD_INPUT in codes else max(codes)


def _nodes_command(args: argparse.Namespace) -> int:
    """Print (or write) a Groot2 TreeNodesModel of the registered leaves, the user's too."""
    user = register_leaves_or_none(args)
    if user is None:
        return EXIT_BAD_INPUT
    from planner.nodes_model import nodes_model_xml

    packages = ("planner", *dict.fromkeys(c.__module__ for c in user))
    if args.embed:
        from planner.atomic_file import atomic_open
        from planner.nodes_model import embed_nodes_model
        from planner.tree_problems import TreeFileError

        target = args.out or args.embed  # --out: a copy with the model, the tree left as it is
        try:
            text = embed_nodes_model(args.embed, packages=packages)
        except (TreeFileError, OSError) as err:
            print(f"--embed {args.embed}: {err}", file=sys.stderr)
            return EXIT_BAD_INPUT
        try:
            with atomic_open(target) as handle:  # a failed write leaves the tree whole
                handle.write(text)
        except OSError as err:
            option = "--out" if args.out else "--embed"
            print(f"{option} {target}: cannot write it: {err.strerror or err}", file=sys.stderr)
            return EXIT_BAD_INPUT
        into = "into it" if target == args.embed else f"into {target}"
        print(f"wrote the TreeNodesModel of the leaves {args.embed} uses {into}")
        return EXIT_OK
    text = nodes_model_xml(packages=packages)
    if args.out:
        from planner.atomic_file import atomic_open

        try:
            with atomic_open(args.out) as handle:
                handle.write(text)
        except OSError as err:
            print(f"--out {args.out}: cannot write it: {err.strerror or err}", file=sys.stderr)
            return EXIT_BAD_INPUT
        print(f"wrote {args.out}")
    else:
        print(text)
    return EXIT_OK


def _render_tree_command(args: argparse.Namespace) -> int:
    """Render a tree file as ascii, dot or svg."""
    if register_leaves_or_none(args) is None:
        return EXIT_BAD_INPUT
    for leaves in args.leaves or ():  # a leaves file is the user's code: never overwritten
        if args.out is not None and Path(leaves).is_file() and os.path.samefile(leaves, args.out):
            print(
                f"--out {args.out}: expected a file other than --leaves {leaves}", file=sys.stderr
            )
            return EXIT_BAD_INPUT
    from planner.render import render_cli

    return render_cli(args.tree, args.format, args.out, args.main_tree)


def _schema_command(args: argparse.Namespace) -> int:
    """Print the world-file JSON Schema."""
    from worlds.world_file import world_cli_schema

    return world_cli_schema()


def _affordances_command(args: argparse.Namespace) -> int:
    """Print the affordance reasoning for each object of a world."""
    from affordances import AffordanceReasoner, render_json, render_text
    from affordances.rule_file import RuleFileError, rule_set
    from worlds.adapters import object_contexts, robot_capabilities

    world = load_world_or_exit(args.world)
    try:
        rules = rule_set([Path(p) for p in args.rules], include_default=not args.no_default_rules)
    except (RuleFileError, OSError) as err:
        print(err, file=sys.stderr)
        return EXIT_BAD_INPUT
    reasoner = AffordanceReasoner(robot_capabilities(world), rules=rules)
    ranked = reasoner.rank_all(object_contexts(world))
    if args.json:
        print(render_text(ranked), file=sys.stderr)
        print(render_json(ranked, indent=None))
    else:
        print(render_text(ranked))
    return EXIT_OK


def _load_library(folder: str | None) -> Any:
    """The library in ``folder``, or the default one learnt from the shipped demonstrations."""
    from skills.default_library import default_library
    from skills.library import SkillLibrary

    if folder is None:
        return default_library()
    return SkillLibrary.load(folder)


def _skills_command(args: argparse.Namespace) -> int:
    """List a skill library."""
    from skills.library import LibraryFileError

    try:
        library = _load_library(args.library)
    except LibraryFileError as err:
        print(err, file=sys.stderr)
        return EXIT_BAD_INPUT
    rows = library.describe()
    if args.json:
        print(json.dumps({"skills": rows}))
        return EXIT_OK
    source = args.library or "default (learnt from skills/demos)"
    print(f"skill library: {source}, {len(rows)} skills")
    for r in rows:
        fit = ", ".join(f"{k}={v:.3g}" for k, v in r["fit"].items())
        demos = ", ".join(r["demonstrations"]) or "none"
        print(f"  {r['name']:<16} {r['label']:<16} {r['action']:<16} {r['space']:<9} {r['kind']}")
        print(f"      from {demos}; {r['method']}" + (f"; fit {fit}" if fit else ""))
    return EXIT_OK


def _teach_command(args: argparse.Namespace) -> int:
    """Learn a skill from a demonstration CSV into a library; report recognition first
    (:func:`skills.teaching.teach`)."""
    from skills.demo_conditioning import DEFAULT_SMOOTHING_S
    from skills.recognition import DEFAULT_THRESHOLD
    from skills.teaching import TeachingError, teach

    smoothing_s = DEFAULT_SMOOTHING_S if args.smooth_ms is None else args.smooth_ms / 1000.0
    if not (math.isfinite(smoothing_s) and 0.0 <= smoothing_s <= 1.0):
        print(f"--smooth-ms: expected 0 to 1000 ms, got {args.smooth_ms}", file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        lesson = teach(
            args.demo,
            args.library,
            args.label,
            args.space,  # the parser's choices are the enums' values
            action=args.action,
            name=args.name,
            smoothing_s=smoothing_s,
            threshold=DEFAULT_THRESHOLD if args.threshold is None else args.threshold,
            force=args.force,
            report=print,
            names=_TEACH_OPTIONS,
        )
    except TeachingError as err:
        print(err, file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.json:
        match, shown, added = lesson.recognition, lesson.reproduction, lesson.added
        summary: dict[str, Any] = {
            "closest": match.best,
            "similarity": round(match.similarity, 4),
            "matched": match.matched,
            "threshold": match.threshold,
            "added": None if added is None else added.name,
            "library": str(lesson.library),
        }
        if shown is not None:
            summary["reproduction"] = {
                "rms_m": round(shown.rms_m, 6),
                "settle_m": round(shown.settle_m, 6),
                "settle_deg": round(shown.settle_deg, 4),
                "smoothing_ms": round(1000.0 * lesson.smoothing_s, 3),
            }
        if added is not None:
            summary["label"] = added.label
            summary["action"] = added.action.value
        print(json.dumps(summary))
    return EXIT_OK


#: ``teach``'s options, by the names :func:`skills.teaching.teach` gives its arguments.
_TEACH_OPTIONS = {
    "label": "--label",
    "action": "--action",
    "name": "--name",
    "smoothing_s": "--smooth-ms",
    "threshold": "--threshold",
    "force": "--force",
}


def _actions() -> list[Any]:
    from skills.vocabulary import Action

    return list(Action)


def _add_leaves_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--leaves",
        action="append",
        default=[],
        metavar="FILE.py|MODULE",
        help="register the planner.leaves.WorldLeaf subclasses a Python file or module defines "
        "(repeatable); installed packages' duet.leaves entry points are registered too",
    )


def _add_main_tree_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--main-tree",
        metavar="ID",
        help="the <BehaviorTree ID> to run instead of main_tree_to_execute (a file saved by "
        "Groot2 has none; a file of one tree runs that one)",
    )


def _path_text(text: str) -> str:
    """An argument naming a file or folder: not empty (an empty ``--out`` had meant the current
    folder, and a campaign wrote its results there)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a path, got an empty string")
    return text


def _seed(text: str) -> int:
    """A seed: a whole number from 0 (numpy's generators take no negative seed)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 0, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 0, got {value}")
    return value


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with one sub-command per job."""
    # prog: how the user ran it (app.py, duet-robot, python -m duet_robot).
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    demo = sub.add_parser("demo", help="learn a DMP from a synthetic demo and plot generalisations")
    demo.add_argument("--out", type=_path_text, default="out", help="output folder (default: out)")
    demo.add_argument("--json", action="store_true", help="print a JSON summary as the last line")
    demo.set_defaults(handler=_demo_command)
    validate = sub.add_parser(
        "validate",
        help="check world files (and what they ask of the robot) and trees; exit 2 if any is bad",
    )
    validate.add_argument(
        "files", nargs="+", metavar="FILE", help="world files (.yaml, .yml, .json), trees (.xml)"
    )
    validate.add_argument(
        "--tree", help="with world files: also check this tree XML and its moves against each"
    )
    validate.add_argument(
        "--nodes",
        action="append",
        default=[],
        metavar="MODEL.xml",
        help="register stub nodes from a Groot2 TreeNodesModel (repeatable; its nodes win over "
        "ours of the same ID), to check a tree written for another robot",
    )
    _add_main_tree_option(validate)
    _add_leaves_option(validate)
    validate.set_defaults(handler=_validate_command)
    nodes = sub.add_parser("nodes", help="export a Groot2 TreeNodesModel of our leaves")
    nodes.add_argument("--out", type=_path_text, help="write to this file instead of printing")
    nodes.add_argument(
        "--embed",
        metavar="TREE.xml",
        help="instead, write the model of the leaves this tree file uses into it (replacing "
        "its <TreeNodesModel>), so Groot2 opens it with their ports; with --out, into a copy",
    )
    _add_leaves_option(nodes)
    nodes.set_defaults(handler=_nodes_command)
    render = sub.add_parser("render-tree", help="draw a tree file")
    render.add_argument("tree", help="tree XML")
    render.add_argument("--format", choices=["ascii", "dot", "svg"], default="ascii")
    render.add_argument("--out", type=_path_text, help="write to this file instead of printing")
    _add_main_tree_option(render)
    _add_leaves_option(render)
    render.set_defaults(handler=_render_tree_command)
    schema = sub.add_parser("schema", help="print the world-file JSON Schema (for editors)")
    schema.set_defaults(handler=_schema_command)
    aff = sub.add_parser("affordances", help="rank semantic actions for each object of a world")
    aff.add_argument("world", help="world file")
    aff.add_argument(
        "--rules",
        action="append",
        default=[],
        metavar="FILE",
        help="extra YAML rule file (repeatable); applied after the defaults",
    )
    aff.add_argument("--no-default-rules", action="store_true", help="use only the --rules files")
    aff.add_argument("--json", action="store_true", help="print a JSON summary as the last line")
    aff.set_defaults(handler=_affordances_command)
    run = sub.add_parser("run", help="run a world's task in PyBullet and judge it")
    run.add_argument("world", help="world file")
    run.add_argument(
        "--tree", help="behaviour tree XML (default: planner/trees/pick_and_place.xml)"
    )
    run.add_argument(
        "--seed",
        type=_seed,
        help="override the world's sim.seed; a run makes no random choice today (physics, "
        "skills and tree are deterministic), so the same world gives the same run whatever "
        "the seed; trials draw their worlds from trials --seed",
    )
    run.add_argument("--out", type=_path_text, default="out", help="output folder (default: out)")
    run.add_argument("--gui", action="store_true", help="show PyBullet's window (needs a display)")
    run.add_argument("--no-animation", action="store_true", help="skip the GIF (faster)")
    run.add_argument("--json", action="store_true", help="print a JSON summary as the last line")
    run.add_argument(
        "--groot",
        type=int,
        metavar="PORT",
        help="serve the run's status live to Groot2's monitor on 127.0.0.1:PORT (and PORT+1); "
        "needs the extra duet-robot[groot] (pyzmq)",
    )
    _add_main_tree_option(run)
    _add_leaves_option(run)
    run.set_defaults(handler=run_command)
    trials = sub.add_parser("trials", help="the paper's experiment: many randomised trials")
    trials.add_argument("world", help="world file (robot, table, object, settings)")
    trials.add_argument("--n", type=int, default=20, help="number of trials (default: 20)")
    trials.add_argument("--seed", type=_seed, default=0, help="campaign seed (default: 0)")
    trials.add_argument(
        "--tree",
        help="behaviour tree XML every trial runs (default: planner/trees/pick_and_place.xml)",
    )
    trials.add_argument(
        "--workers",
        type=int,
        default=max(1, (os.cpu_count() or 1)),
        help="worker processes (default: one per core)",
    )
    trials.add_argument(
        "--backend",
        choices=["local", "ray"],
        default="local",
        help="where trials run: a local pool of --workers processes (default), or Ray",
    )
    trials.add_argument(
        "--address",
        help="with --backend ray: the cluster's address (ray start --head prints it); "
        "default: a local Ray of --workers CPUs",
    )
    trials.add_argument(
        "--out", type=_path_text, default="out/trials", help="folder of results.jsonl"
    )
    trials.add_argument(
        "--hard",
        action="store_true",
        help="Hard mode: each trial's physics (masses, frictions, table height, sensed start "
        "pose, pushes, actuators) is drawn to differ from what the robot is told, within the "
        "world's trials.hard ranges; a campaign of its own",
    )
    trials.add_argument("--json", action="store_true", help="print a JSON summary as the last line")
    trials.add_argument(
        "--trial",
        type=int,
        metavar="K",
        help="run trial K of this campaign alone, as the campaign runs it, writing what run "
        "writes (trajectories.png, run.jsonl, run.btlog) and its drawn world, trial_K.yaml, "
        "to --out",
    )
    _add_main_tree_option(trials)
    _add_leaves_option(trials)
    trials.set_defaults(handler=trials_command)
    report = sub.add_parser(
        "report", help="a campaign's outcomes with Wilson 95 %% intervals, and report.png"
    )
    report.add_argument(
        "out", type=_path_text, help="campaign folder (of results.jsonl) or a results .jsonl file"
    )
    report.add_argument("--json", action="store_true", help="print a JSON summary as the last line")
    report.set_defaults(handler=report_command)
    skills = sub.add_parser("skills", help="list a skill library")
    skills.add_argument("--library", help="library folder (default: learnt from skills/demos)")
    skills.add_argument("--json", action="store_true", help="print JSON")
    skills.set_defaults(handler=_skills_command)
    teach = sub.add_parser("teach", help="learn a skill from a demonstration CSV into a library")
    teach.add_argument("demo", help="CSV with columns t,x,y,z,qx,qy,qz,qw")
    teach.add_argument(
        "--label",
        required=True,
        help="the skill's label, any identifier (a world's move names it with `skill: LABEL`)",
    )
    teach.add_argument("--space", required=True, choices=["absolute", "relative"])
    teach.add_argument(
        "--action",
        choices=[a.value for a in _actions()],
        help="the skill's kind: how the planner uses it (default: the label if it is one, "
        "else transport for an absolute skill)",
    )
    teach.add_argument("--library", default="library", help="library folder (default: library)")
    teach.add_argument("--name", help="skill name (default: the file's stem)")
    teach.add_argument(
        "--threshold",
        type=float,
        help="similarity above which the demo is an existing skill "
        "(default: skills.recognition.DEFAULT_THRESHOLD, derived there)",
    )
    teach.add_argument("--force", action="store_true", help="add even if it matches a skill")
    teach.add_argument(
        "--smooth-ms",
        type=float,
        default=None,
        help="smooth the recording over this many ms before learning (a Gaussian's standard "
        "deviation; default 40, 0: as recorded): a recording's noise, differentiated twice, "
        "is what the forcing would learn",
    )
    teach.add_argument("--json", action="store_true", help="print a JSON summary last")
    teach.set_defaults(handler=_teach_command)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Parse ``argv`` and run the command; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    handler: Callable[[argparse.Namespace], int] = args.handler
    from duet_robot.text import with_notes
    from planner.tree_problems import LeafCodeError, PortValueError

    try:
        return handler(args)
    except (LeafCodeError, PortValueError) as err:  # a user's leaf's bug, a tree's bad value
        print(f"error: {with_notes(err)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt as err:
        print("\n".join(["interrupted", *getattr(err, "__notes__", ())]), file=sys.stderr)
        return 130
    except BrokenPipeError:
        # The reader (e.g. `| head`) went away: not an error of ours.
        sys.stdout = open(os.devnull, "w")
        return EXIT_OK
    except OSError as err:
        # Where the output goes cannot take it (`> /dev/full`, a full disk): said, not a
        # traceback. Every command names its own files' errors before this; a write to
        # stdout fails without a file name.
        print(f"{err.filename or 'stdout'}: cannot write: {err.strerror or err}", file=sys.stderr)
        sys.stdout = open(os.devnull, "w")  # the interpreter's last flush would fail again
        return EXIT_BAD_INPUT


__all__ = ["EXIT_BAD_INPUT", "EXIT_FAILURE", "EXIT_OK", "build_parser", "main"]

if __name__ == "__main__":
    raise SystemExit(main())

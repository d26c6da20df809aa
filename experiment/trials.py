"""The paper's experiment: many trials of consecutive pick-and-place moves with new obstacles.

Each trial is drawn as :mod:`experiment.layout` says (the object's start, one goal per move,
new spheres), from ``numpy.random.default_rng([seed, trial])`` within the world file's
``trials`` section, and run as one episode (:func:`experiment.episode.run_episode`).

With ``hard``, each trial also runs against a physical truth drawn for it
(:mod:`experiment.hard`); its record says what was drawn (``hard``) and ``"mode": "hard"``.

Trials are judged as :func:`experiment.judge.judge` says (2 cm and 10 degrees per placement,
never dropped, no robot link or parcel touching an obstacle, arms never touching). Results
are appended to ``results.jsonl`` one line per trial as they finish, so an interrupted
campaign resumes where it stopped; campaigns run on a local pool of processes or on Ray.
"""

from __future__ import annotations

import ctypes
import hashlib
import json
import os
import signal
import socket
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any

from duet_robot.blas import CORETYPE_VARIABLE
from experiment.hard import HardTrial, draw_hard, with_pushes
from experiment.layout import RobotClearance, draw_trial
from experiment.preflight import tree_task_problems
from experiment.records import campaign_key, code_hash, owned_by, tree_hash
from experiment.results import (
    ResultsFileError,
    campaign_lock,
    read_results,
    repair_tail,
)

# Re-exported: the summary lives below the simulation, for reports that need no PyBullet.
from experiment.summary import composition_label as composition_label
from experiment.summary import reason_of as reason_of
from experiment.summary import summarise as summarise
from planner.tree_problems import LeafCodeError, PortValueError
from planner.tree_reading import read_tree_document
from planner.user_leaves import register_leaves
from worlds.bodies import build_robot
from worlds.world_file import (
    DEFAULT_SKILL_LIBRARY,
    World,
    as_world_spec,
    world_from_data,
)


def run_trial(job: tuple[dict[str, Any], int, int]) -> dict[str, Any]:
    """Run one trial in this process; returns its JSON-ready record (never raises)."""
    from experiment.episode import run_episode

    base_data, seed, trial = job
    die = base_data.get("die_once")
    if die and die[0] == trial and not Path(die[1]).exists():
        # Test-only (DUET_TEST_DIE_ONCE): this worker dies on its first attempt of the trial.
        Path(die[1]).write_text(str(os.getpid()), encoding="utf-8")
        os._exit(1)
    source = Path(base_data["source"]) if base_data["source"] else None
    base = world_from_data(base_data["world"], source)
    tree = Path(base_data["tree"]) if base_data["tree"] else None
    hard: HardTrial | None = None
    try:
        # The user's leaves the tree may use, registered in this process too (a spawned
        # worker starts without them; a forked one finds them registered already).
        register_leaves(base_data.get("leaves", ()))
        world, kinds, hard = trial_world(
            base, seed, trial, bool(base_data.get("hard")), _worker_clearance(base)
        )
        where = layout_of(world)
        misfit = tree_misfit(world, tree, base_data.get("main_tree"))
        record: dict[str, Any]
        if misfit:
            record = {"success": False, "sim_time_s": 0.0, "wall_time_s": 0.0}
            failure = misfit
        else:
            report = run_episode(
                world,
                tree,
                out=None,
                animation=False,
                main_tree=base_data.get("main_tree"),
                truth=None if hard is None else hard.truth,
            )
            record = report.summary()
            record.pop("outputs", None)
            failure = record["failure"] or ""
    except (LeafCodeError, PortValueError) as err:
        # A bug in a user's leaf, a value a tree gives that its port cannot take: every trial
        # would meet it. The campaign stops on it, as a run does (exit 2), nothing recorded.
        return {"trial": trial, STOP_KEY: f"{type(err).__name__}: {err}"}
    except Exception as err:  # a trial that crashes is a failed trial with its reason
        record = {"success": False, "sim_time_s": 0.0, "wall_time_s": 0.0}
        kinds, where = [], {}
        failure = (
            str(err) if isinstance(err, TrialNotDrawn) else f"error: {type(err).__name__}: {err}"
        )
    record.update(
        {
            "trial": trial,
            **base_data.get("key", {"seed": seed}),
            "obstacles": kinds,
            **where,
            "failure": failure,
            "backend": base_data.get("backend", "local"),
            "host": socket.gethostname(),
            "code_sha256": code_hash(),
        }
    )
    if hard is not None:
        record.update({"mode": "hard", "hard": hard.summary()})
    return record


#: The key of what :func:`run_trial` returns instead of a record when a user's code or tree
#: stopped the trial (:class:`CampaignStopped`).
STOP_KEY = "stopped_by"


class CampaignStopped(RuntimeError):
    """A trial stopped by a bug in a user's leaf or a tree's bad value: no trial can go past
    it, so the campaign stops there (exit 2), the trials recorded before it kept."""


class TrialNotDrawn(RuntimeError):
    """A trial whose layout could not be drawn: its message is the record's failure."""


def trial_world(
    base: World, seed: int, trial: int, hard: bool, robot: RobotClearance | None = None
) -> tuple[World, list[str], HardTrial | None]:
    """Trial ``trial`` of campaign ``seed`` on ``base`` as a campaign runs it: the drawn world
    (:func:`experiment.layout.draw_trial`, with Hard mode's pushes when ``hard``), the kind of
    obstacle per move, and Hard mode's draws (None when not ``hard``). A layout that cannot
    be drawn raises :class:`TrialNotDrawn`, saying what to change."""
    try:
        world, kinds = draw_trial(base, seed, trial, robot)
    except RuntimeError as err:
        # Not the robot's failure: the world's trials section left no room for this draw.
        raise TrialNotDrawn(
            f"layout not drawn: {err} (widen the trials regions, draw smaller or farther "
            "spheres: trials.sphere_radius, line_gap, ahead_gap, or lower trials.clearance or "
            "trials.robot_clearance)"
        ) from None
    drawn: HardTrial | None = None
    if hard:
        drawn = draw_hard(world, seed, trial)
        world = with_pushes(world, drawn.pushes)
    return world, kinds, drawn


def tree_misfit(world: World, tree: Path | None, main_tree: str | None) -> str:
    """Why a tree given with ``--tree`` cannot make this trial's task ("" when it can).

    Such a tree runs as written, with the moves its file names; a trial's turned goals may
    make more moves than the world file's (a turn the grip cannot make in one move is
    several), and a Move it lacks would never be made. The trial fails at once, saying so,
    instead of running the moves it has.
    """
    if tree is None:
        return ""
    problems = tree_task_problems(world, read_tree_document(tree, main_tree_id=main_tree))
    if not problems:
        return ""
    return (
        f"tree does not fit this trial's task: {problems[0]} (a tree given with --tree runs "
        "as written; a copy of the shipped tree in the world's tree field is made into each "
        "trial's task)"
    )


#: This process's RobotClearance and the base world it was built for (see _worker_clearance).
_CLEARANCE: dict[str, Any] = {}


def _worker_clearance(base: World) -> RobotClearance:
    """One :class:`RobotClearance` per process for its campaign's base world: a worker builds
    the robot's scene once, not once per trial (each draw restarts it, and so draws what a
    scene of its own would). A forked process builds its own."""
    key = (os.getpid(), base.model_dump_json())
    if _CLEARANCE.get("key") != key:
        _close_worker_clearance()
        _CLEARANCE.update(key=key, robot=RobotClearance(base))
    robot: RobotClearance = _CLEARANCE["robot"]
    return robot


def _close_worker_clearance() -> None:
    """Close this process's :func:`_worker_clearance` robot, if it built one."""
    if _CLEARANCE and _CLEARANCE["key"][0] == os.getpid():
        _CLEARANCE["robot"].close()
    _CLEARANCE.clear()


def layout_of(world: World) -> dict[str, Any]:
    """Where a trial's object started and its moves' goals were (m), for reports."""
    start = world.objects[0].pose.position
    goals = [list(m.goal.position) for step in world.task for m in step.moves]
    return {"start": list(start), "goals": goals}


def campaign_of(
    base: World,
    seed: int,
    tree: Path | None,
    leaves: Sequence[str] = (),
    main_tree: str | None = None,
    hard: bool = False,
) -> dict[str, Any]:
    """The key of the campaign of ``base``, ``seed``, ``tree``, the tree's own ``leaves``, the
    ``main_tree`` run of it and whether it is ``hard`` (:func:`experiment.records.campaign_key`).

    A Hard campaign's settings hold its ranges (``trials.hard``, every value) and the robot's
    torque loop, which acts only on faulty actuators; the world's content hash leaves the
    ranges out, so an Easy campaign's key does not depend on them.
    """
    settings: dict[str, Any] = {"leaves": [_leaf_source(s) for s in leaves]} if leaves else {}
    files = _files_read(base, leaves)
    if files:  # what the world's file names do not say: the content of what they name
        settings["files_sha256"] = files
    if main_tree:
        settings["main_tree"] = main_tree
    if hard:
        settings["hard"] = base.trials.hard.model_dump(mode="json")
        loop = build_robot(as_world_spec(base).scene.robot).torque_loop
        settings["torque_loop"] = None if loop is None else loop.summary()
    template = base.tree_path() if tree is None else None
    if template is not None:  # the world's own tree: its content, not only its path
        settings["world_tree_sha256"] = tree_hash(template)
    data = base.model_dump(mode="json")
    data["trials"].pop("hard", None)
    return campaign_key(base.name, data, tree, seed, settings)


def _files_read(base: World, leaves: Sequence[str]) -> dict[str, str]:
    """SHA-256 of each file a trial reads besides the world and the tree, by the name the
    world file (or ``--leaves``) gives it: the meshes of its shapes, its own skill library's
    files, the leaves' Python files. A mesh or a leaf edited under the same name is then
    another campaign, not the old one's records reused. Empty for a world of none."""
    found: dict[str, str] = {}

    def meshes(value: Any) -> None:
        if isinstance(value, dict):
            if value.get("type") == "mesh" and isinstance(value.get("file"), str):
                found[value["file"]] = _file_hash(base.resolve_path(value["file"]))
            for v in value.values():
                meshes(v)
        elif isinstance(value, list):
            for v in value:
                meshes(v)

    meshes(base.model_dump(mode="json"))
    library = base.skills.library
    if library != DEFAULT_SKILL_LIBRARY:
        folder = base.resolve_path(library)
        for path in sorted(p for p in folder.rglob("*") if p.is_file()):
            found[f"{library}/{path.relative_to(folder).as_posix()}"] = _file_hash(path)
    for source in leaves:
        module = Path(source) if source.endswith(".py") else _module_file(source)
        if module is not None:
            found[source] = _file_hash(module)
    return found


def _file_hash(path: Path) -> str:
    try:
        return hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        return ""  # the run refuses it, naming it; the key need not


def _module_file(name: str) -> Path | None:
    """The file an importable module's leaves are read from, if it has one."""
    import importlib.util

    try:
        spec = importlib.util.find_spec(name)
    except (ImportError, ValueError):
        return None
    origin = spec.origin if spec is not None else None
    return Path(origin) if origin and origin.endswith(".py") else None


def _leaf_source(source: str) -> str:
    return str(Path(source).resolve()) if source.endswith(".py") else source


def campaign_results(path: Path, key: dict[str, Any]) -> dict[int, dict[str, Any]]:
    """The records in ``results.jsonl`` of one campaign (``key``: :func:`campaign_of`);
    records of other campaigns are ignored, as are lines that are not records
    (:func:`experiment.results.read_results` counts them).

    Raises
    ------
    ResultsFileError
        If the file is a folder or unreadable.
    """
    return {
        r["trial"]: r  # a trial run twice (an interrupted write) counts once, the last
        for r in read_results(path).records
        if owned_by(r, key)
    }


def older_code(records: Iterable[dict[str, Any]]) -> str:
    """What a resumed campaign's user is told of its records made by other code than this
    (``code_sha256``, :func:`experiment.records.code_hash`): how many, and how to make them
    again; "" when every one was made by this code."""
    here = code_hash()
    other = sorted(
        (r["trial"] for r in records if r.get("code_sha256") != here), key=lambda t: int(t)
    )
    if not other:
        return ""
    shown = ", ".join(str(t) for t in other[:5]) + (", ..." if len(other) > 5 else "")
    return (
        f"{len(other)} of this campaign's records (trials {shown}) were made by other code "
        "than this (their code_sha256 differs, or they have none); they are kept and counted "
        "as they are: move results.jsonl aside to run them again with this code"
    )


#: Where a campaign's trials can run.
BACKENDS = ("local", "ray")
#: Times Ray runs a trial again whose worker died (a killed process, a lost node).
RAY_RETRIES = 3


_NO_CLUSTER = (
    "no Ray cluster answers there; start one with `ray start --head` and give the address "
    "it prints (HOST:PORT), or leave --address out for a local Ray"
)
#: How long to wait for a cluster's address to answer before ``ray.init``, s (Ray itself
#: retries an address where nothing listens for minutes).
CONNECT_TIMEOUT_S = 5.0


def _reachable(address: str) -> None:
    """Refuse an address (``HOST:PORT`` or ``ray://HOST:PORT``) where nothing listens.

    Raises
    ------
    RuntimeError
        Naming the address, if a TCP connection to it fails within :data:`CONNECT_TIMEOUT_S`.
    """
    where = address.split("://", 1)[-1]
    host, _, port = where.rpartition(":")
    if not host or not port.isdigit():
        if address in ("auto", "local"):
            return  # Ray finds (or refuses) its own
        raise RuntimeError(f"--address {address}: expected HOST:PORT or ray://HOST:PORT")
    try:
        socket.create_connection((host.strip("[]"), int(port)), CONNECT_TIMEOUT_S).close()
    except OSError as err:
        raise RuntimeError(f"--address {address}: {_NO_CLUSTER} ({err.strerror or err})") from None


def _run_on_ray(
    jobs: list[tuple[dict[str, Any], int, int]],
    workers: int,
    address: str | None,
    keep: Callable[[dict[str, Any]], None],
) -> None:
    """Run ``jobs`` as Ray tasks, handing each record to ``keep`` here as it arrives.

    A task whose worker dies is run again by Ray (``RAY_RETRIES``); its record arrives once.
    Without ``address`` a local Ray of ``workers`` CPUs is started, whose workers import this
    project from its folder.
    """
    import ray

    from experiment.records import PROJECT

    # The BLAS kernel this process pinned (duet_robot.blas), in every worker, here or on
    # another host: a trial's record must not depend on the machine that ran it.
    kernel = os.environ.get(CORETYPE_VARIABLE)
    blas = {CORETYPE_VARIABLE: kernel} if kernel else {}
    started = not ray.is_initialized()
    if started:
        if address:
            _reachable(address)
            try:
                ray.init(address=address, log_to_driver=False, runtime_env={"env_vars": blas})
            except ConnectionError as err:
                raise RuntimeError(f"--address {address}: {_NO_CLUSTER} ({err})") from None
        else:
            ray.init(
                num_cpus=workers,
                include_dashboard=False,
                log_to_driver=False,
                runtime_env={"env_vars": {"PYTHONPATH": str(PROJECT), **blas}},
            )
    task = ray.remote(num_cpus=1, max_retries=RAY_RETRIES)(run_trial)
    pending = [task.remote(job) for job in jobs]
    try:
        while pending:
            ready, pending = ray.wait(pending, num_returns=1)
            for ref in ready:
                try:
                    record = ray.get(ref)
                except ray.exceptions.RayError as err:
                    raise RuntimeError(
                        f"ray: a trial's worker failed {RAY_RETRIES + 1} times: {err}"
                    ) from None
                keep(record)
    except BaseException:  # Ctrl-C included: stop what is running, keep what finished
        for ref in pending:
            ray.cancel(ref, force=True)
        raise
    finally:
        if started:
            ray.shutdown()


#: Times the local pool runs a trial again whose worker died (killed, crashed), as Ray does.
POOL_RETRIES = RAY_RETRIES


def _run_on_pool(
    jobs: list[tuple[dict[str, Any], int, int]],
    workers: int,
    keep: Callable[[dict[str, Any]], None],
) -> None:
    """Run ``jobs`` on a pool of ``workers`` forked processes, handing each record to ``keep``
    here as it arrives.

    A worker that dies mid-trial (killed, out of memory, a crash in compiled code) breaks
    the pool: every trial running on it then, its own and the others', is run again on a new
    pool, and each record arrives once, since a trial is done only when its record arrived.
    At most one trial per worker is handed to the pool, so those running when it broke are
    all that is run again. A trial running when its pool broke ``POOL_RETRIES + 1`` times
    is a RuntimeError (as on Ray), not a campaign that never ends.
    """
    import multiprocessing as mp
    from collections import deque
    from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
    from concurrent.futures.process import BrokenProcessPool

    queue = deque(jobs)
    broken_runs: dict[int, int] = {}
    while queue:
        pool = ProcessPoolExecutor(
            workers, mp_context=mp.get_context("fork"), initializer=_worker_init
        )
        running: dict[Future[dict[str, Any]], tuple[dict[str, Any], int, int]] = {}
        lost: list[tuple[dict[str, Any], int, int]] = []
        broken = False
        try:
            while running or (queue and not broken):
                while queue and not broken and len(running) < workers:
                    try:
                        running[pool.submit(run_trial, queue[0])] = queue[0]
                        queue.popleft()
                    except BrokenProcessPool:  # it broke since the last result came
                        broken = True
                if not running:
                    break
                finished, _ = wait(running, return_when=FIRST_COMPLETED)
                for future in finished:
                    job = running.pop(future)
                    try:
                        record = future.result()
                    except BrokenProcessPool:
                        broken = True
                        lost.append(job)
                    else:
                        keep(record)
        except BaseException:  # Ctrl-C included: end the workers, keep what finished
            _end_pool(pool)
            raise
        pool.shutdown(wait=True)
        for _, _, trial in lost:
            broken_runs[trial] = broken_runs.get(trial, 0) + 1
            if broken_runs[trial] > POOL_RETRIES:
                raise RuntimeError(
                    f"local pool: trial {trial} was running when its worker died "
                    f"{broken_runs[trial]} times (killed or crashed)"
                )
        queue.extendleft(reversed(lost))


def _end_pool(pool: Any) -> None:
    """Stop a process pool now, its running trials too (they have no record: they run again
    when the campaign resumes)."""
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    # Python 3.14 has ProcessPoolExecutor.terminate_workers(); before it, its processes.
    for process in processes:
        process.terminate()


def _worker_init() -> None:
    """In a worker: leave Ctrl-C to the parent (which ends the pool), and die with it."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:  # Linux: the kernel sends SIGTERM when the parent dies, even by SIGKILL
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass
    if os.getppid() == 1:  # the parent died before the line above took effect
        os._exit(1)


def run_campaign(
    base: World,
    n: int,
    seed: int,
    out: Path,
    workers: int = 1,
    on_result: Callable[[dict[str, Any], int, int], None] | None = None,
    tree: Path | None = None,
    on_notice: Callable[[str], None] | None = None,
    leaves: Sequence[str] = (),
    backend: str = "local",
    address: str | None = None,
    main_tree: str | None = None,
    hard: bool = False,
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
    tree : Path, optional
        Behaviour tree XML every trial runs (default: the paper's tree built in code).
        Records remember it: a campaign resumes only the trials of its own world, seed, tree
        and leaves (:func:`campaign_of`); other records in the file are kept and ignored.
    on_notice : callable (text), optional
        Told of what was repaired or skipped in an earlier ``results.jsonl``.
    leaves : sequence of str
        ``--leaves`` sources (files or modules) of the tree's own leaves; every worker
        registers them (:func:`planner.user_leaves.register_leaves`).
    backend : {"local", "ray"}
        Where trials run: a pool of ``workers`` processes here, or Ray tasks (a local Ray
        of ``workers`` CPUs, or the cluster at ``address``). Records are the same either way
        but for ``wall_time_s``, ``host`` and ``backend``; only this process writes them.
    address : str, optional
        A Ray cluster's address (``ray start --head`` prints it; "auto" finds a local one).
    main_tree : str, optional
        The ``<BehaviorTree ID>`` of ``tree`` to run instead of its ``main_tree_to_execute``;
        it is part of the campaign's key, so a campaign resumes only trials of the same one.
    hard : bool
        Hard mode (:mod:`experiment.hard`): every trial runs against a physical truth drawn
        for it. Part of the campaign's key, with the world's ``trials.hard`` ranges.

    Returns
    -------
    list of dict
        The records of trials ``0..n-1`` for this seed, in trial order.

    Raises
    ------
    ResultsFileError
        If ``out`` cannot hold the results, or its results file cannot be read or repaired.
    CampaignBusyError
        If another campaign is writing into ``out``.
    """
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise ResultsFileError(f"{out}: cannot make the folder: {err.strerror or err}") from None
    if backend not in BACKENDS:
        raise ValueError(f"run_campaign: expected backend in {BACKENDS}, got {backend!r}")
    with campaign_lock(out):
        return _run_locked(
            base,
            n,
            seed,
            out,
            workers,
            on_result,
            tree,
            on_notice or _quiet,
            leaves,
            backend,
            address,
            main_tree,
            hard,
        )


def _quiet(text: str) -> None:
    del text


def _run_locked(
    base: World,
    n: int,
    seed: int,
    out: Path,
    workers: int,
    on_result: Callable[[dict[str, Any], int, int], None] | None,
    tree: Path | None,
    on_notice: Callable[[str], None],
    leaves: Sequence[str],
    backend: str,
    address: str | None,
    main_tree: str | None = None,
    hard: bool = False,
) -> list[dict[str, Any]]:
    results = out / "results.jsonl"
    cut = repair_tail(results)
    if cut:
        on_notice(f"{results}: cut a torn last line ({cut} bytes) before appending")
    earlier = read_results(results)
    if earlier.skipped:
        on_notice(f"{results}: {earlier.skipped_text()}; their trials run again")
    key = campaign_of(base, seed, tree, leaves, main_tree, hard)
    done = campaign_results(results, key)
    other_code = older_code(done.values())
    if other_code:
        on_notice(f"{results}: {other_code}")
    pending = [t for t in range(n) if t not in done]
    payload: dict[str, Any] = {
        "world": base.model_dump(mode="json"),
        "source": str(base.source or ""),
        "tree": str(tree.resolve()) if tree is not None else "",
        "key": key,
        "leaves": [_leaf_source(s) for s in leaves],
        "backend": backend,
        **({"main_tree": main_tree} if main_tree else {}),
        **({"hard": True} if hard else {}),
    }
    die = os.environ.get("DUET_TEST_DIE_ONCE", "")
    # Test-only (see run_trial): where trials run in worker processes, never in this one.
    if (backend == "ray" or workers > 1) and ":" in die:
        at, marker = die.split(":", 1)
        payload["die_once"] = (int(at), marker)
    jobs = [(payload, seed, t) for t in pending]
    finished = n - len(pending)
    try:
        fh = open(results, "a", encoding="utf-8")
    except OSError as err:
        raise ResultsFileError(f"{results}: cannot write it: {err.strerror or err}") from None
    with fh:

        def keep(rec: dict[str, Any]) -> None:
            nonlocal finished
            if STOP_KEY in rec:
                raise CampaignStopped(
                    f"trial {rec['trial']}: {rec[STOP_KEY]} (the campaign stopped: every trial "
                    f"would meet it; the trials recorded before it are kept in {results})"
                )
            try:
                fh.write(json.dumps(rec) + "\n")
                fh.flush()
                os.fsync(fh.fileno())
            except OSError as err:  # a full disk: the trials before this one are kept whole
                try:
                    fh.close()  # its buffer cannot be written either; do not try again
                except OSError:
                    pass
                raise ResultsFileError(
                    f"{results}: cannot append trial {rec['trial']}: {err.strerror or err} "
                    "(the trials recorded before it are kept; run again to resume)"
                ) from None
            done[int(rec["trial"])] = rec
            finished += 1
            if on_result is not None:
                on_result(rec, finished, n)

        if backend == "ray":
            _run_on_ray(jobs, workers, address, keep)
        elif workers <= 1:
            try:
                for job in jobs:
                    keep(run_trial(job))
            finally:
                _close_worker_clearance()  # this process goes on: leave no scene behind
        else:
            _run_on_pool(jobs, workers, keep)
    return [done[t] for t in range(n) if t in done]

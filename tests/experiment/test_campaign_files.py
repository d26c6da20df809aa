"""A campaign's results file survives kills, corruption and a second campaign, in real processes."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from experiment.records import code_hash
from experiment.results import CampaignBusyError, campaign_lock, read_results, repair_tail
from experiment.trials import campaign_of
from worlds.world_file import load_world

ROOT = Path(__file__).resolve().parents[2]
WORLD = ROOT / "worlds" / "parcel_pick_place.yaml"


def record(trial: int, seed: int = 0) -> str:
    """A record of the default world's campaign of ``seed`` with the default tree."""
    key = campaign_of(load_world(WORLD), seed, None)
    return json.dumps({"trial": trial, **key, "success": True}) + "\n"


def trials(out: Path, n: int, *extra: str, **kwargs: object) -> subprocess.Popen[str]:
    cmd = [sys.executable, str(ROOT / "app.py"), "trials", str(WORLD), "--n", str(n)]
    return subprocess.Popen(
        [*cmd, "--out", str(out), *extra],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        **kwargs,  # type: ignore[arg-type]
    )


def test_a_torn_tail_is_cut_and_bad_lines_are_counted(tmp_path: Path) -> None:
    path = tmp_path / "results.jsonl"
    bad_types = json.dumps({"trial": "1", "seed": 0, "success": True})
    path.write_bytes(
        (record(0) + "\xff\xfe not text\n").encode("latin-1")
        + (bad_types + "\n" + record(2) + '{"trial": 3, "se').encode()
    )
    assert repair_tail(path) == len('{"trial": 3, "se')
    assert path.read_bytes().endswith(b"\n")
    read = read_results(path)
    assert [r["trial"] for r in read.records] == [0, 2] and read.skipped == 2
    assert repair_tail(path) == 0  # whole already
    assert (tmp_path / "results.jsonl.torn").read_bytes() == b'{"trial": 3, "se\n'  # kept


def test_a_whole_last_record_without_its_newline_is_kept(tmp_path: Path) -> None:
    # A file that another tool wrote, or two joined with cat: its last record had been cut
    # as torn, and that trial of that campaign was lost for good.
    path = tmp_path / "results.jsonl"
    path.write_text(record(0) + record(1).rstrip("\n"), encoding="utf-8")
    assert repair_tail(path) == 0
    assert path.read_text(encoding="utf-8") == record(0) + record(1)
    assert [r["trial"] for r in read_results(path).records] == [0, 1]
    assert not (tmp_path / "results.jsonl.torn").exists()


def test_a_whole_file_is_only_read(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # A finished campaign's file that cannot be written had been opened for writing, to
    # repair nothing, and the campaign refused: "cannot repair it: Operation not permitted".
    import builtins

    import experiment.results as results

    def read_only(file: object, mode: str = "r", *args: object, **kwargs: object) -> object:
        if "+" in mode or "w" in mode or "a" in mode:
            raise PermissionError(1, "Operation not permitted")
        return builtins.open(file, mode, *args, **kwargs)  # type: ignore[call-overload]

    path = tmp_path / "results.jsonl"
    path.write_text(record(0), encoding="utf-8")
    monkeypatch.setattr(results, "open", read_only, raising=False)
    assert repair_tail(path) == 0
    path.write_text(record(0) + '{"trial": 1', encoding="utf-8")
    with pytest.raises(results.ResultsFileError, match="cannot repair it"):
        repair_tail(path)


def test_a_folder_where_the_results_belong_is_one_message(tmp_path: Path) -> None:
    (tmp_path / "results.jsonl").mkdir()
    proc = trials(tmp_path, 1)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 2
    assert "results.jsonl: expected a results file, got a folder" in err
    assert "Traceback" not in err


def test_a_second_campaign_in_the_same_folder_is_refused(tmp_path: Path) -> None:
    with campaign_lock(tmp_path):
        with (
            pytest.raises(CampaignBusyError, match=f"process {os.getpid()}"),
            campaign_lock(tmp_path),
        ):
            pass
        proc = trials(tmp_path, 1)
        _, err = proc.communicate(timeout=120)
    assert proc.returncode == 2
    assert "another campaign" in err and f"process {os.getpid()}" in err
    assert "Traceback" not in err
    assert (
        not (tmp_path / "results.jsonl").exists()
        or read_results(tmp_path / "results.jsonl").records == []
    )


@pytest.mark.sim
def test_a_resumed_campaign_appends_after_a_torn_line(tmp_path: Path) -> None:
    path = tmp_path / "results.jsonl"
    path.write_text(record(0) + record(1) + '{"trial": 2, "seed": 0, "tr', encoding="utf-8")
    proc = trials(tmp_path, 3)
    _, err = proc.communicate(timeout=300)
    assert proc.returncode in (0, 1), err
    assert "cut a torn last line" in err and "Traceback" not in err
    assert "resuming: 2 of 3 trials already in" in err and "1 to run" in err
    read = read_results(path)
    assert [r["trial"] for r in read.records] == [0, 1, 2] and read.skipped == 0
    # Trials 0 and 1 were written by no code this one knows: resumed, said, kept.
    assert "2 of this campaign's records (trials 0, 1) were made by other code" in err
    assert read.records[2]["code_sha256"] == code_hash()
    assert "code_sha256" not in read.records[0]


def _terminal_sigint() -> None:
    """In the campaign's process before it starts: SIGINT as a terminal's job has it.

    A command a non-interactive shell starts in the background (``make test &``, ``nohup
    ... &``) ignores SIGINT, and so does everything it starts, this test's campaign too: it
    would run to its end under the Ctrl-C. A terminal's Ctrl-C is what is tested.
    """
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _group_alive(pgid: int) -> bool:
    try:
        os.killpg(pgid, 0)
    except ProcessLookupError:
        return False
    return True


def _wait_for_records(path: Path, count: int, proc: subprocess.Popen[str]) -> None:
    deadline = time.monotonic() + 240
    while time.monotonic() < deadline and proc.poll() is None:
        if path.exists() and len(read_results(path).records) >= count:
            return
        time.sleep(0.2)
    raise AssertionError(f"no {count} records before the deadline: {proc.poll()}")


@pytest.mark.sim
def test_ctrl_c_with_two_workers_ends_them_without_tracebacks(tmp_path: Path) -> None:
    proc = trials(
        tmp_path, 8, "--workers", "2", start_new_session=True, preexec_fn=_terminal_sigint
    )
    _wait_for_records(tmp_path / "results.jsonl", 1, proc)
    os.killpg(proc.pid, signal.SIGINT)  # what a terminal's Ctrl-C does: the whole group
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err[-3000:]
    assert "Traceback" not in err and "KeyboardInterrupt" not in err
    assert "run the same command again to resume" in err
    time.sleep(0.5)
    assert not _group_alive(proc.pid)
    assert read_results(tmp_path / "results.jsonl").skipped == 0


@pytest.mark.sim
def test_a_killed_parent_leaves_no_worker_running(tmp_path: Path) -> None:
    proc = trials(tmp_path, 8, "--workers", "2", start_new_session=True)
    _wait_for_records(tmp_path / "results.jsonl", 1, proc)
    proc.kill()
    proc.communicate(timeout=60)
    deadline = time.monotonic() + 10
    while _group_alive(proc.pid) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not _group_alive(proc.pid)


def test_a_mesh_or_a_leaf_edited_under_its_name_is_another_campaign(tmp_path: Path) -> None:
    # The key had hashed the world file alone: a narrower box.obj, or an edited leaf file,
    # resumed the old campaign's records as the new one's.
    from experiment.records import campaign_key, tree_name
    from tests.worlds.test_adapters import write_mesh_world

    world_file = write_mesh_world(tmp_path / "w", parcel_mesh=True)
    leaves = tmp_path / "my_leaves.py"
    leaves.write_text("DEFAULT = 0.5\n", encoding="utf-8")
    key = campaign_of(load_world(world_file), 0, None, [str(leaves)])
    files = key["settings"]["files_sha256"]
    assert set(files) == {"meshes/box.obj", str(leaves)}
    mesh = tmp_path / "w" / "meshes" / "box.obj"
    mesh.write_text(mesh.read_text(encoding="utf-8").replace("0.1 ", "0.07 "), encoding="utf-8")
    narrower = campaign_of(load_world(world_file), 0, None, [str(leaves)])
    assert narrower["world_sha256"] == key["world_sha256"]  # the world file is the same
    assert narrower != key
    leaves.write_text("DEFAULT = 0.9\n", encoding="utf-8")
    assert campaign_of(load_world(world_file), 0, None, [str(leaves)]) != narrower
    # The shipped world names no file: its key, and its recorded campaigns', are as before.
    assert "files_sha256" not in campaign_of(load_world(WORLD), 0, None)["settings"]
    # A tree outside the project is named by its file name, whatever path it was given by.
    tree = tmp_path / "mine.xml"
    assert tree_name(tree) == tree_name(Path(os.path.relpath(tree))) == "mine.xml"
    assert campaign_key("w", {}, None, 0)["tree"] == ""


def test_the_code_hash_follows_every_file_of_the_code_and_nothing_else(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from experiment import records

    for folder in records.CODE_FOLDERS:
        (tmp_path / folder).mkdir()
    (tmp_path / "app.py").write_text("print()\n", encoding="utf-8")
    law = tmp_path / "worlds" / "law.py"
    law.write_text("GAIN = 1.0\n", encoding="utf-8")
    monkeypatch.setattr(records, "PROJECT", tmp_path)

    def fresh() -> str:
        records.code_hash.cache_clear()
        return records.code_hash()

    try:
        first = fresh()
        (tmp_path / "worlds" / "__pycache__").mkdir()
        (tmp_path / "worlds" / "__pycache__" / "law.cpython-311.pyc").write_bytes(b"\0")
        (tmp_path / "tests.py").write_text("x = 1\n", encoding="utf-8")  # not the code
        assert fresh() == first
        law.write_text("GAIN = 2.0\n", encoding="utf-8")
        assert fresh() != first
        law.write_text("GAIN = 1.0\n", encoding="utf-8")
        assert fresh() == first
        law.rename(tmp_path / "planner" / "law.py")  # the same bytes elsewhere
        assert fresh() != first
    finally:
        records.code_hash.cache_clear()


def test_records_of_other_code_are_named_on_resume_and_in_the_report() -> None:
    from experiment.report import code_line, code_versions
    from experiment.trials import older_code

    here = code_hash()
    mine = [{"trial": t, "code_sha256": here} for t in range(3)]
    assert older_code(mine) == ""
    theirs = [{"trial": t, "code_sha256": "ab" * 32} for t in range(3, 10)] + [{"trial": 10}]
    told = older_code(mine + theirs)
    assert told.startswith("8 of this campaign's records (trials 3, 4, 5, 6, 7, ...)")
    versions = code_versions(mine + theirs)
    assert versions == {"ab" * 32: 7, here: 3, "unrecorded": 1}
    line = code_line({"code": versions})
    assert line is not None and "3 versions of the code" in line and "abababab: 7" in line
    assert code_line({"code": code_versions(mine)}) is None

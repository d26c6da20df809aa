"""Trials on Ray: the same records as the local pool, resume across backends, a killed worker.

Marked ``ray`` (``pytest -m ray``); skipped where Ray is not installed (the ``cluster`` extra).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from experiment.records import outcome
from experiment.results import read_results
from experiment.trials import run_campaign
from worlds.world_file import load_world

ray = pytest.importorskip("ray")

pytestmark = [pytest.mark.ray, pytest.mark.sim]

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def local_ray() -> object:
    ray.init(
        num_cpus=2,
        include_dashboard=False,
        log_to_driver=False,
        runtime_env={"env_vars": {"PYTHONPATH": str(ROOT)}},
    )
    yield ray
    ray.shutdown()


def test_ray_records_match_the_local_pool_resume_and_survive_a_killed_worker(
    tmp_path: Path, local_ray: object, monkeypatch: pytest.MonkeyPatch
) -> None:
    world = load_world(ROOT / "worlds" / "icub_parcel_pick_place.yaml")
    local, remote = tmp_path / "local", tmp_path / "ray"
    run_campaign(world, 2, 0, local, workers=1)
    marker = tmp_path / "died"
    monkeypatch.setenv("DUET_TEST_DIE_ONCE", f"1:{marker}")
    on_ray = run_campaign(world, 2, 0, remote, workers=2, backend="ray")
    assert marker.exists()  # the worker of trial 1 died on its first attempt
    lines = read_results(remote / "results.jsonl").records
    assert sorted(r["trial"] for r in lines) == [0, 1]  # run again, written once
    by_local = run_campaign(world, 2, 0, local)  # nothing left to run
    assert [r["backend"] for r in by_local] == ["local", "local"]
    assert [r["backend"] for r in on_ray] == ["ray", "ray"]
    for a, b in zip(by_local, on_ray, strict=True):
        assert outcome(a) == outcome(b)
    # Resume across backends: Ray runs only what the local pool has not.
    monkeypatch.delenv("DUET_TEST_DIE_ONCE")
    grown = run_campaign(world, 3, 0, local, workers=2, backend="ray")
    assert [r["backend"] for r in grown] == ["local", "local", "ray"]
    assert len(read_results(local / "results.jsonl").records) == 3


def test_an_address_where_no_cluster_answers_is_refused_at_once() -> None:
    # Ray retried such an address for minutes (and "auto" without a cluster raised a
    # traceback): the campaign is refused, exit 2, naming the address.
    import socket

    from experiment.trials import _reachable

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]  # closed when the block ends: nothing listens there
    with pytest.raises(RuntimeError, match=rf"--address 127.0.0.1:{port}: no Ray cluster"):
        _reachable(f"127.0.0.1:{port}")
    with pytest.raises(RuntimeError, match=rf"--address ray://127.0.0.1:{port}: no Ray"):
        _reachable(f"ray://127.0.0.1:{port}")
    with pytest.raises(RuntimeError, match="expected HOST:PORT or ray://HOST:PORT"):
        _reachable("headnode")
    with socket.socket() as listening:
        listening.bind(("127.0.0.1", 0))
        listening.listen()
        _reachable(f"127.0.0.1:{listening.getsockname()[1]}")  # something answers: Ray's turn

"""Hard mode: each trial's physical truth, drawn from the seed and the trial's index alone,
seen only by the physics, recorded whole and kept apart from Easy campaigns."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any
from xml.etree import ElementTree

import numpy as np
import pytest
import yaml
from numpy.testing import assert_allclose

from experiment.hard import draw_hard, draw_pushes, with_pushes
from experiment.layout import draw_trial
from experiment.records import outcome, owned_by
from experiment.trials import campaign_of, run_trial
from worlds.robots import robot_model_of
from worlds.testing import DEFAULT_WORLD
from worlds.world_file import World, load_world, world_spec

REPO = Path(__file__).resolve().parents[2]
SMALL_BOX = REPO / "tests" / "data" / "worlds" / "small_box.yaml"


@pytest.fixture(scope="module")
def world() -> World:
    return load_world(DEFAULT_WORLD)


def _changed(world: World, **hard: Any) -> World:
    trials = world.trials.model_copy(update={"hard": world.trials.hard.model_copy(update=hard)})
    return world.model_copy(update={"trials": trials})


def test_2000_draws_keep_to_their_ranges_with_the_expected_means(world: World) -> None:
    draws = [draw_hard(world, 11, k) for k in range(2000)]
    objects = [d.truth.of("parcel") for d in draws]
    mass = np.array([o.mass_scale for o in objects])
    friction = np.array([o.friction_scale for o in objects])
    palm = np.array([d.truth.palm_friction_scale for d in draws])
    dz = np.array([d.truth.table_dz_m for d in draws])
    for values, (lo, hi) in ((mass, (0.5, 1.5)), (friction, (0.7, 1.3)), (palm, (0.8, 1.2))):
        assert lo <= values.min() and values.max() <= hi
        # Uniform: mean (lo + hi) / 2, standard error (hi - lo) / sqrt(12 * 2000) < 0.0065.
        assert_allclose(values.mean(), (lo + hi) / 2.0, atol=0.03)
        assert_allclose(values.std(), (hi - lo) / math.sqrt(12.0), rtol=0.1)
    assert -0.03 <= dz.min() and dz.max() <= 0.03
    assert_allclose(dz.mean(), 0.0, atol=0.002)
    offsets = np.array([o.sensed_offset_m for o in objects])  # (2000, 2)
    yaws = np.degrees([o.sensed_yaw_offset_rad for o in objects])
    assert_allclose(offsets.mean(axis=0), 0.0, atol=0.0005)
    assert_allclose(offsets.std(axis=0), 0.005, rtol=0.1)
    assert_allclose(yaws.mean(), 0.0, atol=0.2)
    assert_allclose(yaws.std(), 2.0, rtol=0.1)
    model = robot_model_of(world_spec(world).scene.robot)
    limits = np.array([joint.max_torque for joint in model.driven_joints()])
    faults = [d.truth.actuators for d in draws]
    assert all(f is not None for f in faults)
    scale = np.array([f.torque_scale for f in faults if f is not None])  # (2000, 14)
    bias = np.array([f.torque_bias_nm for f in faults if f is not None]) / limits
    lag = np.array([f.lag_s for f in faults if f is not None])
    assert scale.shape == (2000, limits.size)
    assert 0.85 <= scale.min() and scale.max() <= 1.15
    assert_allclose(scale.mean(), 1.0, atol=0.01)
    assert -0.03 <= bias.min() and bias.max() <= 0.03
    assert_allclose(bias.mean(), 0.0, atol=0.001)
    assert 0.01 <= lag.min() and lag.max() <= 0.03
    assert_allclose(lag.mean(), 0.02, atol=0.001)
    assert {f.latency_ticks for f in faults if f is not None} == {1}
    # Pushes: Poisson, 0.2 per second over the 120 s window: 24 per trial on average.
    counts = np.array([len(d.pushes) for d in draws])
    assert_allclose(counts.mean(), 0.2 * 120.0, atol=0.5)
    assert_allclose(counts.var(), 0.2 * 120.0, rtol=0.15)  # a Poisson count's variance
    pushes = [p for d in draws for p in d.pushes]
    at = np.array([p.at_s for p in pushes])
    duration = np.array([p.duration_s for p in pushes])
    force = np.array([p.force_n for p in pushes])
    magnitude = np.linalg.norm(force, axis=1)
    assert 0.0 <= at.min() and at.max() < 120.0
    assert 0.05 <= duration.min() and duration.max() <= 0.2
    assert 5.0 - 1e-9 <= magnitude.min() and magnitude.max() <= 20.0 + 1e-9
    assert_allclose(magnitude.mean(), 12.5, atol=0.1)
    # Uniform on the sphere: each axis carries a third of the squared direction, mean 0.
    direction = force / magnitude[:, None]
    assert_allclose(direction.mean(axis=0), 0.0, atol=0.02)
    assert_allclose((direction**2).mean(axis=0), 1.0 / 3.0, atol=0.02)
    assert {p.object for p in pushes} == {"parcel"}


def test_a_trial_draws_the_same_truth_from_its_seed_and_index(world: World) -> None:
    a, b = draw_hard(world, 4, 17), draw_hard(world, 4, 17)
    assert a == b and a.summary() == b.summary()
    assert json.loads(json.dumps(a.summary())) == a.summary()  # a record holds it exactly
    assert draw_hard(world, 4, 18).summary() != a.summary()
    assert draw_hard(world, 5, 17).summary() != a.summary()
    # The trial's layout (start, goals, spheres) does not change what is drawn.
    trial_world, _ = draw_trial(world, 4, 17)
    assert draw_hard(trial_world, 4, 17) == a
    # Each kind of draw has a stream of its own: fewer pushes leave the truth as it was.
    calm = draw_hard(_changed(world, push_rate_hz=0.0), 4, 17)
    assert calm.truth == a.truth and calm.pushes == ()


def test_pushes_are_a_poisson_process_over_the_window() -> None:
    rng = np.random.default_rng(0)
    pushes = draw_pushes(rng, "box", 2.0, 1000.0, (1.0, 1.0), (0.1, 0.1))
    times = np.array([p.at_s for p in pushes])
    gaps = np.diff(np.concatenate(([0.0], times)))
    assert_allclose(len(pushes), 2000, atol=3 * math.sqrt(2000))
    assert_allclose(gaps.mean(), 0.5, rtol=0.05)  # exponential gaps of mean 1 / rate
    assert_allclose(gaps.std(), 0.5, rtol=0.1)
    assert_allclose(np.linalg.norm([p.force_n for p in pushes], axis=1), 1.0, rtol=1e-12)
    assert draw_pushes(rng, "box", 0.0, 1000.0, (1.0, 1.0), (0.1, 0.1)) == ()


def test_pushes_join_the_trial_worlds_own_disturbances(world: World) -> None:
    drawn = draw_hard(world, 0, 2)
    pushed = with_pushes(world, drawn.pushes)
    assert world_spec(pushed).scene.disturbances == drawn.pushes
    assert pushed.objects == world.objects and pushed.trials == world.trials


def test_hard_campaigns_have_keys_of_their_own_and_easy_keys_stay(world: World) -> None:
    # The records of earlier Easy campaigns are still their campaigns' own.
    for results, path in (
        ("trials_yaw_seed0_n100.jsonl", DEFAULT_WORLD),
        ("trials_yaw0_seed0_n100.jsonl", REPO / "bench" / "worlds" / "parcel_pick_place_yaw0.yaml"),
        ("small_box_trials_seed0_n100.jsonl", SMALL_BOX),
    ):
        text = (REPO / "bench" / "results" / results).read_text(encoding="utf-8")
        record = json.loads(text.splitlines()[0])
        base = load_world(path)
        assert owned_by(record, campaign_of(base, 0, None))
        assert not owned_by(record, campaign_of(base, 0, None, hard=True))
    easy, hard = campaign_of(world, 0, None), campaign_of(world, 0, None, hard=True)
    assert hard["settings"]["hard"] == world.trials.hard.model_dump(mode="json")
    # The robot's torque loop acts only on faulty actuators: a Hard key names it.
    assert hard["settings"]["torque_loop"]["integral_s"] > 0.0
    assert "torque_loop" not in easy["settings"]
    before_loop = REPO / "bench" / "results" / "hard_no_torque_loop_seed0_n300.jsonl"
    old_hard = json.loads(before_loop.read_text(encoding="utf-8").splitlines()[0])
    assert not owned_by(old_hard, hard)  # recorded before the loop: not resumed into it
    assert {k: v for k, v in hard.items() if k != "settings"} == {
        k: v for k, v in easy.items() if k != "settings"
    }
    # The ranges are a Hard campaign's, not an Easy one's.
    other = _changed(world, mass_scale=(0.9, 1.1))
    assert campaign_of(other, 0, None) == easy
    assert campaign_of(other, 0, None, hard=True) != hard


def _short_world(tmp_path: Path) -> Path:
    """The small box, its run cut to 2 s, pushed often enough for some to fall in it."""
    data = yaml.safe_load(SMALL_BOX.read_text(encoding="utf-8"))
    data["sim"]["max_sim_time_s"] = 2.0
    data["trials"]["hard"] = {"push_rate_hz": 3.0}
    path = tmp_path / "short_hard.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    return path


@pytest.mark.sim
def test_the_reasoner_is_told_the_file_and_the_physics_has_the_truth() -> None:
    import pybullet as pb

    from worlds.sim_world import SimWorld

    base = load_world(SMALL_BOX)
    trial_world, _ = draw_trial(base, 0, 3)
    drawn = draw_hard(trial_world, 0, 3)
    told = trial_world.objects[0]
    truth = drawn.truth.of(told.name)
    with SimWorld(trial_world, truth=drawn.truth) as sim:
        context = sim.object_context(told.name)  # what the Select leaf hands the reasoner
        body = sim.scene.object_ids[told.name]
        mass, friction = pb.getDynamicsInfo(body, -1, physicsClientId=sim.scene.client)[:2]
        start, _ = sim.scene.object_pose(told.name)
    assert (context.mass_kg, context.friction) == (told.mass, told.friction)
    assert_allclose(mass, told.mass * truth.mass_scale, rtol=1e-12)
    assert_allclose(friction, told.friction * truth.friction_scale, rtol=1e-12)
    assert abs(truth.mass_scale - 1.0) > 1e-3  # a truth that differs, so the test can tell
    # Resting on the true table; sensed (and told to the reasoner) off along x, y and yaw.
    assert_allclose(start[2], told.pose.position[2] + drawn.truth.table_dz_m, atol=1e-9)
    assert_allclose(context.position[:2], start[:2] + truth.sensed_offset_m, atol=1e-12)
    assert_allclose(context.yaw, truth.sensed_yaw_offset_rad, atol=1e-12)


@pytest.mark.sim
def test_a_hard_trial_runs_again_bit_for_bit_from_world_seed_and_index(tmp_path: Path) -> None:
    base = load_world(_short_world(tmp_path))
    payload = {
        "world": base.model_dump(mode="json"),
        "source": str(base.source),
        "tree": "",
        "key": campaign_of(base, 2, None, hard=True),
        "hard": True,
    }
    first, second = (run_trial((payload, 2, 1)) for _ in range(2))
    assert outcome(first) == outcome(second)
    assert first["mode"] == "hard" and not first["failure"].startswith("error")
    trial_world, _ = draw_trial(base, 2, 1)
    assert first["hard"] == json.loads(json.dumps(draw_hard(trial_world, 2, 1).summary()))
    # Each push reached the physics: in this 2 s world nothing is carried yet, so each was
    # skipped (pushes act during carries only: tests/worlds/test_disturbances.py).
    entries = first["disturbances"]["entries"]
    assert entries and all(e["while_held"] and (e["skipped"] or e["steps"]) for e in entries)
    pushes = first["hard"]["pushes"]
    assert [e["force_n"] for e in first["disturbances"]["entries"]] == [
        p["force_n"] for p in pushes
    ]
    # The same trial in Easy mode: no truth, no pushes, no mode.
    easy = run_trial(({**payload, "hard": False, "key": campaign_of(base, 2, None)}, 2, 1))
    assert "hard" not in easy and "mode" not in easy and "disturbances" not in easy
    assert easy["start"] == first["start"] and easy["goals"] == first["goals"]


@pytest.mark.sim
def test_trials_hard_is_a_campaign_of_its_own(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import app

    world, out = str(_short_world(tmp_path)), str(tmp_path / "out")
    common = ["trials", world, "--n", "1", "--workers", "1", "--out", out]
    assert app.main([*common, "--hard"]) == app.EXIT_FAILURE  # 2 s cannot place the box
    text = capsys.readouterr().out
    assert "0 of 1 Hard trials succeeded; results in" in text and "the paper" not in text
    assert "by mode" in text and "hard" in text
    app.main(common)  # Easy, into the same file: its trial 0 is not the Hard one's
    assert "0 of 1 trials succeeded (the paper: 16 of 20)" in capsys.readouterr().out
    lines = (tmp_path / "out" / "results.jsonl").read_text(encoding="utf-8").splitlines()
    hard, easy = (json.loads(line) for line in lines)
    assert hard["mode"] == "hard" and "hard" in hard["settings"]
    assert "mode" not in easy and easy["settings"] == {}
    assert app.main(["report", out]) == app.EXIT_OK
    report = capsys.readouterr().out
    assert "seed 0, Hard: 1 trial\n" in report and "seed 0: 1 trial\n" in report


@pytest.mark.sim
def test_only_the_papers_experiment_is_compared_with_its_16_of_20(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A world's own moves (``trials.moves``, as the task suite's worlds have) are another
    experiment than the paper's three goal regions: its summary makes no comparison."""
    import app

    data = yaml.safe_load(_short_world(tmp_path).read_text(encoding="utf-8"))
    regions = [data["trials"].pop(k) for k in ("centre", "right", "left") if k in data["trials"]]
    data["trials"]["moves"] = regions or [
        {"x": [0.58, 0.68], "y": [-0.03, 0.03]},
        {"x": [0.55, 0.65], "y": [-0.18, -0.12]},
        {"x": [0.55, 0.65], "y": [0.12, 0.18]},
    ]
    path = tmp_path / "own_moves.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    out = str(tmp_path / "out")
    app.main(["trials", str(path), "--n", "1", "--workers", "1", "--out", out])
    text = capsys.readouterr().out
    assert "0 of 1 trials succeeded; results in" in text and "the paper" not in text


def test_the_no_hold_ablation_checks_each_carry_with_the_gain_it_runs() -> None:
    # Transport refuses a composition PathClear checked with another hold gain: an ablated
    # tree that zeroed one and not the other would never carry at all.
    tree = ElementTree.parse(REPO / "bench" / "worlds" / "pick_and_place_no_hold.xml")
    leaves = [e for e in tree.iter() if e.tag in ("PathClear", "Transport") and e.get("name")]
    assert {e.tag for e in leaves} == {"PathClear", "Transport"}
    assert all(e.get("hold_gain") == "0" for e in leaves), [
        (e.tag, e.get("name"), e.get("hold_gain")) for e in leaves if e.get("hold_gain") != "0"
    ]

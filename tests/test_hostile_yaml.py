"""Alias bombs, huge files and repeated keys: refused at once, with one line, never a hang."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from affordances.safe_yaml import MAX_EXPANDED_NODES, YamlFileError, parse_yaml, shown

ROOT = Path(__file__).resolve().parents[1]
DEFAULT = ROOT / "worlds" / "parcel_pick_place.yaml"


def alias_bomb(levels: int = 9, width: int = 9) -> str:
    lines = ['a0: &a0 ["lol"]']
    for i in range(1, levels + 1):
        refs = ", ".join(f"*a{i - 1}" for _ in range(width))
        lines.append(f"a{i}: &a{i} [{refs}]")
    return "\n".join(lines) + f"\nname: *a{levels}\n"


def test_an_alias_bomb_is_refused_without_expanding_it() -> None:
    with pytest.raises(YamlFileError, match="alias bomb"):
        parse_yaml(alias_bomb())
    # Aliases a document can afford still load, shared.
    data = parse_yaml("base: &b {x: 1}\nfirst: *b\nsecond: *b\n")
    assert data["first"] is data["second"]
    assert MAX_EXPANDED_NODES >= 10_000


def test_messages_show_values_cut_by_depth_items_and_length() -> None:
    deep: list[object] = []
    for _ in range(50):
        deep = [deep, deep]
    assert len(shown(deep)) < 200
    assert len(shown("x" * 10_000)) < 100
    assert len(shown(10**400)) < 100


def run_app(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, str(ROOT / "app.py"), *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,  # a hang fails the test instead of blocking the suite
    )


@pytest.mark.parametrize("command", ["validate", "affordances"])
def test_a_world_alias_bomb_is_one_line_and_exit_2(command: str, tmp_path: Path) -> None:
    world = tmp_path / "bomb.yaml"
    text = DEFAULT.read_text(encoding="utf-8")
    world.write_text(alias_bomb() + text.split("name:", 1)[1].split("\n", 1)[1], encoding="utf-8")
    done = run_app(command, str(world))
    assert done.returncode == 2
    assert f"{world}: expected a world file, got an alias bomb: over 100000 nodes" in done.stderr
    assert "Traceback" not in done.stderr


def test_a_rule_file_alias_bomb_and_repeated_keys_are_refused(tmp_path: Path) -> None:
    bomb = tmp_path / "rules.yaml"
    bomb.write_text(alias_bomb() + "version: 1\nrules: []\n", encoding="utf-8")
    done = run_app("affordances", str(DEFAULT), "--rules", str(bomb))
    assert done.returncode == 2 and "alias bomb" in done.stderr, done.stderr
    twice = tmp_path / "twice.yaml"
    twice.write_text("version: 1\nversion: 1\nrules: []\n", encoding="utf-8")
    done = run_app("affordances", str(DEFAULT), "--rules", str(twice))
    assert done.returncode == 2 and "found duplicate key 'version'" in done.stderr, done.stderr


def test_a_huge_world_file_is_refused_before_parsing(tmp_path: Path) -> None:
    world = tmp_path / "huge.yaml"
    text = DEFAULT.read_text(encoding="utf-8")
    world.write_text(text + "#" + "x" * (2 << 20) + "\n", encoding="utf-8")
    done = run_app("validate", str(world))
    assert done.returncode == 2
    assert "over the limit of 1048576" in done.stderr and "Traceback" not in done.stderr


def test_a_tree_including_devices_is_refused_without_reading_them(tmp_path: Path) -> None:
    tree = tmp_path / "devices.xml"
    tree.write_text(
        '<root BTCPP_format="4"><include path="/dev/zero"/><include path="/dev/stdin"/>'
        '<BehaviorTree ID="Main"><Retreat name="r"/></BehaviorTree></root>',
        encoding="utf-8",
    )
    done = subprocess.run(
        [sys.executable, str(ROOT / "app.py"), "validate", str(tree)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
        stdin=subprocess.PIPE,  # /dev/stdin would block a reader forever
    )
    assert done.returncode == 2
    assert "'/dev/zero' (/dev/zero): expected a regular file, got a device or pipe" in done.stderr
    assert "'/dev/stdin'" in done.stderr and "Traceback" not in done.stderr


def test_numbers_in_exponent_form_are_numbers_as_yaml_1_2_reads_them(tmp_path: Path) -> None:
    # YAML 1.1 (PyYAML) reads 4e-2 and 1.5e3 as text: a world's `radius: 4e-2` had been
    # refused as "expected a number, got '4e-2'".
    doc = parse_yaml("a: 4e-2\nb: 1.5e3\nc: -2E+1\nd: .5e1\ne: 42\nf: 0.04\ng: 1e5x\nh: 1e400\n")
    assert doc["a"] == 0.04 and doc["b"] == 1500.0 and doc["c"] == -20.0 and doc["d"] == 5.0
    assert doc["e"] == 42 and isinstance(doc["e"], int) and doc["f"] == 0.04
    assert doc["g"] == "1e5x" and doc["h"] == float("inf")
    world = tmp_path / "w.yaml"
    text = DEFAULT.read_text(encoding="utf-8")
    world.write_text(text.replace("radius: 0.04", "radius: 4e-2", 1), encoding="utf-8")
    assert "radius: 4e-2" in world.read_text(encoding="utf-8")
    ok = subprocess.run(
        [sys.executable, str(ROOT / "app.py"), "validate", str(world)],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert ok.returncode == 0, ok.stderr
    world.write_text(text.replace("mass: 1.0", "mass: 1e400", 1), encoding="utf-8")
    bad = subprocess.run(
        [sys.executable, str(ROOT / "app.py"), "validate", str(world)],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert (
        bad.returncode == 2 and "objects[0].mass: expected a finite number, got inf" in bad.stderr
    )

"""A user's own leaf, from a file or module outside the project: registered, validated, run."""

from __future__ import annotations

import sys
from collections.abc import Iterator
from importlib.metadata import EntryPoint
from pathlib import Path

import numpy as np
import py_trees
import pytest
from py_trees.common import Status
from py_trees.ports import get_ports_registry

import app
import planner.user_leaves as user_leaves
from planner.loader import TreeFileError, load_tree
from planner.port import Move, Pose
from planner.script_enums import clear_script_enums
from planner.testing import FakeObject, FakeWorld, tick_until
from planner.user_leaves import LeafSourceError, register_leaves
from skills.library import SkillLibrary

LEAF = '''
from py_trees.common import Status
from py_trees.ports import PortInformation

from planner.leaves import WorldLeaf


class HeightAtLeast(WorldLeaf):
    """The object's centre is at least ``min_height_m`` high."""

    NODE_TYPE = "Condition"
    INPUT_PORTS = {
        "object": PortInformation(str, description="the object"),
        "min_height_m": PortInformation(
            float, required=False, default_value=0.5, description="lowest height, m"
        ),
    }
    OUTPUT_PORTS = {"height_m": PortInformation(float, description="its height, m")}

    def update(self) -> Status:
        z = float(self.world.object_pose(self.get_input("object")).position[2])
        self._set_output("height_m", z)
        if z >= float(self.get_input("min_height_m")):
            return self.succeed(f"at {z:.3f} m")
        return self.fail(f"at {z:.3f} m, below {self.get_input('min_height_m')} m")
'''

TREE = """<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Sequence name="check">
      <HeightAtLeast name="high" object="parcel" min_height_m="{low}" height_m="{z}"/>
    </Sequence>
  </BehaviorTree>
</root>
"""


@pytest.fixture
def registry_restored(clean_blackboard: None) -> Iterator[None]:
    """py_trees' ports registry and sys.modules are global: undo what a test registers."""
    before, modules = get_ports_registry(), set(sys.modules)
    yield
    registry = py_trees.ports._REGISTRY
    registry.clear()
    registry.update(before)
    for name in set(sys.modules) - modules:
        if name.startswith("duet_user_leaves") or name.startswith("tmp_leaves"):
            del sys.modules[name]


@pytest.fixture
def leaf_file(tmp_path: Path, registry_restored: None) -> Path:
    path = tmp_path / "my_leaves.py"
    path.write_text(LEAF, encoding="utf-8")
    (tmp_path / "tree.xml").write_text(TREE.replace("{low}", "0.6"), encoding="utf-8")
    return path


def test_a_leaf_from_a_file_is_validated_and_runs_on_the_fake_world(
    leaf_file: Path, library: SkillLibrary
) -> None:
    tree_file = leaf_file.parent / "tree.xml"
    with pytest.raises(TreeFileError, match=r"unknown node type 'HeightAtLeast': register it"):
        load_tree(tree_file)
    (cls,) = register_leaves([str(leaf_file)])
    assert cls.__name__ == "HeightAtLeast" and get_ports_registry()["HeightAtLeast"] is cls
    root = load_tree(tree_file)
    world = FakeWorld(
        objects=[FakeObject("parcel", np.array([0.20, 0.30, 0.15]))],
        moves={"parcel": (Move(Pose.of([0.6, 0.0, 0.675])),)},
    )
    tree = py_trees.trees.BehaviourTree(root)
    tree.setup(world=world, library=library)
    log = tick_until(tree.root, world)
    z = float(world.object_pose("parcel").position[2])
    assert log.final == Status.SUCCESS, log.feedback
    assert py_trees.blackboard.Blackboard.get("/z") == pytest.approx(z)
    # Registering the same file again is the same class (a worker, a second command).
    assert register_leaves([str(leaf_file)]) == [cls]


def test_a_leaf_with_inputs_only_or_outputs_only_is_registered(
    tmp_path: Path, registry_restored: None
) -> None:
    # BT.CPP's providedPorts() may list inputs only: such a leaf is a leaf, not skipped.
    source = LEAF.replace(
        'OUTPUT_PORTS = {"height_m": PortInformation(float, description="its height, m")}', ""
    ).replace('self._set_output("height_m", z)', "")
    source += '''

class Tally(WorldLeaf):
    """Write how many ticks it has seen."""

    OUTPUT_PORTS = {"count": PortInformation(int, description="ticks so far")}

    def update(self) -> Status:
        self._set_output("count", 1)
        return Status.SUCCESS
'''
    path = tmp_path / "one_sided.py"
    path.write_text(source, encoding="utf-8")
    classes = register_leaves([str(path)])
    assert sorted(c.__name__ for c in classes) == ["HeightAtLeast", "Tally"]
    assert [c.OUTPUT_PORTS for c in classes if c.__name__ == "HeightAtLeast"] == [{}]
    assert [c.INPUT_PORTS for c in classes if c.__name__ == "Tally"] == [{}]


def test_app_validate_and_nodes_take_leaves(
    leaf_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    tree = str(leaf_file.parent / "tree.xml")
    assert app.main(["validate", tree]) == app.EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert (
        "unknown node type 'HeightAtLeast': register it with --leaves my_leaves.py (a module "
        "defining a planner.leaves.WorldLeaf subclass named HeightAtLeast), or an installed "
        "package's duet.leaves entry point"
    ) in err
    assert app.main(["validate", tree, "--leaves", str(leaf_file)]) == app.EXIT_OK
    assert "ok (main tree 'Main'" in capsys.readouterr().out
    assert app.main(["nodes", "--leaves", str(leaf_file)]) == app.EXIT_OK
    model = capsys.readouterr().out
    assert '<Condition ID="HeightAtLeast">' in model
    assert '<input_port name="min_height_m" type="float" default="0.5">lowest height' in model
    assert '<output_port name="height_m" type="float">its height, m</output_port>' in model
    assert '<Action ID="Transport">' in model  # the shipped leaves are still there
    assert app.main(["render-tree", tree, "--leaves", str(leaf_file)]) == app.EXIT_OK
    assert "--> check.high" in capsys.readouterr().out


BUGGY = """
from py_trees.common import Status
from py_trees.ports import PortInformation

from planner.leaves import WorldLeaf


class Misspelt(WorldLeaf):
    NODE_TYPE = "Condition"
    INPUT_PORTS = {"object": PortInformation(str, description="the object")}
    OUTPUT_PORTS = {}

    def update(self) -> Status:
        return self.world.objct_pose(self.get_input("object"))


class Silent(WorldLeaf):
    NODE_TYPE = "Condition"
    INPUT_PORTS = {"object": PortInformation(str, description="the object")}
    OUTPUT_PORTS = {}

    def update(self) -> Status:
        self.succeed("looked")


class BadSetup(WorldLeaf):
    NODE_TYPE = "Condition"
    INPUT_PORTS = {"object": PortInformation(str, description="the object")}
    OUTPUT_PORTS = {}

    def setup(self, **kwargs) -> None:
        super().setup(**kwargs)
        self.camera = kwargs["camera"]

    def update(self) -> Status:
        return self.succeed("looked")


class BadTerminate(WorldLeaf):
    NODE_TYPE = "Condition"
    INPUT_PORTS = {"object": PortInformation(str, description="the object")}
    OUTPUT_PORTS = {}

    def update(self) -> Status:
        return self.running("looking")

    def terminate(self, new_status: Status) -> None:
        self.recording.stop()


class WritesText(WorldLeaf):
    NODE_TYPE = "Action"
    INPUT_PORTS = {"object": PortInformation(str, description="the object")}
    OUTPUT_PORTS = {"height_m": PortInformation(float, description="its height, m")}

    def update(self) -> Status:
        self._set_output("height_m", "tall")
        return self.succeed("wrote")
"""


def _buggy_tree(tmp_path: Path, leaf: str) -> tuple[Path, py_trees.trees.BehaviourTree, FakeWorld]:
    """The leaf file BUGGY registered, a tree of its ``leaf`` alone, and a world of a parcel:
    (the file, the tree, the world)."""
    path = tmp_path / "buggy_leaves.py"
    path.write_text(BUGGY, encoding="utf-8")
    register_leaves([str(path)])
    tree = tmp_path / "t.xml"
    tree.write_text(
        TREE.replace(
            '<HeightAtLeast name="high" object="parcel" min_height_m="{low}" height_m="{z}"/>',
            f'<{leaf} object="parcel"/>',
        ),
        encoding="utf-8",
    )
    world = FakeWorld(objects=[FakeObject("parcel", np.array([0.20, 0.30, 0.15]))])
    return path, py_trees.trees.BehaviourTree(load_tree(tree)), world


@pytest.mark.parametrize(
    ("leaf", "says"),
    [
        (
            "Misspelt",
            "buggy_leaves.py:14: leaf 'check.Misspelt' (Misspelt) raised AttributeError in "
            "update(): 'FakeWorld' object has no attribute 'objct_pose'",
        ),
        (
            "Silent",
            "leaf 'check.Silent' (Silent) update() returned None: expected a py_trees Status",
        ),
        # It had been a task failure (exit 1), "not placed" for every move, as if the world
        # had given the leaf an impossible value.
        (
            "WritesText",
            "buggy_leaves.py:57: leaf 'check.WritesText' (WritesText) raised OutputTypeError "
            "in update(): output port 'height_m': expected float, got str 'tall'; a bug in the "
            "leaf's code",
        ),
        ("BadSetup", "leaf 'check.BadSetup' (BadSetup) raised KeyError in setup(): 'camera'"),
        (
            "BadTerminate",
            "leaf 'check.BadTerminate' (BadTerminate) raised AttributeError in terminate(): "
            "'BadTerminate' object has no attribute 'recording'",
        ),
    ],
)
def test_a_bug_in_a_users_leaf_names_its_line_and_the_leaf(
    tmp_path: Path, registry_restored: None, library: SkillLibrary, leaf: str, says: str
) -> None:
    # An AttributeError in a user's update() had ended the run in Duet's traceback (exit 1);
    # an update() without a return, in 7200 "invalid status" lines until the time limit. Only
    # initialise() and update() had been guarded: a bug in setup() or terminate() ended the
    # run in Duet's traceback, exit 1, too.
    from planner.tree_problems import LeafCodeError

    path, bt, world = _buggy_tree(tmp_path, leaf)
    with pytest.raises(LeafCodeError) as err:
        bt.setup(world=world, library=library)
        bt.tick()
        bt.root.stop(Status.INVALID)  # halted while running, as a time limit halts it
    assert says in str(err.value)
    assert str(err.value).startswith(str(path))


def test_a_module_path_registers_its_leaves(
    tmp_path: Path, registry_restored: None, monkeypatch: pytest.MonkeyPatch
) -> None:
    package = tmp_path / "tmp_leaves_pkg"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "checks.py").write_text(LEAF)
    monkeypatch.syspath_prepend(str(tmp_path))
    (cls,) = register_leaves(["tmp_leaves_pkg.checks"])
    assert cls.__module__ == "tmp_leaves_pkg.checks"


def test_an_installed_entry_point_registers_its_leaves(
    tmp_path: Path, registry_restored: None, monkeypatch: pytest.MonkeyPatch
) -> None:
    (tmp_path / "tmp_leaves_ep.py").write_text(LEAF)
    monkeypatch.syspath_prepend(str(tmp_path))
    shipped = [EntryPoint("height", "tmp_leaves_ep", "duet.leaves")]
    seen: list[str] = []

    def fake_entry_points(group: str) -> list[EntryPoint]:
        seen.append(group)
        return shipped

    monkeypatch.setattr(user_leaves, "entry_points", fake_entry_points)
    (cls,) = register_leaves()
    assert seen == ["duet.leaves"] and cls.__name__ == "HeightAtLeast"
    shipped[:] = [EntryPoint("one", "tmp_leaves_ep:HeightAtLeast", "duet.leaves")]
    assert register_leaves() == [cls]
    shipped[:] = [EntryPoint("broken", "tmp_leaves_nowhere", "duet.leaves")]
    with pytest.raises(LeafSourceError, match=r"entry point broken = 'tmp_leaves_nowhere'.*"):
        register_leaves()


@pytest.mark.parametrize(
    ("text", "name", "match"),
    [
        (
            None,
            "missing.py",
            r"--leaves .*missing.py: expected a Python file or module .*got no such file",
        ),
        (
            "x = (",
            "syntax.py",
            r"--leaves .*syntax.py: cannot import it: SyntaxError: .*\(line 1\)",
        ),
        (
            "import math\n\nraise RuntimeError('no robot here')\n",
            "raises.py",
            r"cannot import it: RuntimeError: no robot here \(line 3\)",
        ),
        (
            "X = 1\n",
            "empty.py",
            r"empty.py: expected at least one planner.leaves.WorldLeaf subclass with INPUT_PORTS "
            r"or OUTPUT_PORTS defined in it, got none$",
        ),
        (
            "from planner.leaves import WorldLeaf\n\n\nclass Half(WorldLeaf):\n    pass\n",
            "abstract.py",
            r"got none \(Half declare no ports\)",
        ),
        (
            'SCRIPT_ENUMS = {"RED": "1"}\n',
            "enum_text.py",
            r"--leaves .*enum_text.py: SCRIPT_ENUMS: RED: expected an integer, got '1'$",
        ),
        (
            "SCRIPT_ENUMS = 3\n",
            "enum_int.py",
            r"SCRIPT_ENUMS: expected a dict of names to integers, an enum class or a list of "
            r"those, got int$",
        ),
        (
            'SCRIPT_ENUMS = [{"RED": 1}, {"RED": 2}]\n',
            "enum_twice.py",
            r"SCRIPT_ENUMS: RED: expected one value, got 1 and 2$",
        ),
        (
            LEAF.replace("HeightAtLeast", "Transport"),
            "clash.py",
            r"leaf Transport: expected a name no registered leaf has, got that of "
            r"planner.leaves.transport.Transport",
        ),
        # These had been registered over BT.CPP's own node (11 problems of "a leaf takes no
        # children" for a tree's every <Sequence>), a traceback, or exit 0 without a word.
        (
            LEAF.replace("HeightAtLeast", "Sequence"),
            "control.py",
            r"leaf Sequence: expected a name no built-in node has, got that of "
            r"BehaviorTree.CPP's Sequence",
        ),
        (
            LEAF.replace("HeightAtLeast", "Sleep"),
            "sleep.py",
            r"leaf Sleep: expected a name no built-in node has",
        ),
        (
            LEAF.replace("INPUT_PORTS = {", 'INPUT_PORTS = {"bad": 5, '),
            "int_port.py",
            r"leaf HeightAtLeast: INPUT_PORTS\['bad'\]: expected a py_trees.ports.PortInformation "
            r"under a port name, got int 5",
        ),
        # Port names BehaviorTree.CPP refuses: "name" had silently read the node's own path,
        # and a port starting with "_" could never be set from a tree.
        (
            LEAF.replace('"min_height_m": PortInformation', '"name": PortInformation'),
            "name_port.py",
            r"leaf HeightAtLeast: INPUT_PORTS\['name'\]: expected a port name other than ID, "
            r"_autoremap, name, which a node's element keeps for itself",
        ),
        (
            LEAF.replace('"height_m": PortInformation', '"_height": PortInformation'),
            "underscore_port.py",
            r"leaf HeightAtLeast: OUTPUT_PORTS\['_height'\]: expected a port name starting "
            r"with a letter",
        ),
        (
            LEAF.replace('"height_m": PortInformation', '"height.m": PortInformation'),
            "dotted_port.py",
            r"OUTPUT_PORTS\['height.m'\]: expected a port name without '\.'",
        ),
        (
            LEAF.replace('NODE_TYPE = "Condition"', 'NODE_TYPE = "Sandwich"'),
            "kind.py",
            r"leaf HeightAtLeast: NODE_TYPE: expected one of Action, Condition, got 'Sandwich'",
        ),
        (
            "import sys\n\nsys.exit(3)\n",
            "script.py",
            r"script.py: cannot import it: it called sys.exit\(3\) \(line 3\)",
        ),
    ],
)
def test_bad_leaf_sources_exit_2_naming_the_file(
    tmp_path: Path,
    registry_restored: None,
    capsys: pytest.CaptureFixture[str],
    text: str | None,
    name: str,
    match: str,
) -> None:
    path = tmp_path / name
    if text is not None:
        path.write_text(text, encoding="utf-8")
    with pytest.raises(LeafSourceError, match=match):
        register_leaves([str(path)])
    from planner.leaves import Transport

    assert get_ports_registry()["Transport"] is Transport  # a clash leaves the shipped leaf
    assert not {"Sequence", "Sleep", "HeightAtLeast"} & set(get_ports_registry())
    tree = Path(__file__).resolve().parents[2] / "planner" / "trees" / "pick_and_place.xml"
    assert app.main(["validate", str(tree), "--leaves", str(path)]) == app.EXIT_BAD_INPUT
    assert str(path) in capsys.readouterr().err


def test_a_module_that_is_not_there_is_named(registry_restored: None) -> None:
    with pytest.raises(
        LeafSourceError,
        match=r"--leaves no_such_pkg.leaves: expected .*no module named 'no_such_pkg'",
    ):
        register_leaves(["no_such_pkg.leaves"])


ENUMS = """
import enum


class Color(enum.IntEnum):
    RED = 1
    BLUE = 2


SCRIPT_ENUMS = [Color, {"THE_ANSWER": 42}]
"""

ENUM_TREE = """<root BTCPP_format="4">
  <BehaviorTree>
    <Sequence name="s">
      <Script name="set" code="a := THE_ANSWER; color := BLUE"/>
      <ScriptCondition name="is_blue" code="color == BLUE &amp;&amp; color != RED"/>
      <Switch2 name="sw" variable="{color}" case_1="RED" case_2="BLUE">
        <AlwaysFailure name="red"/>
        <Script name="blue" code="picked := 2"/>
        <AlwaysFailure name="other"/>
      </Switch2>
    </Sequence>
  </BehaviorTree>
</root>
"""


@pytest.fixture
def enums_restored() -> Iterator[None]:
    yield
    clear_script_enums()


def test_a_leaves_module_declares_the_enum_names_its_scripts_use(
    tmp_path: Path, registry_restored: None, enums_restored: None
) -> None:
    path = tmp_path / "colours.py"
    path.write_text(LEAF + ENUMS, encoding="utf-8")
    tree_file = tmp_path / "enums.xml"
    tree_file.write_text(ENUM_TREE, encoding="utf-8")

    def run() -> Status:
        py_trees.blackboard.Blackboard.clear()
        tree = py_trees.trees.BehaviourTree(load_tree(tree_file))
        tree.setup()
        tree.tick()
        return tree.root.status

    # Unregistered, RED is a key nothing wrote: the script cannot run.
    assert run() == Status.FAILURE
    (cls,) = register_leaves([str(path)])
    assert cls.__name__ == "HeightAtLeast"
    assert run() == Status.SUCCESS
    get = py_trees.blackboard.Blackboard.get
    assert (get("/a"), get("/color"), get("/picked")) == (42, 2, 2)
    # Registering the same source again (a worker) is no clash; a module of enums alone is
    # a source too, and another value for a known name is refused.
    register_leaves([str(path)])
    only = tmp_path / "only_enums.py"
    only.write_text('SCRIPT_ENUMS = {"GREEN": 3}\n', encoding="utf-8")
    assert register_leaves([str(only)]) == []
    other = tmp_path / "other.py"
    other.write_text('SCRIPT_ENUMS = {"RED": 5}\n', encoding="utf-8")
    with pytest.raises(
        LeafSourceError, match=r"other.py: SCRIPT_ENUMS: RED: expected one value, got 1 and 5$"
    ):
        register_leaves([str(other)])


def test_a_leaf_file_imports_a_helper_module_beside_it(
    tmp_path: Path, registry_restored: None, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(sys, "path", [*sys.path])  # the folder is added to a copy
    # It had failed, "No module named 'heights'", run from anywhere, that folder too.
    (tmp_path / "heights.py").write_text("def lowest() -> float:\n    return 0.25\n")
    leaf = LEAF.replace(
        "from planner.leaves import WorldLeaf",
        "from planner.leaves import WorldLeaf\n\nfrom heights import lowest",
    ).replace("default_value=0.5", "default_value=lowest()")
    path = tmp_path / "beside.py"
    path.write_text(leaf, encoding="utf-8")
    # Another folder's heights.py, imported by another leaf file: each file its own.
    other = tmp_path / "other"
    other.mkdir()
    (other / "heights.py").write_text("def lowest() -> float:\n    return 0.75\n")
    second = other / "beside_too.py"
    second.write_text(leaf.replace("HeightAtLeast", "HeightAtLeastToo"), encoding="utf-8")
    try:
        (cls,) = register_leaves([str(path)])
        (too,) = register_leaves([str(second)])
    finally:
        sys.modules.pop("heights", None)
    assert cls.INPUT_PORTS["min_height_m"].default_value == 0.25
    assert too.INPUT_PORTS["min_height_m"].default_value == 0.75
    assert str(tmp_path) not in sys.path and str(other) not in sys.path  # as it was


def test_a_number_is_written_as_its_output_ports_kind_where_nothing_is_lost(
    registry_restored: None,
) -> None:
    # A numpy comparison, a numpy mean or a plain 0 on a float port had stopped the run
    # ("expected bool, got bool np.True_"); BT.CPP's blackboard converts numbers so.
    from py_trees.ports import PortInformation

    from planner.leaves import WorldLeaf
    from planner.leaves.base import OutputTypeError
    from planner.wiring import wire

    class Writes(WorldLeaf):
        INPUT_PORTS: dict[str, PortInformation] = {}
        OUTPUT_PORTS = {
            "f": PortInformation(float, description="a float"),
            "i": PortInformation(int, description="an integer"),
            "b": PortInformation(bool, description="a flag"),
        }

        def update(self) -> Status:
            return Status.SUCCESS

    leaf = Writes("writes")
    wire(leaf, f="{f}", i="{i}", b="{b}")
    board = py_trees.blackboard.Client(name="reader")
    for key in ("f", "i", "b"):
        board.register_key(key, access=py_trees.common.Access.READ)
    for port, value, stored in (
        ("b", np.float64(0.1) < 0.2, True),
        ("f", 0, 0.0),
        ("f", np.float32(0.5), 0.5),
        ("f", np.float64(0.25), 0.25),
        ("i", np.int64(3), 3),
        ("i", 4.0, 4),
    ):
        leaf._set_output(port, value)
        got = board.get(port)
        assert got == stored and type(got) is type(stored), (port, value, got)
    leaf._set_output("i", np.True_)  # as a Python True, which an int port takes (py_trees)
    assert board.get("i") is True
    with pytest.raises(OutputTypeError, match=r"output port 'f': expected float, got int"):
        leaf._set_output("f", 2**53 + 1)  # no float holds it
    with pytest.raises(OutputTypeError, match=r"output port 'f': expected float, got int"):
        leaf._set_output("f", 10**400)
    with pytest.raises(OutputTypeError, match=r"output port 'i': expected int, got float 0\.5"):
        leaf._set_output("i", 0.5)
    with pytest.raises(
        OutputTypeError, match=r"output port 'f': expected float, got numpy\.str_ np\.str_\('x'\)"
    ):
        leaf._set_output("f", np.str_("x"))


def test_validate_refuses_a_key_written_as_one_type_and_read_as_another(
    leaf_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # A float written and read by a str port had validated "ok", then failed at the reader's
    # first tick ("cannot convert 0.1 (float) to str"); BT.CPP refuses it as it builds the
    # tree. A key a str port made first takes any type (BT.CPP converts from strings).
    tree = leaf_file.parent / "typed.xml"
    body = (
        '<HeightAtLeast name="high" object="parcel" height_m="{z}"/>\n'
        '      <IsHeld name="held" object="{z}"/>'
    )
    tree.write_text(TREE.replace(TREE.splitlines()[3].strip(), body), encoding="utf-8")
    argv = ["validate", str(tree), "--leaves", str(leaf_file)]
    assert app.main(argv) == app.EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert (
        f"{tree}:5: <IsHeld name=\"held\">: port 'object' (str) uses {{z}} (blackboard key "
        "/z), which <HeightAtLeast name=\"high\"> port 'height_m' made float: expected ports of "
        "one type on a key"
    ) in err
    # Two str ports on one key, which a SetBlackboard (of no type) wrote: the same type.
    shared = (
        '<SetBlackboard value="parcel" output_key="name"/>\n'
        '      <IsHeld name="held" object="{name}"/>\n'
        '      <HeightAtLeast name="high" object="{name}" height_m="{z}"/>'
    )
    tree.write_text(TREE.replace(TREE.splitlines()[3].strip(), shared), encoding="utf-8")
    assert app.main(argv) == app.EXIT_OK, capsys.readouterr().err


def test_wiring_in_code_refuses_a_missing_required_port_as_a_tree_file_does() -> None:
    # It had wired, and the leaf failed at its first tick with NoDataAvailable on a key named
    # after a uuid ("/still_dd57a0a7-.../object").
    from planner.leaves import IsHeld
    from planner.wiring import wire

    with pytest.raises(KeyError, match=r"IsHeld 'held': missing required input port 'object'"):
        wire(IsHeld("held"))
    assert wire(IsHeld("held"), object="parcel").name == "held"


def test_type_check_takes_equal_generic_types_untyped_first_uses_and_names_root_keys(
    tmp_path: Path, registry_restored: None
) -> None:
    # A reviewer's cases: two list[float] ports had been refused ("made list[float]"), as
    # had a key a SetBlackboard made before a typed port; a {@key} was named ROOT__key.
    from planner.loader import load_tree_string

    leaves = tmp_path / "lists.py"
    leaves.write_text(
        "from py_trees.common import Status\nfrom py_trees.ports import PortInformation\n"
        "from planner.leaves import WorldLeaf\n\n\n"
        "class Points(WorldLeaf):\n"
        '    OUTPUT_PORTS = {"points": PortInformation(list[float], description="p")}\n\n'
        "    def update(self) -> Status:\n        return Status.SUCCESS\n\n\n"
        "class UsesPoints(WorldLeaf):\n"
        '    INPUT_PORTS = {"points": PortInformation(list[float], description="p")}\n\n'
        "    def update(self) -> Status:\n        return Status.SUCCESS\n",
        encoding="utf-8",
    )
    register_leaves([str(leaves)])
    tree = """<root BTCPP_format="4" main_tree_to_execute="M"><BehaviorTree ID="M"><Sequence>
      <Points points="{p}"/><UsesPoints points="{p}"/>
      <SetBlackboard output_key="m" value="1"/>
      <LoopDouble queue="1.0;2.0" value="{m}"><Sleep msec="{m}"/></LoopDouble>
      </Sequence></BehaviorTree></root>"""
    load_tree_string(tree)  # no problem
    rooted = """<root BTCPP_format="4" main_tree_to_execute="M">
      <BehaviorTree ID="M"><Sequence><LoopDouble queue="1.0" value="{@m}">
        <SubTree ID="S"/></LoopDouble></Sequence></BehaviorTree>
      <BehaviorTree ID="S"><Sleep msec="{@m}"/></BehaviorTree></root>"""
    with pytest.raises(
        TreeFileError, match=r"port 'msec' \(int\) uses \{@m\} \(blackboard key /m\)"
    ):
        load_tree_string(rooted)

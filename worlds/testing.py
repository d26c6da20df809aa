"""Pytest plugin: leaves tested against a real PyBullet world (DIRECT mode), any world file.

Installed, the package registers it (and :mod:`planner.testing.fixtures`) as a pytest plugin
through its ``pytest11`` entry points; without installing, load both with ``-p
planner.testing.fixtures -p worlds.testing`` or ``pytest_plugins = [...]`` in a conftest.
PyBullet is imported only when a test uses one of the fixtures below. Then::

    @pytest.mark.sim
    def test_grasp_in_physics(sim_world, tick_leaf):  # the shipped parcel world
        log = tick_leaf(Grasp("grasp"), sim_world, object="parcel", state="{state}")

    @pytest.mark.sim
    @pytest.mark.world("my_world.yaml")  # relative to the test file's folder
    def test_in_my_world(sim_world): ...

    def test_two_worlds(make_sim_world):
        a, b = make_sim_world("a.yaml"), make_sim_world("b.yaml")

A suite can also override the ``sim_world_file`` fixture to choose the world of every test.
"""

from __future__ import annotations

# isort: off
from duet_robot.blas import pin_blas_kernel

# pytest loads its plugins before any conftest.py: the kernel app.py pins (duet_robot.blas),
# asked for here, before anything this plugin imports loads numpy.
pin_blas_kernel()
from collections.abc import Callable, Iterator  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import TYPE_CHECKING, Any  # noqa: E402

import pytest  # noqa: E402

# isort: on

if TYPE_CHECKING:
    from worlds.sim_world import SimWorld

#: The world ``sim_world`` loads unless told otherwise.
DEFAULT_WORLD = Path(__file__).resolve().parent / "parcel_pick_place.yaml"
WORLD_MARKER = "world(path): the world file sim_world loads (relative to the test file's folder)"


def pytest_configure(config: pytest.Config) -> None:
    """Register the ``world`` marker (``sim`` is planner.testing.fixtures', which this needs)."""
    config.addinivalue_line("markers", WORLD_MARKER)


def _open(path: str | Path, base: Path) -> SimWorld:
    from worlds.sim_world import SimWorld
    from worlds.world_file import load_world

    file = Path(path)
    return SimWorld(load_world(file if file.is_absolute() else base / file))


@pytest.fixture
def sim_world_file(request: pytest.FixtureRequest) -> Path:
    """The world file ``sim_world`` loads: the test's ``@pytest.mark.world(path)``, else the
    shipped parcel world. Override it in a conftest to choose another for a whole suite."""
    marker = request.node.get_closest_marker("world")
    if marker is None:
        return DEFAULT_WORLD
    if len(marker.args) != 1 or not isinstance(marker.args[0], str | Path):
        raise pytest.UsageError(
            f"{request.node.nodeid}: @pytest.mark.world: expected one world file path, "
            f"got {marker.args!r}"
        )
    path = Path(marker.args[0])
    return path if path.is_absolute() else Path(request.path).parent / path


@pytest.fixture
def sim_world(clean_blackboard: None, sim_world_file: Path) -> Iterator[SimWorld]:
    """The world of ``sim_world_file`` in PyBullet DIRECT mode, closed after the test."""
    with _open(sim_world_file, Path.cwd()) as world:
        yield world


@pytest.fixture
def make_sim_world(
    clean_blackboard: None, request: pytest.FixtureRequest
) -> Iterator[Callable[[str | Path], Any]]:
    """``make_sim_world(path)``: a SimWorld of any world file (relative paths from the test
    file's folder), each closed after the test."""
    opened: list[SimWorld] = []

    def make(path: str | Path) -> SimWorld:
        world = _open(path, Path(request.path).parent)
        opened.append(world)
        return world

    yield make
    for world in opened:
        world.close()

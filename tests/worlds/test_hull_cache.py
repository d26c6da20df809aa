"""Collision hulls of mesh files, computed once per content: read back bit for bit."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest

from skills import file_cache
from worlds.fcl_shapes import _mesh_hull, cached_mesh_hull

trimesh = pytest.importorskip("trimesh")


@pytest.fixture
def mesh(tmp_path: Path) -> Path:
    path = tmp_path / "meshes" / "blob.stl"
    path.parent.mkdir()
    # An icosphere with its vertices pushed about: a hull with many faces, not a box.
    sphere = trimesh.creation.icosphere(subdivisions=2, radius=0.05)
    rng = np.random.default_rng(3)
    sphere.vertices = sphere.vertices * rng.uniform(0.8, 1.2, size=(len(sphere.vertices), 1))
    sphere.export(path)
    return path


def _same(a: tuple[np.ndarray, np.ndarray], b: tuple[np.ndarray, np.ndarray]) -> None:
    for x, y in zip(a, b, strict=True):
        assert (x.dtype, x.shape, x.tobytes()) == (y.dtype, y.shape, y.tobytes())


def test_a_cached_hull_is_the_computed_one(mesh: Path, tmp_path: Path) -> None:
    cache = tmp_path / "cache"
    computed = _mesh_hull(mesh, 2.0)
    assert computed[0].shape[0] > 12 and computed[1].shape[1] == 3
    first = cached_mesh_hull(mesh, 2.0, cache)
    (entry,) = cache.iterdir()
    written = entry.stat().st_mtime_ns
    second = cached_mesh_hull(mesh, 2.0, cache)
    assert entry.stat().st_mtime_ns == written  # read, not computed again
    _same(computed, first)
    _same(computed, second)


def test_another_scale_or_content_is_another_entry(mesh: Path, tmp_path: Path) -> None:
    cache = tmp_path / "cache"
    cached_mesh_hull(mesh, 1.0, cache)
    cached_mesh_hull(mesh, 1.5, cache)
    assert len(list(cache.iterdir())) == 2
    trimesh.creation.box(extents=(0.1, 0.2, 0.3)).export(mesh)  # the same name, new content
    box = cached_mesh_hull(mesh, 1.0, cache)
    assert len(list(cache.iterdir())) == 3
    np.testing.assert_allclose(np.sort(np.abs(box[0]).max(axis=0)), [0.05, 0.1, 0.15])


def test_a_damaged_or_inconsistent_entry_is_computed_again(mesh: Path, tmp_path: Path) -> None:
    cache = tmp_path / "cache"
    computed = cached_mesh_hull(mesh, 1.0, cache)
    (entry,) = cache.iterdir()
    data = bytearray(entry.read_bytes())
    data[-30] ^= 0xFF
    entry.write_bytes(bytes(data))
    _same(computed, cached_mesh_hull(mesh, 1.0, cache))
    # A whole entry whose faces name vertices it does not have is not a hull either.
    buffer = io.BytesIO()
    np.savez(buffer, vertices=computed[0][:3], faces=computed[1])
    file_cache.write_entry(entry, buffer.getvalue())
    _same(computed, cached_mesh_hull(mesh, 1.0, cache))
    assert file_cache.read_entry(entry) is not None

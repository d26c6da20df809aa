"""World files, the PyBullet scene, robot control and FCL collision.

The only package that imports pybullet, fcl and trimesh.
"""

import importlib.abc as _abc
import importlib.machinery as _machinery
import os as _os
import sys as _sys
from typing import Any as _Any


class _QuietLoader(_abc.Loader):
    """pybullet's own loader, its module created with the process's stderr closed to it: the
    C module prints ``pybullet build time: ...`` to stderr as it loads, a line on every
    command's error stream that says nothing to a user. A load that fails still raises."""

    def __init__(self, loader: _Any) -> None:
        self._loader = loader

    def create_module(self, spec: _machinery.ModuleSpec) -> _Any:
        try:
            _sys.stderr.flush()
            saved = _os.dup(2)
        except (OSError, ValueError):  # no stderr to keep quiet
            return self._loader.create_module(spec)
        devnull = _os.open(_os.devnull, _os.O_WRONLY)
        try:
            _os.dup2(devnull, 2)
            return self._loader.create_module(spec)
        finally:
            _os.dup2(saved, 2)
            _os.close(saved)
            _os.close(devnull)

    def exec_module(self, module: _Any) -> None:
        self._loader.exec_module(module)


class _QuietPybullet(_abc.MetaPathFinder):
    """Finds ``pybullet`` as the path finder does, and loads it with :class:`_QuietLoader`.
    Only when something imports it: importing ``worlds`` alone (the pytest plugin) does not."""

    def find_spec(self, name: str, path: _Any = None, target: _Any = None) -> _Any:
        if name != "pybullet":
            return None
        spec = _machinery.PathFinder.find_spec(name, path)
        if spec is not None and spec.loader is not None:
            spec.loader = _QuietLoader(spec.loader)
        return spec


if not any(isinstance(f, _QuietPybullet) for f in _sys.meta_path):
    _sys.meta_path.insert(0, _QuietPybullet())

"""PyBullet for the modules outside :mod:`worlds` that call it (the figure's renderer, the
trial layout's reach probe).

Importing it from here runs :mod:`worlds` first, whose finder loads pybullet without its
``pybullet build time: ...`` line on stderr; a module that imported pybullet itself before
anything imported :mod:`worlds` printed that line on every command that loaded it.
"""

import pybullet as pb

__all__ = ["pb"]

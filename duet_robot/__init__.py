"""Duet's command line as an installed package: ``python -m duet_robot`` and the ``duet-robot``
command both run :func:`app.main`, the same commands as ``python app.py`` in a checkout.

``app`` is installed as a top-level module beside the packages it composes (``skills``,
``affordances``, ``worlds``, ``planner``, ``experiment``); this package only names the entry.
"""

from __future__ import annotations

__all__ = ["main"]


def main() -> int:
    """Run the command line on ``sys.argv``; returns the exit code."""
    from app import main as app_main

    return app_main()

"""The experiment layer: episodes, trial campaigns and their figures, above worlds and planner.

It composes a world (:mod:`worlds`) with a tree (:mod:`planner`), runs it and judges it; it
may import every other package, and none imports it (``tests/test_architecture.py``).
"""

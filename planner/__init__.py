"""Behaviour trees (py_trees) that sequence skills; talks to the world through a port."""

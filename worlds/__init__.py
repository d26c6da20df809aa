"""World files, the PyBullet scene, robot control and FCL collision.

The only package that imports pybullet, fcl and trimesh.
"""

"""The shipped leaf-testing fixtures, used by this suite as a user's suite would use them."""

from duet_robot.blas import pin_blas_kernel

pin_blas_kernel()  # as app.py does, before the plugins load numpy

pytest_plugins = ["planner.testing.fixtures", "worlds.testing"]

"""The shipped leaf-testing fixtures, used by this suite as a user's suite would use them."""

pytest_plugins = ["planner.testing.fixtures", "worlds.testing"]

"""Dynamic Movement Primitive skills: numpy and scipy only."""

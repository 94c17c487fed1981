"""Perception: the depth cameras' clouds (cloud.py), asking for them (depth_camera.py).
docs/perception.md."""

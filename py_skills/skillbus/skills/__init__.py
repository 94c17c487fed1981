"""skillbus's standard skill libraries (load one with ``skills-process --library
skillbus.skills.gripper``)."""

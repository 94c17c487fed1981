"""The robot as skills see it: the arm (through the physics server's robot interface, or
a real arm's driver speaking the same messages) and the motion service."""

"""The robot as skills see it, through its own channels (skillbus.robot.messages): the arm
(``arm.py``: joint state, trajectories, the motion service) and the camera
(``camera.py``: the objects it sees). The physics server is one implementation of those
channels, a real robot's drivers another; nothing here imports skillbus.sim."""

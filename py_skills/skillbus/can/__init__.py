"""CAN for skillbus: a user-space virtual SocketCAN bus (hub + python-can interface).

The kernel here may have no CAN (no vcan), so tests and demos use a hub on a Unix
domain socket that relays raw SocketCAN records (`struct can_frame`, 16 bytes;
`struct canfd_frame`, 72 bytes) between clients, with SocketCAN's semantics. Clients are
python-can buses of interface ``skillbus_vcan`` (or set ``CAN_INTERFACE``)::

    hub = start with `skillbus can-hub --channel gripper0`
    bus = can.Bus(interface="skillbus_vcan", channel="gripper0")
"""

"""skillbus: skill-based robot control without ROS.

Modules:
    bus       publish/subscribe over LCM (the transport is picked by URL)
    rpc       request/reply over the bus, with retries and exactly-once writes
    lockstep  the lockstep participant (frames, counts, canonical order, digests)
    netns     private network namespaces and process supervision for tests and demos
    cli       the `skillbus` command
"""

__version__ = "0.1.0"

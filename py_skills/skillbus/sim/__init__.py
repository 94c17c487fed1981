"""Talking to the physics server (sim_server): its messages, its control services and a
scripted lockstep participant (``skillbus sim-script``)."""

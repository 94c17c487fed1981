"""Attach and detach (``skills-process --interface attach=skillbus.sim.attach``): the
physics server welds an object to the robot's tool link (sim_attach_t on SB_SIM_ATTACH,
answered by sim_cmd_reply_t on SB_SIM_CMD_REPLY). This is a simulator's shortcut, as
data-generation simulators offer beside the friction grasp (InternDataEngine's
``attach_obj``/``detach_obj``): a real robot has no such interface, and a skill that asks
for one there fails naming it.

Under lockstep a request is a lockstep publication (from a tick of frame n it goes out
in frame n + 1, is applied at that frame's end and answered in the next).
"""

from __future__ import annotations

from typing import Any

from skillbus.bus import Bus, channel
from skillbus.msgs import decode, sim_attach_t, sim_cmd_reply_t


def attach_channel() -> str:
    return channel("SB_SIM_ATTACH")


def reply_channel() -> str:
    return channel("SB_SIM_CMD_REPLY")


PREFIX = "attach-"


class Attacher:
    def __init__(self, bus: Bus, participant: Any = None) -> None:
        self.bus, self.participant = bus, participant
        self.replies: dict[str, sim_cmd_reply_t] = {}
        self.bad = 0
        if participant is not None:
            participant.subscribe(reply_channel(), lambda m: self._on_reply(m.data))
        else:
            bus.subscribe(reply_channel(), lambda ch, d: self._on_reply(d))

    def _on_reply(self, data: bytes) -> None:
        r = decode(sim_cmd_reply_t, data)
        if r is None:
            self.bad += 1
            return
        if r.id.startswith(PREFIX):  # (the fingers' replies share the channel)
            self.replies[r.id] = r
            while len(self.replies) > 1000:
                self.replies.pop(next(iter(self.replies)))

    def request(self, attach: bool, obj: str, label: str) -> str:
        """Asks for a weld of `obj` to the tool (attach) or its release ("" releases
        everything the robot holds welded); returns the request's id, ``attach-`` and
        `label` (which the caller makes unique: under lockstep from the frame, so that a
        run's messages are the same on every run)."""
        m = sim_attach_t()
        m.id = PREFIX + label
        m.attach, m.object = bool(attach), obj
        if self.participant is not None:
            self.participant.publish(attach_channel(), m)
        else:
            self.bus.publish(attach_channel(), m.encode())
        return m.id

    def result(self, request_id: str) -> tuple[bool, str] | None:
        """(accepted, error) once the physics server has answered, else None."""
        r = self.replies.get(request_id)
        return None if r is None else (bool(r.accepted), r.error)


def interface(bus: Bus, participant: Any = None, arg: str = "", **options: Any) -> Attacher:
    """The attach interface (skillbus.robot.interfaces). `arg` is unused."""
    return Attacher(bus, participant)

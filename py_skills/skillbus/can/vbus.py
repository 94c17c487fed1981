"""The python-can interface ``skillbus_vcan``: a client of the virtual SocketCAN hub.

    bus = can.Bus(interface="skillbus_vcan", channel="gripper0", receive_own_messages=False)

Behaves like python-can's ``socketcan`` interface: raw SocketCAN records, CAN and CAN
FD, id/mask filters, own frames only with ``receive_own_messages``. ``send`` blocks
(up to its timeout) when the hub applies back-pressure, instead of dropping.
"""

from __future__ import annotations

import collections
import select
import socket
import time
from typing import Any

import can

from skillbus.can.hub import ECHO_OFF, ECHO_ON, JOINED, socket_path
from skillbus.can.records import CANFD_MTU, from_record, to_record
from skillbus.waiting import WaitTimeout, wait_until


class VirtualSocketCanBus(can.BusABC):
    def __init__(self, channel: str = "vcan0", receive_own_messages: bool = False, fd: bool = True,
                 connect_timeout: float = 5.0, **kwargs: Any) -> None:
        self.channel = channel
        self.channel_info = f"skillbus virtual SocketCAN {channel}"
        self._fd = fd
        path = socket_path(str(channel))
        self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        deadline = time.monotonic() + connect_timeout  # for the connection and the hub's JOINED

        def connected() -> bool:
            self.sock.connect(str(path))
            return True

        try:
            wait_until(connected, connect_timeout, f"the virtual SocketCAN hub at {path}", interval=0.02,
                       retry_on=(FileNotFoundError, ConnectionRefusedError))
        except WaitTimeout as e:
            self.sock.close()
            raise can.CanInitializationError(
                f"no virtual SocketCAN hub at {path} (start one: skillbus can-hub --channel {channel}): {e.__cause__}"
            ) from None
        self.sock.send(ECHO_ON if receive_own_messages else ECHO_OFF)
        self.bad_records = 0
        self._early: collections.deque[bytes] = collections.deque()
        # Wait until the hub has us: frames sent by anyone after this returns reach us.
        while True:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self.sock], [], [], max(left, 0.5))[0]:
                self.sock.close()
                raise can.CanInitializationError(f"the virtual SocketCAN hub at {path} did not answer")
            rec = self.sock.recv(CANFD_MTU + 1)
            if rec == JOINED:
                break
            if not rec:
                self.sock.close()
                raise can.CanInitializationError(f"the virtual SocketCAN hub at {path} hung up")
            self._early.append(rec)  # relayed to us before our first record was read: keep it
        super().__init__(channel=channel, **kwargs)

    def fileno(self) -> int:
        return self.sock.fileno()

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        if msg.is_fd and not self._fd:
            raise can.CanOperationError("CAN FD frame on a bus opened with fd=False")
        rec = to_record(msg)
        ready = select.select([], [self.sock], [], timeout)[1] if timeout is not None else [self.sock]
        if not ready:
            raise can.CanOperationError(f"send timed out after {timeout} s (the hub applies back-pressure)")
        try:
            self.sock.send(rec)
        except OSError as e:
            raise can.CanOperationError(f"virtual SocketCAN send failed: {e}") from e

    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        while True:
            if self._early:
                rec = self._early.popleft()
            else:
                ready = select.select([self.sock], [], [], timeout)[0]
                if not ready:
                    return None, False
                try:
                    rec = self.sock.recv(CANFD_MTU + 1)
                except OSError as e:
                    raise can.CanOperationError(f"virtual SocketCAN receive failed: {e}") from e
            if not rec:
                raise can.CanOperationError(f"the virtual SocketCAN hub of {self.channel} is gone")
            try:
                return from_record(rec, time.time(), self.channel), False
            except ValueError:
                self.bad_records += 1  # counted, not raised: a broken sender must not crash us
                timeout = 0.0

    def shutdown(self) -> None:
        super().shutdown()
        self.sock.close()

    @staticmethod
    def _detect_available_configs() -> list[dict]:
        d = socket_path("x").parent
        return [{"interface": "skillbus_vcan", "channel": p.stem} for p in d.glob("*.sock")] if d.exists() else []

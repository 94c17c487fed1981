"""The python-can interface ``skillbus_vcan``: a client of the virtual SocketCAN hub.

    bus = can.Bus(interface="skillbus_vcan", channel="gripper0", receive_own_messages=False)

Behaves like python-can's ``socketcan`` interface: raw SocketCAN records, CAN and CAN
FD, id/mask filters, own frames only with ``receive_own_messages``. ``send`` blocks
(up to its timeout) when the hub applies back-pressure, instead of dropping.

A hub that goes away (killed, restarted) does not end the client. While it is gone,
``send`` raises ``CanOperationError("CAN hub gone: <socket path>")``, ``recv`` returns
nothing, ``fault`` holds that text, and the client tries to connect again every
``reconnect_interval`` seconds (in ``recv``, and at once in ``send``); a restarted hub
on the same socket takes it back, with the same filters and echo setting, and
``reconnects`` counts that. After ``reconnect_timeout`` seconds without a hub (0: at
once) it gives up: ``recv`` and ``send`` raise, naming the hub and how long it waited.
Frames sent while the hub is gone are lost, as on a bus whose wires are cut. Periodic
sends (``send_periodic``, canopen's heartbeat producer) skip their frames while the hub
is gone and go on when it is back.
"""

from __future__ import annotations

import collections
import logging
import select
import socket
import threading
import time
from typing import Any

import can
from can.broadcastmanager import ThreadBasedCyclicSendTask

from skillbus.can.hub import ECHO_OFF, ECHO_ON, JOINED, socket_path
from skillbus.can.records import CANFD_MTU, from_record, to_record
from skillbus.waiting import WaitTimeout, wait_until

log = logging.getLogger("vcan")


class HubGone(can.CanOperationError):
    """The hub of a virtual SocketCAN bus is gone (for now, or for good)."""


class VirtualSocketCanBus(can.BusABC):
    def __init__(self, channel: str = "vcan0", receive_own_messages: bool = False, fd: bool = True,
                 connect_timeout: float = 5.0, reconnect_timeout: float = 60.0, reconnect_interval: float = 0.05,
                 **kwargs: Any) -> None:
        self.channel = channel
        self.channel_info = f"skillbus virtual SocketCAN {channel}"
        self._fd = fd
        self.path = socket_path(str(channel))
        self._echo = ECHO_ON if receive_own_messages else ECHO_OFF
        self.reconnect_timeout, self.reconnect_interval = float(reconnect_timeout), float(reconnect_interval)
        self.bad_records = 0
        self.reconnects = 0
        self._early: collections.deque[bytes] = collections.deque()
        self._conn_lock = threading.Lock()  # one (re)connection at a time
        self._gone_since: float | None = None  # monotonic time the hub went away; None while connected
        self.hub_losses = 0  # times the hub went away under this bus (a reconnect does not undo it)
        self.last_loss_at: float | None = None  # time.monotonic() of the last
        self._gave_up = False
        self._next_try = 0.0
        self._closed = False
        sock = self._open(connect_timeout, wait_for_socket=True)
        self.sock: socket.socket | None = sock
        super().__init__(channel=channel, **kwargs)

    # -- connecting ---------------------------------------------------------------------------
    def _open(self, timeout: float, wait_for_socket: bool) -> socket.socket:
        """A connected socket the hub has taken (JOINED), or CanInitializationError."""
        path = self.path
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        deadline = time.monotonic() + timeout  # for the connection and the hub's JOINED

        def connected() -> bool:
            sock.connect(str(path))
            return True

        try:
            if wait_for_socket:
                wait_until(connected, timeout, f"the virtual SocketCAN hub at {path}", interval=0.02,
                           retry_on=(FileNotFoundError, ConnectionRefusedError))
            else:
                connected()
        except (WaitTimeout, OSError) as e:
            sock.close()
            cause = e.__cause__ if isinstance(e, WaitTimeout) else e
            raise can.CanInitializationError(
                f"no virtual SocketCAN hub at {path} (start one: skillbus can-hub --channel {self.channel}): {cause}"
            ) from None
        try:
            sock.send(self._echo)
            # Wait until the hub has us: frames sent by anyone after this returns reach us.
            while True:
                left = deadline - time.monotonic()
                if not select.select([sock], [], [], max(left, 0.5 if wait_for_socket else 0.0))[0]:
                    raise can.CanInitializationError(f"the virtual SocketCAN hub at {path} did not answer")
                rec = sock.recv(CANFD_MTU + 1)
                if rec == JOINED:
                    return sock
                if not rec:
                    raise can.CanInitializationError(f"the virtual SocketCAN hub at {path} hung up")
                self._early.append(rec)  # relayed to us before our first record was read: keep it
        except OSError as e:
            sock.close()
            raise can.CanInitializationError(f"the virtual SocketCAN hub at {path}: {e}") from None
        except can.CanInitializationError:
            sock.close()
            raise

    @property
    def fault(self) -> str | None:
        """'CAN hub gone: <socket path>' while the hub is gone, else None."""
        if self._gone_since is None:
            return None
        return self._gone_text()

    def _gone_text(self) -> str:
        text = f"CAN hub gone: {self.path}"
        if self._gave_up:
            text += f" (not back within {self.reconnect_timeout:g} s: closed)"
        return text

    def _lost(self, sock: socket.socket, why: object) -> None:
        """The hub went away under `sock` (once per socket, whichever thread sees it first)."""
        with self._conn_lock:
            if self.sock is not sock:
                return
            self.sock = None
            self.hub_losses += 1
            self._gone_since = self.last_loss_at = time.monotonic()
            self._next_try = 0.0
            self._early.clear()
        try:
            sock.close()
        except OSError:
            pass
        log.warning("CAN hub gone: %s (%s); reconnecting for up to %g s", self.path, why, self.reconnect_timeout)

    def _reconnect(self) -> socket.socket:
        """The socket, connected again if the hub is back; HubGone while it is not."""
        with self._conn_lock:
            if self.sock is not None:
                return self.sock
            if self._closed:
                raise can.CanOperationError(f"virtual SocketCAN bus {self.channel} is shut down")
            now = time.monotonic()
            if self._gave_up or now - self._gone_since > self.reconnect_timeout:
                if not self._gave_up:
                    self._gave_up = True
                    log.error("%s", self._gone_text())
                raise HubGone(self._gone_text())
            if now < self._next_try:
                raise HubGone(self._gone_text())
            self._next_try = now + self.reconnect_interval
            try:
                sock = self._open(1.0, wait_for_socket=False)
            except can.CanInitializationError:
                raise HubGone(self._gone_text()) from None
            took = now - self._gone_since
            self.sock, self._gone_since = sock, None
            self.reconnects += 1
        log.warning("CAN hub back: %s (reconnected after %.2f s)", self.path, took)
        return sock

    # -- the python-can surface -----------------------------------------------------------------
    def fileno(self) -> int:
        sock = self.sock
        return sock.fileno() if sock is not None else -1

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        if msg.is_fd and not self._fd:
            raise can.CanOperationError("CAN FD frame on a bus opened with fd=False")
        rec = to_record(msg)
        sock = self.sock
        if sock is None:
            sock = self._reconnect()
        try:
            ready = select.select([], [sock], [], timeout)[1] if timeout is not None else [sock]
            if not ready:
                raise can.CanOperationError(f"send timed out after {timeout} s (the hub applies back-pressure)")
            sock.send(rec)
        except (ValueError, OSError) as e:  # EPIPE, ECONNRESET; a socket closed by another thread
            self._lost(sock, e)
            raise HubGone(self._gone_text()) from None

    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            left = None if deadline is None else max(0.0, deadline - time.monotonic())
            if self._early:
                rec = self._early.popleft()
            else:
                sock = self.sock
                if sock is None:
                    try:
                        self._reconnect()
                    except HubGone:
                        if self._gave_up:
                            raise
                        nap = self.reconnect_interval if left is None else min(self.reconnect_interval, left)
                        time.sleep(nap)
                        if left is not None and left <= nap:
                            return None, False
                    continue
                try:
                    ready = select.select([sock], [], [], left)[0]
                except (ValueError, OSError):  # closed by another thread (it found the hub gone)
                    continue
                if not ready:
                    return None, False
                try:
                    rec = sock.recv(CANFD_MTU + 1)
                except OSError as e:
                    self._lost(sock, e)
                    continue
                if not rec:
                    self._lost(sock, "it hung up")
                    continue
            try:
                return from_record(rec, time.time(), self.channel), False
            except ValueError:
                self.bad_records += 1  # counted, not raised: a broken sender must not crash us
                deadline = time.monotonic()

    def _send_periodic_internal(self, msgs, period: float, duration: float | None = None, autostart: bool = True,
                                modifier_callback=None) -> ThreadBasedCyclicSendTask:
        """python-can's thread-based periodic task, skipping its frames while the hub is gone
        (by default such a task would end at the first failed send)."""
        if not hasattr(self, "_lock_send_periodic"):
            self._lock_send_periodic = threading.Lock()
        return ThreadBasedCyclicSendTask(_SkipWhileGone(self), self._lock_send_periodic, msgs, period, duration,
                                         autostart=autostart, modifier_callback=modifier_callback)

    def shutdown(self) -> None:
        super().shutdown()
        with self._conn_lock:
            self._closed = True
            sock, self.sock = self.sock, None
        if sock is not None:
            sock.close()

    @staticmethod
    def _detect_available_configs() -> list[dict]:
        d = socket_path("x").parent
        return [{"interface": "skillbus_vcan", "channel": p.stem} for p in d.glob("*.sock")] if d.exists() else []


class _SkipWhileGone:
    """What a periodic task sends through: the bus, with sends while the hub is gone skipped."""

    def __init__(self, bus: VirtualSocketCanBus) -> None:
        self.bus = bus

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        try:
            self.bus.send(msg, timeout)
        except HubGone:
            if self.bus._gave_up:
                raise  # for good: the task ends (python-can logs it)

"""The virtual SocketCAN hub: relays records between the clients of one channel.

    skillbus can-hub --channel gripper0        # socket $SKILLBUS_CAN_DIR/gripper0.sock

SocketCAN semantics:
* a record from one client goes to every other client, in the order it arrived;
* a client gets its own records back only if it asked (control record b"ECHO1");
* nothing is dropped: each client has an outgoing queue; while any queue is over its
  limit, the hub stops reading from senders (back-pressure) until it drains;
* a client that dies or hangs up is removed; the others go on. So is a client that stops
  reading: one whose queue stays over the limit without draining for `stall_timeout`
  seconds is disconnected (logged with what it had queued), since the kernel's SocketCAN
  would not hold up a bus for one socket either;
* a record that is neither 16 nor 72 bytes, or whose length byte claims more data than
  it has room for, is counted and dropped (a broken client).
Filters are applied by each client (python-can's id/mask filters, as SocketCAN applies
them per socket).
"""

from __future__ import annotations

import collections
import logging
import os
import selectors
import signal
import socket
import stat
import sys
import time
from pathlib import Path

from skillbus import startup_heap
from skillbus.can.records import CANFD_MTU, check_record

log = logging.getLogger("can-hub")
QUEUE_LIMIT = 20000     # records per client before back-pressure
ECHO_ON, ECHO_OFF = b"ECHO1", b"ECHO0"
# The hub's answer to a client's first record: from now on every frame reaches it. A
# client waits for it before it is used, as a kernel socket is bound before it is used.
JOINED = b"JOIN1"


def socket_dir() -> Path:
    """Where named CAN buses live: $SKILLBUS_CAN_DIR, else a folder of this user's own
    ($XDG_RUNTIME_DIR/skillbus-can, or /tmp/skillbus-can-UID): the bus carries gripper
    commands, so no other user may reach or replace its socket."""
    env = os.environ.get("SKILLBUS_CAN_DIR")
    if env:
        return Path(env)
    runtime = os.environ.get("XDG_RUNTIME_DIR")
    return Path(runtime) / "skillbus-can" if runtime else Path(f"/tmp/skillbus-can-{os.getuid()}")


class UnsafePath(RuntimeError):
    """The socket's folder or path is not this user's own (or not a socket)."""


def private_dir(path: Path) -> None:
    """Creates `path` 0700, or checks that an existing one is ours and closed to others
    (a shared /tmp folder someone else made could hold a socket of theirs)."""
    path.mkdir(mode=0o700, parents=True, exist_ok=True)
    st = path.stat()
    if st.st_uid != os.getuid() or st.st_mode & 0o077:
        raise UnsafePath(f"the CAN socket folder {path} is not private to this user (owner uid {st.st_uid}, "
                         f"mode {stat.S_IMODE(st.st_mode):o}): use a folder of your own (SKILLBUS_CAN_DIR) or "
                         f"chmod 700 it")


def socket_path(channel: str) -> Path:
    """A channel is a name (under SKILLBUS_CAN_DIR) or a path to the hub's socket."""
    return Path(channel) if "/" in channel else socket_dir() / f"{channel}.sock"


class Client:
    def __init__(self, sock: socket.socket) -> None:
        self.sock = sock
        self.out: collections.deque[bytes] = collections.deque()
        self.echo = False
        self.last_progress = time.monotonic()  # when it last took a record
        self.gone = False  # its end is closed for reading: relay nothing more to it
        self.events = selectors.EVENT_READ  # what the selector watches for it now
        self.reset = False  # it closed with records of ours unread (ECONNRESET, reported once)


def refuse_a_live_hub(path: Path) -> None:
    """UnsafePath when a hub answers at `path`: a second hub there took the path over, and
    the first one's clients (a device, a driver) went on talking among themselves, cut off
    from everyone who connected after: one CAN bus split in two, without a word. Only a
    refused connection (a hub that died) leaves a socket that may be replaced."""
    probe = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
    probe.settimeout(1.0)
    try:
        probe.connect(str(path))
    except (ConnectionRefusedError, FileNotFoundError):
        return  # stale
    except OSError as e:
        raise UnsafePath(f"{path}: a CAN hub may still serve it ({e.strerror or e}): not taking it over") from None
    finally:
        probe.close()
    raise UnsafePath(f"a CAN hub already serves {path}: not taking its bus over (stop that hub first, or choose "
                     "another CAN channel)")


class Hub:
    def __init__(self, path: Path, queue_limit: int = QUEUE_LIMIT, stall_timeout: float = 2.0) -> None:
        self.path = path
        self.queue_limit, self.stall_timeout = queue_limit, stall_timeout
        if path.parent == socket_dir():
            private_dir(path.parent)
        else:
            path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
        if path.is_symlink() or path.exists():
            st = path.lstat()
            if not stat.S_ISSOCK(st.st_mode) or st.st_uid != os.getuid():
                raise UnsafePath(f"{path} exists and is not a socket of this user's: not removing it "
                                 f"(choose another CAN channel path)")
            refuse_a_live_hub(path)
            path.unlink()  # a stale socket from a hub that died
        self.listener = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        old_umask = os.umask(0o177)  # the socket is born 0600: only this user connects
        try:
            self.listener.bind(str(path))
        finally:
            os.umask(old_umask)
        self.listener.listen(64)
        self.listener.setblocking(False)
        self.sel = selectors.DefaultSelector()
        self.sel.register(self.listener, selectors.EVENT_READ)
        self.clients: dict[int, Client] = {}
        self.relayed = self.bad = self.stalled = 0
        self.running = True

    def _update(self, c: Client) -> None:
        events = (0 if self._paused() else selectors.EVENT_READ) | (selectors.EVENT_WRITE if c.out else 0)
        events = events or selectors.EVENT_READ  # always notice a hang-up
        if events == c.events:
            return  # (a system call saved: this runs for every record relayed)
        try:
            self.sel.modify(c.sock, events, c)
            c.events = events
        except KeyError:
            pass

    def _paused(self) -> bool:
        return any(len(c.out) > self.queue_limit for c in self.clients.values())

    def _drop(self, c: Client, why: str) -> None:
        log.info("client %d left (%s)", c.sock.fileno(), why)
        self.clients.pop(c.sock.fileno(), None)
        try:
            self.sel.unregister(c.sock)
        except (KeyError, ValueError):
            pass
        c.sock.close()

    def _read(self, c: Client) -> None:
        for _ in range(256):  # a burst per wake-up, fairly
            if self._paused():
                return
            try:
                rec = c.sock.recv(CANFD_MTU + 1)
            except BlockingIOError:
                if c.reset:  # (gone, and nothing of its is left to read)
                    self._drop(c, "connection reset, its records relayed")
                return
            except ConnectionResetError as e:
                # It closed while records we sent it were unread. The kernel says so once,
                # before the records it sent before closing: those are read and relayed,
                # then it is dropped (before, they were lost with it).
                if c.reset:
                    self._drop(c, str(e))
                    return
                c.reset = True
                continue
            except OSError as e:
                self._drop(c, str(e))
                return
            if not rec:
                self._drop(c, "hung up")
                return
            if rec in (ECHO_ON, ECHO_OFF):
                c.echo = rec == ECHO_ON
                c.out.append(JOINED)
                self._update(c)
                continue
            try:
                check_record(rec)  # its size, and a length byte that fits the data field
            except ValueError as e:
                self.bad += 1
                if self.bad <= 5 or self.bad % 1000 == 0:
                    log.warning("dropped a %d-byte record (%s; %d so far)", len(rec), e, self.bad)
                continue
            for other in list(self.clients.values()):
                if not other.gone and (other is not c or c.echo):
                    other.out.append(rec)
                    if len(other.out) == 1:
                        # Sent at once while its socket takes it: a record then costs the hub
                        # one wake-up, not a second one for the socket to become writable.
                        self._write(other)
                    else:
                        self._update(other)
            self.relayed += 1

    def _write(self, c: Client) -> None:
        while c.out:
            try:
                c.sock.send(c.out[0])
            except BlockingIOError:
                break
            except OSError as e:
                # Its end is closed, but records it sent before closing may still wait to be
                # read: stop writing, and drop it when the read side sees the hang-up.
                log.info("client %d no longer reads (%s)", c.sock.fileno(), e)
                c.gone = True
                c.out.clear()
                self._update(c)
                return
            c.out.popleft()
            c.last_progress = time.monotonic()
        self._update(c)
        if not self._paused():
            for other in list(self.clients.values()):
                self._update(other)

    def _drop_stalled(self) -> None:
        now = time.monotonic()
        for c in list(self.clients.values()):
            if len(c.out) > self.queue_limit and now - c.last_progress > self.stall_timeout:
                log.warning("client %d stopped reading: disconnected with %d records queued", c.sock.fileno(),
                            len(c.out))
                self.stalled += 1
                self._drop(c, "stopped reading")
        for c in list(self.clients.values()):
            self._update(c)

    def run(self) -> None:
        log.info("virtual SocketCAN hub on %s", self.path)
        while self.running:
            if self._paused():
                self._drop_stalled()
            for key, events in self.sel.select(timeout=0.2):
                if key.fileobj is self.listener:
                    try:
                        sock, _ = self.listener.accept()
                    except BlockingIOError:
                        continue
                    sock.setblocking(False)
                    c = Client(sock)
                    c.last_progress = time.monotonic()
                    self.clients[sock.fileno()] = c
                    self.sel.register(sock, selectors.EVENT_READ, c)
                    continue
                c = key.data
                if c.sock.fileno() not in self.clients:
                    continue
                if events & selectors.EVENT_READ:  # reads first: what a client sent before leaving counts
                    self._read(c)
                if events & selectors.EVENT_WRITE and c.sock.fileno() in self.clients:
                    self._write(c)
        self.close()

    def close(self) -> None:
        for c in list(self.clients.values()):
            self._drop(c, "hub stopping")
        self.sel.close()
        self.listener.close()
        try:
            self.path.unlink()
        except FileNotFoundError:
            pass


def main(args) -> int:
    try:
        hub = Hub(socket_path(args.channel), args.queue_limit, args.stall_timeout)
    except (UnsafePath, OSError) as e:
        print(f"error: can-hub: {e}", file=sys.stderr)
        return 1

    def stop(*_):
        hub.running = False

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    print(f"can-hub {hub.path}", flush=True)
    startup_heap.set_aside()
    hub.run()
    print(f'{{"relayed": {hub.relayed}, "bad": {hub.bad}, "stalled": {hub.stalled}}}', flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))

"""The bus: publish bytes on a channel, subscribe a handler, dispatch with a timeout.

Every skillbus process talks through this interface, never through LCM directly, so the
transport is picked by URL at start-up::

    udpm://239.255.76.67:7667?ttl=0   LCM over UDP multicast (the default)
    memq://                           LCM in-process queue (unit tests)
    dds://DOMAIN                      Cyclone DDS (skillbus.dds; loopback only unless told)

Example::

    bus = open_bus("memq://")
    bus.subscribe("SB_X", lambda channel, data: print(channel, data))
    bus.publish("SB_X", b"hello")
    bus.handle(0.1)
"""

from __future__ import annotations

import abc
import collections
import errno
import logging
import os
import re
import select
import time
from typing import Callable

import lcm

from skillbus import channels, native
from skillbus.udpm import UdpmReceiver

Handler = Callable[[str, bytes], None]
DEFAULT_URL = "udpm://239.255.76.67:7667?ttl=0"
DEFAULT_QUEUE_CAPACITY = 10000  # LCM's default of 30 silently drops bursts
# Bytes of socket receive buffer every udpm:// socket asks for unless the URL names one
# (recv_buf_size=): with the kernel's default (about 208 KB) a reply of a few UDP
# fragments, or a burst that arrives while the process is busy, overflows it and is lost
# whole. The kernel caps it at net.core.rmem_max (warned about once). As common/src/lcm_bus.cpp.
RECEIVE_BUFFER = 4 << 20
RMEM_MAX = "/proc/sys/net/core/rmem_max"

log = logging.getLogger("bus")


class BusError(RuntimeError):
    pass


class Bus(abc.ABC):
    @abc.abstractmethod
    def publish(self, channel: str, data: bytes) -> None: ...

    def caught_up_at(self) -> float:
        """The monotonic time at which this bus last had nothing left to hand out: every
        message that had arrived by then was dispatched. A wall-clock liveness check
        measures a sender's silence up to here, not up to now: a process that was not
        scheduled for a second, or is inside a long handler, has not heard a sender that
        kept sending (its messages wait in the socket), and must not call it silent. A
        bus that cannot tell says now."""
        return time.monotonic()

    @abc.abstractmethod
    def subscribe(self, channel: str, handler: Handler,
                  queue_capacity: int = DEFAULT_QUEUE_CAPACITY) -> int: ...

    @abc.abstractmethod
    def unsubscribe(self, subscription_id: int) -> None: ...

    @abc.abstractmethod
    def handle(self, timeout: float) -> bool:
        """Dispatches pending messages, waiting at most ``timeout`` seconds for the first.
        Returns True if a message was handled."""

    @property
    @abc.abstractmethod
    def url(self) -> str: ...


def guarded(handler: Handler) -> Handler:
    """`handler`, whose failure is logged instead of raised: every backend's dispatch loop
    goes on (never crash on input)."""
    def call(ch: str, data: bytes) -> None:
        try:
            handler(ch, data)
        except Exception:
            log.exception("handler for %s failed", ch)
    return call


def refuse_long_channel(channel: str) -> None:
    """BusError when `channel` is longer than LCM carries: every backend refuses it, so a
    name that works on one transport works on the other (skillbus.channels.too_long)."""
    # (every publish passes here: an ASCII name is its length in bytes, and only a name of
    # other characters is encoded to count them)
    if len(channel) > channels.MAX_CHANNEL or (not channel.isascii() and len(channel) > channels.MAX_CHANNEL // 4):
        why = channels.too_long(channel)
        if why:
            raise BusError(why)


MAX_MESSAGE_BYTES = 1 << 24  # the largest message a receiver reassembles from LCM's fragments (as LCM)
JUNK_CHECK = 256  # datagrams that dispatch nothing, read between two looks at the time


def refuse_oversized(channel: str, size: int) -> None:
    """BusError when a message of `size` bytes is larger than a receiver reassembles: it
    would be sent and dropped by every receiver. Every backend refuses it, DDS too (one
    limit, both transports); replies of any size go in chunks (skillbus.rpc). As
    common/src/channels.cpp."""
    if size > MAX_MESSAGE_BYTES:
        raise BusError(f"a message of {size} bytes on {channel}: over the {MAX_MESSAGE_BYTES} bytes (16 MiB) a "
                       f"receiver reassembles, so every receiver would drop it; send it in parts")


def resolve_url(url: str | None = None) -> str:
    return url or os.environ.get("SKILLBUS_BUS_URL") or DEFAULT_URL


def channel(name: str) -> str:
    """The channel `name` as this process names it (skillbus.channels: a robot's own
    channels under its robot, everything behind $SKILLBUS_NAMESPACE)."""
    return channels.channel(name)


def open_bus(url: str | None = None) -> Bus:
    """The bus the URL names; with a key ($SKILLBUS_KEY_FILE) every message is
    authenticated (AuthenticatedBus), and with a policy ($SKILLBUS_POLICY_FILE) only the
    identities it names may send on a channel."""
    return authenticated(open_raw_bus(url))


def open_raw_bus(url: str | None = None) -> Bus:
    """The backend the URL names (LCM or DDS) without the deployment's key: messages as
    they are on the wire. For what must see or forge those (a recorder, the tests' forgers
    and fuzzers); everything else uses open_bus."""
    url = resolve_url(url)
    scheme = url.split("://", 1)[0] if "://" in url else ""
    if scheme == "udpm":
        check_multicast_interface(url)
    if scheme in ("udpm", "memq", "file", "tcpq"):
        return LcmBus(url)
    if scheme == "dds":
        from skillbus.dds import DdsBus
        return DdsBus(url)
    raise BusError(f"bus URL '{url}': unknown scheme (expected udpm://, memq:// or dds://)")


_UDPM = re.compile(r"^udpm://([^:/?]*)(?::(\d+))?(\?.*)?$")


def check_multicast_interface(url: str) -> None:
    """Local by default: LCM joins a udpm:// group on the interface the routing table picks
    for it; on a host whose default route leaves through a network card the process would
    hear (and with ttl>0 talk to) the whole network. BusError, saying what to do, unless
    that is loopback or the interface named by $SKILLBUS_NETWORK (``--network IFACE``).
    The same check as common/src/network_guard.cpp."""
    import socket
    m = _UDPM.match(url)
    if not m:
        return
    group = m.group(1) or "239.255.76.67"
    try:
        address = int.from_bytes(socket.inet_aton(group), "big")
    except OSError:
        return  # LCM names the bad URL itself
    iface = route_interface(address)
    if iface in ("", "lo") or iface == os.environ.get("SKILLBUS_NETWORK"):
        return  # ("": no route; LCM fails with its own message)
    raise BusError(f"bus URL '{url}': the multicast group {group} would be joined on the network interface "
                   f"{iface}, where other hosts can reach it. skillbus stays on this host unless told otherwise: "
                   f"run inside a private network namespace (deploy/netns-run ...), or route multicast to loopback "
                   f"(sudo ip route add 224.0.0.0/4 dev lo), or allow that network with --network {iface} (or "
                   f"SKILLBUS_NETWORK={iface}; docs/security.md)")


def route_interface(address: int, table: str = "/proc/net/route") -> str:
    """The interface of the main routing table's longest matching route for an IPv4
    address (as an int), "" when none matches.

    >>> import tempfile
    >>> t = tempfile.NamedTemporaryFile("w", delete=False)
    >>> _ = t.write("Iface\\tDestination\\tGateway\\tFlags\\tRefCnt\\tUse\\tMetric\\tMask\\n"
    ...             "eth0\\t00000000\\t010200C0\\t0003\\t0\\t0\\t0\\t00000000\\n"
    ...             "lo\\t000000E0\\t00000000\\t0001\\t0\\t0\\t0\\t000000F0\\n"); t.close()
    >>> route_interface(0xEFFF4C43, t.name), route_interface(0x08080808, t.name)
    ('lo', 'eth0')
    """
    best, best_len, best_metric = "", -1, 0
    try:
        lines = open(table).read().splitlines()[1:]
    except OSError:
        return ""
    for line in lines:
        f = line.split()
        if len(f) < 8 or not int(f[3], 16) & 1:  # RTF_UP
            continue
        dest = int.from_bytes(bytes.fromhex(f[1])[::-1], "big")  # (little-endian hex)
        mask = int.from_bytes(bytes.fromhex(f[7])[::-1], "big")
        length, metric = bin(mask).count("1"), int(f[6])
        if address & mask == dest & mask and (length > best_len or (length == best_len and metric < best_metric)):
            best, best_len, best_metric = f[0], length, metric
    return best


def with_receive_buffer(url: str, rmem_max: int | None) -> str:
    """`url` with recv_buf_size=min(RECEIVE_BUFFER, rmem_max) for a udpm:// URL that does
    not set it (rmem_max None: unknown, the request as it is).

    >>> with_receive_buffer("udpm://239.255.76.67:7667?ttl=0", 8 << 20)
    'udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304'
    >>> with_receive_buffer("udpm://239.1.2.3", 1000000), with_receive_buffer("memq://", None)
    ('udpm://239.1.2.3?recv_buf_size=1000000', 'memq://')
    >>> with_receive_buffer("udpm://239.1.2.3?recv_buf_size=9", 1 << 30)
    'udpm://239.1.2.3?recv_buf_size=9'
    """
    if not url.startswith("udpm://") or "recv_buf_size=" in url:
        return url
    size = RECEIVE_BUFFER if not rmem_max or rmem_max <= 0 else min(RECEIVE_BUFFER, rmem_max)
    return url + ("&" if "?" in url else "?") + f"recv_buf_size={size}"


def kernel_receive_buffer_cap(path: str = RMEM_MAX) -> int | None:
    try:
        return int(open(path).read())
    except (OSError, ValueError):
        return None


_warned_cap = False


def receive_buffer_url(url: str) -> str:
    """with_receive_buffer with the kernel's cap, warning once per process when the cap is
    below RECEIVE_BUFFER."""
    global _warned_cap
    if not url.startswith("udpm://") or "recv_buf_size=" in url:
        return url
    cap = kernel_receive_buffer_cap()
    if cap is not None and cap < RECEIVE_BUFFER and not _warned_cap:
        _warned_cap = True
        log.warning("the kernel caps a socket's UDP receive buffer at %d bytes (net.core.rmem_max), under the %d "
                    "skillbus asks for: a large reply or a burst can be lost; raise it with "
                    "`sudo sysctl -w net.core.rmem_max=%d`", cap, RECEIVE_BUFFER, RECEIVE_BUFFER)
    return with_receive_buffer(url, cap)


def lane_of(channel: str) -> int:
    """Lane 1 for many-to-one channels (names ending in _ACK or _JOIN), else lane 0."""
    return 1 if channel.endswith(("_ACK", "_JOIN")) else 0


def lane1_url(url: str) -> str:
    """URL of lane 1 for a udpm:// URL (same group, port+1); "" when the URL has one lane."""
    m = _UDPM.match(url)
    if not m:
        return ""
    port = int(m.group(2)) if m.group(2) else 7667
    if not 1 <= port <= 65534:  # (refused here, naming why: LCM would refuse lane 1 only at the first ack)
        raise BusError(f"bus URL '{url}': port {m.group(2)} (1 to 65534: the second lane, for acks and joins, "
                       f"is port+1)")
    return f"udpm://{m.group(1) or '239.255.76.67'}:{port + 1}{m.group(3) or ''}"


def udpm_address(url: str) -> tuple[str, int, int]:
    """(group, port, recv_buf_size or 0) of a udpm:// URL.

    >>> udpm_address("udpm://239.1.2.3:7000?ttl=0&recv_buf_size=4096"), udpm_address("udpm://")
    (('239.1.2.3', 7000, 4096), ('239.255.76.67', 7667, 0))
    """
    m = _UDPM.match(url)
    if not m:
        raise BusError(f"bus URL '{url}': not a udpm:// URL")
    size = re.search(r"[?&]recv_buf_size=(\d+)", m.group(3) or "")
    return m.group(1) or "239.255.76.67", int(m.group(2) or 7667), int(size.group(1)) if size else 0


class LcmBus(Bus):
    """LCM backend with two lanes (same design as common/src/lcm_bus.hpp).

    LCM's UDP multicast wakes every process on a group and port for every datagram.
    Many-to-one channels (lockstep acks and joins) therefore travel on lane 1, the same
    group on port+1, which only their receiver listens to; everything else uses lane 0.

    On udpm:// the bus publishes with LCM and receives on the calling thread
    (skillbus.udpm: no receive thread, no pipe between it and this one); the socket's
    receive buffer is the queue. Other URLs (memq://, file://) use LCM both ways.
    """

    def __init__(self, url: str) -> None:
        lane1 = lane1_url(url)  # (a URL that cannot be is named first)
        check_multicast_interface(url)  # (here, not only in open_raw_bus: before any socket joins a group)
        self._url = url
        self._lane_urls = [receive_buffer_url(url), receive_buffer_url(lane1) if lane1 else ""]
        self._lanes: list[lcm.LCM | None] = [None, None]
        self._lane_subs = [0, 0]
        self._subs: dict[int, tuple[int, object]] = {}
        self._next_id = 1
        # ($SKILLBUS_LCM_RECEIVE_THREAD set: LCM's own receive thread, as before; docs/transport.md)
        self._direct = url.startswith("udpm://") and not os.environ.get("SKILLBUS_LCM_RECEIVE_THREAD")
        self._receivers: list[UdpmReceiver | None] = [None, None]
        self._by_channel: dict[str, dict[int, Handler]] = {}
        self._turn = 0  # the lane read first by the next handle(): neither starves the other
        self._caught_up = time.monotonic()  # (caught_up_at: set each time every socket was read empty)
        self.lost_sends = 0  # messages the network refused to send
        self._publishing: dict[str, int] = {}  # channel -> the lane it is published on (checked once)
        self._read_orders: tuple = (([], []), ([], []))  # handle()'s receivers and their sockets, in turns
        self._lane(0)  # fail early, with a clear message

    def _lane(self, i: int) -> lcm.LCM:
        if not self._lane_urls[i]:
            i = 0
        lane = self._lanes[i]
        if lane is None:
            try:
                lane = self._lanes[i] = lcm.LCM(self._lane_urls[i])
            except (RuntimeError, OSError) as e:
                raise BusError(f"cannot open LCM at '{self._lane_urls[i]}' (for udpm:// the host needs a "
                               f"multicast route, e.g. `ip route add 224.0.0.0/4 dev lo`): {e}") from e
        return lane

    def _receiver(self, i: int) -> UdpmReceiver:
        r = self._receivers[i]
        if r is None:
            group, port, buffer = udpm_address(self._lane_urls[i])
            try:
                r = self._receivers[i] = UdpmReceiver(group, port, buffer)
            except OSError as e:
                raise BusError(f"cannot receive on '{self._lane_urls[i]}' (for udpm:// the host needs a "
                               f"multicast route, e.g. `ip route add 224.0.0.0/4 dev lo`): {e}") from e
            # (made once here, not at every handle(): with two lanes each is read first in turn)
            order = [x for x in self._receivers if x is not None]
            orders = [order, order[::-1]] if len(order) == 2 else [order, order]
            self._read_orders = tuple((rs, [x.sock for x in rs]) for rs in orders)
        return r

    _filter_refused = False  # the kernel refused a filter once: logged, not tried again

    def _refilter(self, lane: int) -> None:
        """The lane's kernel filter (common/include/skillbus/channel_filter.hpp, through
        skillbus_native): datagrams of channels nobody here subscribed to are dropped before
        they wake the process. Without the native module every datagram wakes it, as before."""
        r = self._receivers[lane]
        lib = native.module()
        if r is None or lib is None or self._filter_refused:
            return
        two = bool(self._lane_urls[1])
        why = lib.attach_channel_filter(r.fileno(), [c for c in self._by_channel if (lane_of(c) if two else 0) == lane])
        if why:
            self._filter_refused = True
            log.warning("no channel filter on %s: %s", self._lane_urls[lane], why)
            for other in self._receivers:
                if other is not None:
                    lib.detach_channel_filter(other.fileno())

    @property
    def url(self) -> str:
        return self._url

    def publish(self, channel: str, data: bytes) -> None:
        i = self._publishing.get(channel)
        if i is None:  # (a channel's name is checked and its lane found once)
            refuse_long_channel(channel)
            i = lane_of(channel) if self._lane_urls[1] else 0
            self._lane(i)
            if len(self._publishing) > 4096:  # (a process sends on few channels; bounded anyway)
                self._publishing.clear()
            self._publishing[channel] = i
        if len(data) > MAX_MESSAGE_BYTES:
            refuse_oversized(channel, len(data))
        try:
            self._lanes[i].publish(channel, data)  # type: ignore[union-attr]
        except OSError as e:
            if e.errno in (None, 0, errno.EMSGSIZE, errno.EINVAL):  # LCM refused it, or it can never fit
                raise BusError(f"LCM publish failed on {channel} ({len(data)} bytes): {e}") from None
            # The network refused the send (down, unreachable, out of buffers): the message
            # is lost, as a datagram can be, and the protocols above notice and retry (RPC,
            # lockstep resends) or report it. Counted and logged, never fatal.
            self.lost_sends += 1
            if self.lost_sends <= 5 or self.lost_sends % 1000 == 0:
                log.warning("sending on %s failed (%s): message lost (#%d)", channel, e.strerror, self.lost_sends)

    def subscribe(self, channel: str, handler: Handler,
                  queue_capacity: int = DEFAULT_QUEUE_CAPACITY) -> int:
        refuse_long_channel(channel)
        lane = lane_of(channel) if self._lane_urls[1] else 0
        sid = self._next_id
        if self._direct:
            self._receiver(lane)
            new = channel not in self._by_channel
            self._by_channel.setdefault(channel, {})[sid] = guarded(handler)
            if new:
                self._refilter(lane)
            sub: object = channel
        else:
            sub = self._lane(lane).subscribe(channel, guarded(handler))
            sub.set_queue_capacity(queue_capacity)  # type: ignore[attr-defined]
        self._next_id += 1
        self._subs[sid] = (lane, sub)
        self._lane_subs[lane] += 1
        return sid

    def unsubscribe(self, subscription_id: int) -> None:
        entry = self._subs.pop(subscription_id, None)
        if entry is None:
            return
        lane, sub = entry
        self._lane_subs[lane] -= 1
        if self._direct:
            handlers = self._by_channel.get(sub, {})  # type: ignore[call-overload]
            handlers.pop(subscription_id, None)
            if not handlers:
                self._by_channel.pop(sub, None)  # type: ignore[call-overload]
                self._refilter(lane)
        else:
            self._lane(lane).unsubscribe(sub)

    def caught_up_at(self) -> float:
        return self._caught_up if self._direct else time.monotonic()  # (LCM's own thread: cannot tell)

    def handle(self, timeout: float) -> bool:
        if self._direct:
            return self._handle_direct(timeout)
        ms = max(0, int(timeout * 1000 + 0.999))
        if self._lane_subs[1] == 0 or self._lane_subs[0] == 0:
            r = self._lane(1 if self._lane_subs[0] == 0 and self._lane_subs[1] else 0).handle_timeout(ms)
            if r < 0:
                raise BusError(f"LCM dispatch failed on {self._url}")
            return r > 0
        lanes = [self._lane(0), self._lane(1)]
        ready, _, _ = select.select(lanes, [], [], ms / 1000)
        handled = False
        for lane in ready:
            handled |= lane.handle_timeout(0) > 0
        return handled

    def _handle_direct(self, timeout: float) -> bool:
        """One message to its handlers, waiting at most `timeout` for it (datagrams for
        channels nobody here subscribed to are read and dropped meanwhile)."""
        receivers, sockets = self._read_orders[self._turn]  # (select asks a socket for its descriptor in C)
        self._turn ^= 1
        # A flood of datagrams nobody here reads (malformed, fragments never completed,
        # channels the kernel's filter let through) must not hold the caller past its
        # timeout: the time is looked at every JUNK_CHECK of them, and the wait after them
        # is what is left of the timeout.
        deadline = time.monotonic() + timeout
        while True:
            for r in receivers:
                junk = 0
                while (m := r.read()) is not False:
                    if m is not None and self._dispatch(m):
                        return True
                    junk += 1
                    if junk % JUNK_CHECK == 0 and time.monotonic() >= deadline:
                        return False
            now = self._caught_up = time.monotonic()  # (every socket read empty)
            left = deadline - now
            if left <= 0:
                return False
            select.select(sockets, [], [], left)

    def _dispatch(self, m: tuple[str, bytes]) -> bool:
        handlers = self._by_channel.get(m[0])
        if not handlers:
            return False
        for h in list(handlers.values()):
            h(m[0], m[1])
        return True

    def subscribers(self, channel: str) -> int:
        """How many subscriptions here hear `channel` (read on the caller's thread)."""
        return len(self._by_channel.get(channel, ()))

    def lane0_socket(self) -> int | None:
        """The file descriptor of the lane-0 socket this bus reads on the caller's thread,
        when it reads only that one (else None): what skillbus.quiet_frames waits on."""
        if not self._direct or self._receivers[0] is None or self._receivers[1] is not None:
            return None
        return self._receivers[0].fileno()

    @property
    def lane1_url(self) -> str:
        """The URL acks and joins go out on."""
        return self._lane_urls[1] or self._lane_urls[0]

    def feed_datagram(self, d: bytes, sender: object) -> bool:
        """Hands a datagram read from the lane-0 socket by someone else (skillbus.
        quiet_frames) to this bus's handlers, as handle() would have: True if it
        completed a message someone here subscribed to."""
        r = self._receivers[0]
        m = r.parse(d, sender) if r is not None else None
        return m is not None and self._dispatch(m)

    @property
    def undecodable(self) -> int:
        """Datagrams on this bus's sockets that were no LCM message, and fragmented
        messages given up because a fragment was lost."""
        return sum(r.reassembler.bad + r.reassembler.incomplete for r in self._receivers if r is not None)


class DropEveryNthBus(Bus):
    """Drops every n-th message published on each channel (tests of retries and loss),
    or only on the given channels."""

    def __init__(self, inner: Bus, n: int, channels: set[str] | None = None) -> None:
        self.inner, self.n, self.channels = inner, n, channels
        self.published: collections.Counter[str] = collections.Counter()
        self.dropped = 0

    @property
    def url(self) -> str:
        return self.inner.url

    def publish(self, channel: str, data: bytes) -> None:
        self.published[channel] += 1
        if self.n > 0 and self.published[channel] % self.n == 0 and (
                self.channels is None or channel in self.channels):
            self.dropped += 1
            return
        self.inner.publish(channel, data)

    def subscribe(self, channel: str, handler: Handler,
                  queue_capacity: int = DEFAULT_QUEUE_CAPACITY) -> int:
        return self.inner.subscribe(channel, handler, queue_capacity)

    def unsubscribe(self, subscription_id: int) -> None:
        self.inner.unsubscribe(subscription_id)

    def handle(self, timeout: float) -> bool:
        return self.inner.handle(timeout)

    def caught_up_at(self) -> float:
        return self.inner.caught_up_at()


class DropEveryNthReceivedBus(DropEveryNthBus):
    """Drops every n-th message received on each channel whose name ends with one of
    `suffixes` (tests of a watcher that must not depend on hearing everything)."""

    def __init__(self, inner: Bus, n: int, suffixes: tuple[str, ...]) -> None:
        super().__init__(inner, 0)
        self.receive_n, self.suffixes = n, suffixes
        self.received: collections.Counter[str] = collections.Counter()

    def subscribe(self, channel: str, handler: Handler,
                  queue_capacity: int = DEFAULT_QUEUE_CAPACITY) -> int:
        if not channel.endswith(self.suffixes):
            return self.inner.subscribe(channel, handler, queue_capacity)

        def losing(ch: str, data: bytes) -> None:
            self.received[ch] += 1
            if self.received[ch] % self.receive_n == 0:
                self.dropped += 1
                return
            handler(ch, data)
        return self.inner.subscribe(channel, losing, queue_capacity)


def authenticated(inner: Bus) -> Bus:
    """`inner` behind the deployment's key, when there is one (skillbus.auth.key_path);
    else `inner` as it is, with one warning per process: without a key anyone who can
    reach the bus commands the robot."""
    from skillbus import auth, policy
    path = auth.key_path()
    if path is None:
        global _warned_open
        if not _warned_open:
            _warned_open = True
            log.warning("no bus key (neither $%s nor %s): messages are neither signed nor checked; any "
                        "process that reaches the bus can command this robot (skillbus key create; "
                        "docs/security.md)", auth.KEY_ENV, auth.default_key_path())
        return inner
    try:
        keys = auth.load_keys(path)
        rules = policy.from_env()
    except (auth.KeyFileError, policy.PolicyError) as e:
        raise BusError(str(e)) from None
    try:
        return AuthenticatedBus(inner, keys, auth.default_identity(), rules)
    except ValueError as e:  # (an identity that cannot sign)
        raise BusError(str(e)) from None


_warned_open = False


class AuthenticatedBus(Bus):
    """Signs what it publishes and hands its handlers only messages that verify
    (skillbus.auth): unsigned, forged, stale, replayed and forbidden ones are dropped and
    counted in `rejected`, and logged at most once per 10 s per reason and sender."""

    LOG_EVERY_S = 10.0

    def __init__(self, inner: Bus, keys: list[bytes], identity: str, rules=None) -> None:
        from skillbus import auth
        self.inner, self.identity, self._rules = inner, identity, rules
        self.keys = list(keys)
        self._sealer = auth.bus_sealer(keys[0], identity)
        self._opener = auth.bus_opener(keys, rules)
        self._rejected_type = auth.Rejected
        self._last_log: dict[tuple[str, str], float] = {}
        self._quiet: collections.Counter[tuple[str, str]] = collections.Counter()
        self._verified: dict[tuple[str, bytes], object] = {}  # this handle()'s datagrams

    @property
    def url(self) -> str:
        return self.inner.url

    @property
    def rejected(self) -> collections.Counter:
        """Messages dropped, by reason (skillbus.auth.REASONS); "ok" counts the good ones."""
        return self._opener.stats

    @property
    def native_opener(self):
        """The skillbus_native.Opener this bus verifies with, or None when Python verifies
        (skillbus.quiet_frames shares it: one replay window)."""
        return getattr(self._opener, "core", None)

    def refused(self, channel: str) -> str:
        """Why this process may not send on `channel` under the policy ("" when it may): a
        program checks the channels it answers on at start, not at its first answer."""
        if self._rules is None or self._rules.allows(self.identity, channel):
            return ""
        return (f"the bus policy {self._rules.source} does not let '{self.identity}' send on {channel} (set "
                f"$SKILLBUS_IDENTITY to an identity the policy names for it, or add a rule; docs/security.md)")

    def publish(self, channel: str, data: bytes) -> None:
        """Raises BusError when the policy does not let this identity send on the
        channel: every receiver would drop the message (and a lockstep frame would wait
        for it, then fail as "message lost"); refused here, the sender names the rule it
        lacks. As common/src/auth.cpp."""
        if self._rules is not None and not self._rules.allows(self.identity, channel):
            raise BusError(f"the bus policy {self._rules.source} does not let '{self.identity}' send on {channel}: "
                           f"every receiver would drop it (add a rule for it; docs/security.md)")
        self.inner.publish(channel, self._sealer.seal(channel, bytes(data)))

    def subscribe(self, channel: str, handler: Handler,
                  queue_capacity: int = DEFAULT_QUEUE_CAPACITY) -> int:
        def verified(ch: str, data: bytes) -> None:
            # One datagram reaches every subscription it matches, within one handle():
            # it is verified once (a second check would call it a replay); a replay comes
            # as another datagram, in a later handle().
            key = (ch, bytes(data[-38:]))
            opened = self._verified.get(key)
            if opened is None:
                try:
                    opened = self._opener.open(ch, data)
                except self._rejected_type as r:
                    opened = r
                    self._note(r)
                self._verified[key] = opened
            if not isinstance(opened, self._rejected_type):
                handler(ch, opened.payload)
        return self.inner.subscribe(channel, verified, queue_capacity)

    def _note(self, r) -> None:
        import time
        key = (r.reason, r.identity)
        now = time.monotonic()
        if now - self._last_log.get(key, -1e9) < self.LOG_EVERY_S:
            self._quiet[key] += 1
            return
        self._last_log[key] = now
        more = self._quiet.pop(key, 0)
        log.warning("dropped %s%s", ascii(str(r))[1:-1], f" (and {more} more like it)" if more else "")

    def unsubscribe(self, subscription_id: int) -> None:
        self.inner.unsubscribe(subscription_id)

    def caught_up_at(self) -> float:
        return self.inner.caught_up_at()

    def handle(self, timeout: float) -> bool:
        self._verified.clear()
        try:
            return self.inner.handle(timeout)
        finally:
            self._verified.clear()

    def feed_datagram(self, d: bytes, sender: object) -> bool:
        """As LcmBus.feed_datagram, the message verified first."""
        self._verified.clear()
        try:
            return self.inner.feed_datagram(d, sender)  # type: ignore[attr-defined]
        finally:
            self._verified.clear()

    def note_verified(self, what: str, channel: str, count: int) -> None:
        """Counts `count` messages on `channel` verified for this bus by someone else
        (skillbus.quiet_frames): "ok", or the reason they were dropped (logged as the bus
        logs its own)."""
        from skillbus import auth
        self._opener.stats[what] += count
        if what != "ok":
            self._note(auth.Rejected(what, f"{count} message(s) on {channel}"))

"""The Cyclone DDS backend of the bus: ``dds://DOMAIN[?peers=HOST,HOST&interface=ADDR&state=best-effort]``.

Messages stay LCM-encoded (lcmtypes/); DDS carries each as a sequence of octets
(``skillbus::Envelope``, lcmtypes/dds/envelope.idl), one DDS topic per channel, so a
process receives only the channels it reads (LCM's multicast wakes every process for
every datagram on the port). The C++ twin is common/src/dds_bus.cpp; the Python side is
the ``cyclonedds`` wheel (its own Cyclone DDS 11), the C++ side Debian's 0.10: the two
interoperate for this octet payload (an int8/uint8 field would not; keep it so).

Quality of service per channel class (docs/transport.md, "DDS"):

* everything by default (RPC, lockstep, the world model's change stream, skills):
  reliable, keep-all, transient-local with the last 16 kept for readers that match
  later: nothing published to a matched reader is lost;
* state (names ending in ``_STATE``, ``_OBJECTS``, ``_ARTICULATION``): reliable keep-last
  1,024 (a reader that falls that far behind gets the latest), or with
  ``state=best-effort`` best-effort, for wall-clock state on a real network (never under
  lockstep: a lost state stops a run); a reader gets none written before it existed.

Private by default: the participant talks on loopback only (no multicast; discovery by
unicast to localhost); a $CYCLONEDDS_URI of the user's is used only where the network is
allowed (cyclone_config). ``peers=`` adds hosts to
discover (a fixed peer list, for a network without multicast), ``interface=`` names
the address to talk on instead of 127.0.0.1 (the network guard applies as for udpm://).
"""


import atexit
import logging
import os
import re
import struct
import time
from dataclasses import dataclass
from skillbus.bus import Bus, BusError, Handler, guarded, refuse_long_channel, refuse_oversized

log = logging.getLogger("bus")

try:
    from cyclonedds import core
    from cyclonedds._clayer import ddspy_take, ddspy_write  # (the wheel's raw CDR calls: no Python codec)
    from cyclonedds.idl import IdlStruct
    from cyclonedds.idl.types import byte, sequence

    class Envelope(IdlStruct, typename="skillbus::Envelope"):
        """One LCM-encoded message (lcmtypes/dds/envelope.idl)."""
        data: sequence[byte]

    _IMPORT_ERROR: ImportError | None = None
except ImportError as _e:
    _IMPORT_ERROR = _e

# A state reader keeps this many samples it has not taken (like LCM's 4 MB receive buffer, so a
# burst, a flood of forgeries included, does not push a frame's state out before it is
# read); keep-last, so a slow reader never holds its writer back.
STATE_DEPTH = 1024
LATE_JOINER_DEPTH = 16  # samples a writer keeps for readers that match it later
LATE_JOINER_WINDOW_NS = 2_000_000_000  # of those, only what was written this long before the reader
MAX_PARTICIPANTS = 120  # per host and domain (Cyclone's participant index: ports 7410 + 2 * index ...)
# How long a process that vanished without saying so (killed) is still matched: a
# reliable writer keeps what it sent for that process's readers until then, and blocks
# once too much is unacknowledged. Cyclone's default is 10 s.
LEASE_S = 3
_RETCODE_TIMEOUT = -10  # DDS_RETCODE_TIMEOUT
_PATTERN = re.compile(r"[.*+?\[\](){}|^$\\]")  # (what makes an LCM channel a regular expression)
_URL = re.compile(r"^dds://(\d+)(?:\?(.*))?$")
_LEN_LE, _LEN_BE = struct.Struct("<I"), struct.Struct(">I")
_CDR_HEADER = b"\x00\x01\x00\x00"  # CDR, little-endian (XCDR1: what a final struct of octets is in both)


class DdsUrlError(ValueError):
    pass


@dataclass(frozen=True)
class DdsUrl:
    domain: int
    peers: tuple[str, ...] = ()
    interface: str = "127.0.0.1"
    state_best_effort: bool = False


def parse_url(url: str) -> DdsUrl:
    """The parts of a dds:// URL; DdsUrlError naming what is wrong.

    >>> parse_url("dds://7")
    DdsUrl(domain=7, peers=(), interface='127.0.0.1', state_best_effort=False)
    >>> parse_url("dds://0?peers=10.0.0.2,robot-b&interface=10.0.0.1&state=best-effort").peers
    ('10.0.0.2', 'robot-b')
    """
    m = _URL.match(url)
    if not m:
        raise DdsUrlError(f"bus URL '{url}': expected dds://DOMAIN (a number 0-232), optionally "
                          f"?peers=HOST,...&interface=ADDRESS&state=best-effort")
    domain = int(m.group(1))
    if domain > 232:
        raise DdsUrlError(f"bus URL '{url}': DDS domain {domain} is out of range (0-232)")
    out = DdsUrl(domain)
    for part in filter(None, (m.group(2) or "").split("&")):
        key, _, value = part.partition("=")
        if key == "peers":
            out = DdsUrl(out.domain, tuple(p for p in value.split(",") if p), out.interface, out.state_best_effort)
        elif key == "interface" and value:
            out = DdsUrl(out.domain, out.peers, value, out.state_best_effort)
        elif key == "state" and value in ("best-effort", "reliable"):
            out = DdsUrl(out.domain, out.peers, out.interface, value == "best-effort")
        else:
            raise DdsUrlError(f"bus URL '{url}': unknown option '{part}' (peers=, interface=, state=best-effort)")
    return out


def check_local(u: DdsUrl, url: str, allowed: str | None = None) -> None:
    """Local by default, as udpm:// is: an interface other than loopback, or a peer other
    than this host, lets other hosts in; BusError saying how to allow it, unless
    $SKILLBUS_NETWORK (``--network``) is set.

    >>> check_local(parse_url("dds://1"), "dds://1")
    >>> check_local(parse_url("dds://1?interface=10.0.0.1"), "dds://1?interface=10.0.0.1", allowed="eth0")
    """
    allowed = os.environ.get("SKILLBUS_NETWORK") if allowed is None else allowed
    if allowed:
        return
    outside = [a for a in (u.interface, *u.peers) if not (a.startswith("127.") or a == "localhost")]
    if outside:
        raise BusError(f"bus URL '{url}': {', '.join(outside)} would let other hosts reach this robot's bus. "
                       f"skillbus stays on this host unless told otherwise: allow the network with --network IFACE "
                       f"(or SKILLBUS_NETWORK=IFACE; docs/security.md, docs/transport.md)")


OWN_CONFIG_ENV = "SKILLBUS_DDS_CONFIG"  # the configuration skillbus set (children inherit both)


def cyclone_config(u: DdsUrl, url: str, env: dict | None = None) -> str:
    """The configuration Cyclone is to read ($CYCLONEDDS_URI): skillbus's own for the URL,
    unless the user set one, which is used as it is only where the network is allowed
    ($SKILLBUS_NETWORK): a $CYCLONEDDS_URI inherited from elsewhere (a ROS 2 shell) would
    otherwise put the robot's bus on the network. Records its own in $SKILLBUS_DDS_CONFIG,
    so that a child process that inherits both knows it is not the user's."""
    env = os.environ if env is None else env
    given, own = env.get("CYCLONEDDS_URI", ""), env.get(OWN_CONFIG_ENV, "")
    if given and given != own:
        if env.get("SKILLBUS_NETWORK"):
            return given
        raise BusError(f"bus URL '{url}': $CYCLONEDDS_URI is set ({given[:80]}{'...' if len(given) > 80 else ''}), "
                       f"and Cyclone would use it as it is, which may reach other hosts. skillbus stays on this host "
                       f"unless told otherwise: unset it (skillbus then configures Cyclone for this host), or allow "
                       f"the network with --network IFACE (SKILLBUS_NETWORK=IFACE; docs/transport.md)")
    xml = config_xml(u)
    env[OWN_CONFIG_ENV] = xml
    return xml


def config_xml(u: DdsUrl) -> str:
    """Cyclone DDS's configuration for a URL: one interface, no multicast, discovery by
    unicast to localhost and the named peers."""
    peers = "".join(f'<Peer address="{p}"/>' for p in ("localhost", *u.peers))
    return ("<CycloneDDS><Domain id=\"any\"><General><Interfaces>"
            f"<NetworkInterface address=\"{u.interface}\" multicast=\"false\"/></Interfaces>"
            "<AllowMulticast>false</AllowMulticast></General>"
            "<Discovery><ParticipantIndex>auto</ParticipantIndex>"
            f"<MaxAutoParticipantIndex>{MAX_PARTICIPANTS}</MaxAutoParticipantIndex>"
            f"<LeaseDuration>{LEASE_S} s</LeaseDuration>"
            f"<Peers>{peers}</Peers></Discovery></Domain></CycloneDDS>")


def is_state(channel: str) -> bool:
    """State: what a publisher sends again and again, each message replacing the last (the
    physics' arm and simulator state, the objects a camera sees, articulated joints)."""
    return channel.endswith(("_STATE", "_OBJECTS", "_ARTICULATION"))


def late_joiner_window_ns(channel: str) -> int:
    """How long before a reader existed a sample may have been written and still be
    delivered to it. RPC requests: none (a restarted server must not execute its
    predecessor's requests; the client's retry reaches it), as on LCM. State: none either,
    as on LCM: a reader that comes later wants the state as it is, and a writer's history
    for late joiners held a second of it under lockstep (a probe reading the arm's pose saw
    where it had been before its last move). What was written after the reader existed
    still arrives when discovery matches them late."""
    return 0 if channel.endswith("_REQ") or is_state(channel) else LATE_JOINER_WINDOW_NS


def wrap(data: bytes) -> bytes:
    """An Envelope's serialized form: header, octet count, octets, padding to 4."""
    pad = -len(data) % 4
    return _CDR_HEADER + _LEN_LE.pack(len(data)) + data + bytes(pad)


def unwrap(sample: bytes) -> bytes | None:
    """The octets of a serialized Envelope; None when it is none.

    >>> unwrap(wrap(b"abc")), unwrap(b"\\x00\\x00\\x00\\x00\\x00\\x00\\x00\\x02xy"), unwrap(b"\\x00\\x01")
    (b'abc', b'xy', None)
    """
    if len(sample) < 8:
        return None
    length = (_LEN_LE if sample[1] & 1 else _LEN_BE).unpack_from(sample, 4)[0]
    if 8 + length > len(sample):
        return None
    return bytes(sample[8:8 + length])


class DdsBus(Bus):
    """The bus over Cyclone DDS (see the module's docstring). One reader per channel
    read, one writer per channel written, made on first use."""

    def __init__(self, url: str) -> None:
        self._error = BusError
        try:
            self.parsed = parse_url(url)
        except DdsUrlError as e:
            raise BusError(str(e)) from None
        check_local(self.parsed, url)
        os.environ["CYCLONEDDS_URI"] = cyclone_config(self.parsed, url)
        if _IMPORT_ERROR is not None:
            raise BusError(f"bus URL '{url}': the cyclonedds package is missing ({_IMPORT_ERROR}); run make setup")
        from cyclonedds import domain
        self._envelope, self._core, self._take, self._write = Envelope, core, ddspy_take, ddspy_write
        self._url = url
        self._caught_up = time.monotonic()  # (caught_up_at: set each time nothing was left to take)
        try:
            self._dp = domain.DomainParticipant(self.parsed.domain)
        except Exception as e:  # (cyclonedds raises DDSException)
            raise BusError(f"bus URL '{url}': cannot join DDS domain {self.parsed.domain}: {e}") from None
        self._waitset = core.WaitSet(self._dp)
        # Leave the domain when the process ends: the others unmatch its readers at once
        # (the wheel keeps every entity referenced, so it is never collected by itself).
        atexit.register(self.close)
        self._topics: dict[str, object] = {}
        self._writers: dict[str, object] = {}
        self._readers: dict[str, tuple[object, object]] = {}  # channel -> (reader, read condition)
        self._handlers: dict[str, dict[int, Handler]] = {}
        self.undecodable = 0  # samples that were no Envelope
        self.lost_sends = 0  # writes that timed out (see publish)
        self._since: dict[str, int] = {}  # channel -> the oldest source time delivered to its reader
        self._subs: dict[int, str] = {}
        self._next_id = 1
        self._order: list[str] = []  # channels read, in a rotating order: none starves
        self._mask = core.SampleState.Any | core.ViewState.Any | core.InstanceState.Any

    @property
    def url(self) -> str:
        return self._url

    def _qos(self, channel: str):
        from cyclonedds.core import Policy, Qos
        from cyclonedds.util import duration
        # Transient-local with a short history for late joiners: DDS matches a new writer
        # with its readers some time after it is made, and a volatile writer's first
        # samples would miss readers that existed (LCM delivers to every subscriber at
        # once). The reader drops what was written long before it (_take_one).
        late = Policy.DurabilityService(0, Policy.History.KeepLast(LATE_JOINER_DEPTH), -1, -1, -1)
        if is_state(channel):
            reliability = (Policy.Reliability.BestEffort if self.parsed.state_best_effort
                           else Policy.Reliability.Reliable(duration(seconds=1)))
            return Qos(reliability, Policy.History.KeepLast(STATE_DEPTH), Policy.Durability.TransientLocal, late)
        return Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepAll,
                   Policy.Durability.TransientLocal, late)

    def _topic(self, channel: str):
        t = self._topics.get(channel)
        if t is None:
            if _PATTERN.search(channel):
                raise self._error(f"DDS topic '{channel}': a channel name, not a pattern (DDS has no LCM-style "
                                  f"regular-expression subscriptions: subscribe to each channel)")
            refuse_long_channel(channel)  # (DDS would carry it; LCM, the other transport, would not)
            from cyclonedds.topic import Topic
            try:
                t = self._topics[channel] = Topic(self._dp, channel, self._envelope, qos=self._qos(channel))
            except Exception as e:
                raise self._error(f"DDS topic '{channel}': {e}") from None
        return t

    def publish(self, channel: str, data: bytes) -> None:
        refuse_oversized(channel, len(data))  # (DDS would carry it; LCM, the other transport, would not)
        w = self._writers.get(channel)
        if w is None:
            from cyclonedds.pub import DataWriter
            w = self._writers[channel] = DataWriter(self._dp, self._topic(channel), qos=self._qos(channel))
        ret = self._write(w._ref, wrap(bytes(data)))
        if ret == _RETCODE_TIMEOUT:
            # A reliable writer waits (up to its blocking time) while a matched reader has
            # not taken what it holds: a stopped process, or a killed one until its lease
            # ends. The message is lost, as a datagram can be on LCM, and the protocols
            # above notice and retry (RPC, lockstep resends) or report it: counted, logged.
            self.lost_sends += 1
            if self.lost_sends <= 5 or self.lost_sends % 1000 == 0:
                log.warning("sending on %s timed out: a reader takes nothing (stopped, or killed and still "
                            "matched): message lost (#%d)", channel, self.lost_sends)
            return
        if ret < 0:
            raise self._error(f"DDS write on {channel} failed ({ret})")

    def wait_matched(self, channel: str, timeout: float) -> bool:
        """Waits up to `timeout` s until this process's writer of `channel` (made by its
        first publish) has found a reader of it; False if it has not. DDS finds readers some
        time after a writer appears (milliseconds, more on a loaded machine): what must
        reach a reader that discovers the topic (a recorder) is sent after this."""
        from skillbus.waiting import poll_until

        def matched() -> bool:
            w = self._writers.get(channel)
            return w is not None and bool(w.get_matched_subscriptions())

        return bool(poll_until(matched, timeout, interval=0.005))

    def wait_acknowledged(self, timeout: float) -> bool:
        """Waits up to `timeout` s until every reader found has acknowledged all this
        process wrote (it is in their queues, and no longer lost if this process ends).
        Not what a writer kept for a reader that matched it after the writes (a late
        joiner's history): Cyclone may answer before that is sent, and a process that then
        ends takes it along (seen: a recorder that found a burst's topic late recorded none
        of it in 2 of 6 runs). Such a writer stays a moment longer."""
        from cyclonedds.util import duration
        deadline = time.monotonic() + timeout
        return all(w.wait_for_acks(duration(seconds=max(0.0, deadline - time.monotonic())))
                   for w in list(self._writers.values()))

    def subscribe(self, channel: str, handler: Handler, queue_capacity: int = 0, *, history: bool = False) -> int:
        """As Bus.subscribe. `history`: the channel's reader also takes what its writers kept
        for late readers (up to LATE_JOINER_WINDOW_NS old) on every channel, state and
        requests included: for a recorder, which subscribes to a topic once discovery
        finds it, after its first messages. (The channel's first subscription here decides.)"""
        if channel not in self._readers:
            from cyclonedds.sub import DataReader
            r = DataReader(self._dp, self._topic(channel), qos=self._qos(channel))
            cond = self._core.ReadCondition(r, self._mask)
            self._waitset.attach(cond)
            self._readers[channel] = (r, cond)
            self._since[channel] = time.time_ns() - (LATE_JOINER_WINDOW_NS if history else
                                                     late_joiner_window_ns(channel))
            self._order.append(channel)
        sid = self._next_id
        self._next_id += 1
        self._handlers.setdefault(channel, {})[sid] = guarded(handler)
        self._subs[sid] = channel
        return sid

    def unsubscribe(self, subscription_id: int) -> None:
        channel = self._subs.pop(subscription_id, None)
        if channel is None:
            return
        handlers = self._handlers.get(channel, {})
        handlers.pop(subscription_id, None)
        if not handlers:  # nobody reads it here any more: the reader goes, DDS stops sending
            self._handlers.pop(channel, None)
            r, cond = self._readers.pop(channel)
            self._waitset.detach(cond)
            self._order.remove(channel)
            del cond, r

    def _take_one(self) -> bool:
        for i, channel in enumerate(self._order):
            reader, _ = self._readers[channel]
            got = self._take(reader._ref, self._mask, 1)
            if isinstance(got, int) or not got:
                continue
            self._order.append(self._order.pop(i))  # (next time, the others first)
            since = self._since.get(channel, 0)
            for data, info in got:
                if not info.valid_data or info.source_timestamp < since:
                    continue  # (a late joiner's history from before we subscribed: LCM never had it)
                payload = unwrap(data)
                if payload is None:
                    self.undecodable += 1  # (no Envelope: a foreign writer on our topic)
                    continue
                for h in list(self._handlers.get(channel, {}).values()):
                    h(channel, payload)
            return True
        return False

    def handle(self, timeout: float) -> bool:
        from cyclonedds.util import duration
        deadline = None
        while True:
            if self._take_one():
                return True
            now = self._caught_up = time.monotonic()  # (nothing left to take: caught_up_at)
            if deadline is None:
                deadline = now + timeout
            left = deadline - now
            if left <= 0:
                return False
            if not self._readers:
                time.sleep(left)
                return False
            self._waitset.wait(duration(seconds=left))

    def caught_up_at(self) -> float:
        return self._caught_up

    def close(self) -> None:
        """Leaves the DDS domain (deletes the participant, its readers and writers)."""
        dp, self._dp = self._dp, None
        self._readers.clear()
        self._writers.clear()
        self._order.clear()
        if dp is not None:
            dp.__del__()
